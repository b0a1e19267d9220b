"""The bad-input inventory in docs/bad_inputs.md names tests that exist."""

import re
import subprocess
import sys

from conftest import REPO

ROW = re.compile(r'^\| (\d+) \|.*\| `(test/[^`:]+::\w+(\[[^`]*)?)` \|$')


def _rows():
    text = (REPO / 'docs' / 'bad_inputs.md').read_text()
    return [(line, ROW.match(line)) for line in text.splitlines()
            if re.match(r'^\| \d+ \|', line)]


def test_rows_are_numbered_and_name_a_test():
    rows = _rows()
    for line, row in rows:
        assert row, f'row does not end with a test name: {line}'
    assert [int(row.group(1)) for _, row in rows] == list(range(1, len(rows) + 1))
    assert len(rows) >= 40


def test_every_named_test_is_collected(request):
    names = [row.group(2) for _, row in _rows()]
    files = sorted({name.split('::')[0] for name in names})
    # The run's own collection when it holds those files (the whole suite); otherwise, or
    # for a file that skipped itself, a collection of those files in a process of its own.
    collected = [item.nodeid for item in request.session.items]
    here = {test.split('::')[0] for test in collected}
    missing = [path for path in files if path not in here]
    skipped: set[str] = set()
    if missing:
        done = subprocess.run(
            [sys.executable, '-m', 'pytest', '--collect-only', '-q', '-rs', '-n0', '-p',
             'no:cacheprovider', *missing], cwd=REPO, capture_output=True, text=True)
        # 5: nothing collected, as when every missing file skipped itself.
        assert done.returncode in (0, 5), done.stdout + done.stderr
        listing = done.stdout
        collected += [line for line in listing.splitlines() if '::' in line]
        # A module that skips itself (the rosbag2 fixtures beside the repository are
        # missing) collects nothing: its tests must then at least be defined in it.
        skipped = set(re.findall(r'^SKIPPED \[\d+\] ([^:]+):\d+:', listing, re.MULTILINE))
    for name in names:
        path, function = name.split('::')
        if path in skipped:
            function = function.split('[')[0]
            assert f'def {function}(' in (REPO / path).read_text(), \
                f'{name} is not a test of the suite'
            continue
        # A parameter case is named by its pytest id up to the first '-'.
        start = name[:-1] + '-' if name.endswith(']') else name + '['
        assert any(test == name or test.startswith(start) for test in collected), \
            f'{name} is not a test of the suite'
