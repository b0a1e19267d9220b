"""
Every example of the README and the user guide runs as written.

The fenced blocks are read from the Markdown (``support.doc_blocks``) and run in one
scratch folder laid out as a fresh clone (``config/`` and an empty ``docs/figures/``),
page after page, so that a page uses what the pages before it made: the README and the
command line guide make ``steps_bag``, ``random_bag``, ``j2_model.yaml``... A shell
line ``hydro-sdp ...`` runs the console script's ``main`` (in this process, which saves
a second of imports per line) and must exit 0; the
``ros2`` lines are done by ``support.ros_cli`` (``ros2 run`` starts the console script
as a node process, ``ros2 topic pub --once``, ``ros2 param``, ``ros2 lifecycle set`` by
a client node), and a blank line in a block ends a scene: its nodes must still run, and
Ctrl-C ends each with exit code 0 (or as docs/interfaces.md 3.11 bounds a middleware that
holds the node: ``support.node_exit``). Python blocks run with this environment's Python.
Blocks that cannot run here carry ``<!-- not run: REASON -->``; the recordings and logs of
"your machine" that the examples name are made first (``support.your_machine``).
"""

from contextlib import redirect_stderr, redirect_stdout
import io
import os
from pathlib import Path
import re
import shlex
import shutil
import subprocess
import sys
import time

from conftest import REPO
from hydro_sdp.cli.main import main
from hydro_sdp.io.documents import load_yaml
import pytest
from support.doc_blocks import Block, blocks, commands
from support.your_machine import write_your_machine
import yaml

# The longest module of the suite, one chain of pages: started first. The commands' figures
# are written as blank PNGs (support.figures): drawing them is what the tests of
# test/plots and test/report, the demo's and test_cli_says_what_it_wrote are for.
pytestmark = [pytest.mark.slow(120), pytest.mark.usefixtures('figures_not_drawn')]

#: The pages, in the order a newcomer reads them (each may use what those before it made).
PAGES = ['README.md'] + [f'docs/guide/{name}.md' for name in (
    'command_line', 'files', 'diagnosis', 'your_machine', 'sdp', 'nodes', 'security',
    'troubleshooting', 'development')]
BIN = Path(sys.executable).parent
#: Longest a single command may take, s.
TIMEOUT = 300.0
#: Node executables that end by themselves (run in the foreground).
ENDS_BY_ITSELF = ('bag_player',)


def all_blocks():
    return [block for page in PAGES for block in blocks(REPO / page)]


def test_every_block_is_run_or_marked_with_a_reason():
    found = all_blocks()
    assert len(found) > 20
    for block in found:
        if block.note in ('not run', 'file', 'same as'):
            assert block.argument, f'{block.where}: say why (or which file)'
            continue
        assert block.language in ('bash', 'python'), \
            f'{block.where}: a {block.language or "plain"} block must be marked ' \
            '<!-- not run: REASON -->, <!-- file: PATH --> or <!-- same as: PATH -->'


def test_the_page_list_covers_the_guide():
    assert {p for p in PAGES if p.startswith('docs/guide')} == {
        f'docs/guide/{path.name}' for path in (REPO / 'docs' / 'guide').glob('*.md')}


@pytest.fixture(scope='module')
def scratch(tmp_path_factory):
    """Lay out a folder as a fresh clone, with the recordings of "your machine"."""
    folder = tmp_path_factory.mktemp('docs')
    shutil.copytree(REPO / 'config', folder / 'config')
    (folder / 'docs' / 'figures').mkdir(parents=True)
    # ros2 run's workspace: the shipped files where colcon installs them.
    share = folder / 'install' / 'hydro_sdp' / 'share' / 'hydro_sdp'
    share.mkdir(parents=True)
    (share / 'config').symlink_to(folder / 'config')
    write_your_machine(folder)
    return folder


def expand(token, cwd):
    """Expand a shell glob as the shell does (left as it is when nothing matches)."""
    if '*' not in token or ':=' in token:
        return [token]
    found = sorted(str(path.relative_to(cwd)) for path in cwd.glob(token))
    return found or [token]


def hydro_sdp(line, arguments, cwd):
    """Run the ``hydro-sdp`` console script's ``main`` in ``cwd`` (in this process: fast)."""
    out, err = io.StringIO(), io.StringIO()
    previous = os.getcwd()
    os.chdir(cwd)
    try:
        with redirect_stdout(out), redirect_stderr(err):
            try:
                code = main(arguments)
            except SystemExit as error:        # argparse's usage errors
                code = error.code
    finally:
        os.chdir(previous)
    assert code == 0, f'{line}\nexit {code}: {err.getvalue()}'
    return out.getvalue()


def run_command(line, cwd, scene_of):
    """Run one shell line; return what it printed."""
    words = shlex.split(line)
    arguments = [word for token in words[1:] for word in expand(token, cwd)]
    if words[0] == 'ros2' and words[1:3] == ['run', 'hydro_sdp']:
        executable, arguments = words[3], [word for token in words[4:]
                                           for word in expand(token, cwd)]
        if executable == 'hydro-sdp':
            return run_command(shlex.join(['hydro-sdp', *arguments]), cwd, scene_of)
        if executable in ENDS_BY_ITSELF:
            return scene_of().run(executable, arguments)
        scene_of().start(executable, arguments)
        return ''
    if words[0] == 'hydro-sdp':
        return hydro_sdp(line, arguments, cwd)
    if words[:4] == ['ros2', 'topic', 'pub', '--once']:
        scene_of().publish_once(words[4], words[5], words[6])
        return ''
    if words[:3] == ['ros2', 'param', 'set']:
        scene_of().set_parameter(words[3], words[4], words[5])
        return ''
    if words[:3] == ['ros2', 'param', 'get']:
        return f'{scene_of().get_parameter(words[3], words[4])}\n'
    if words[:3] == ['ros2', 'lifecycle', 'set']:
        scene_of().lifecycle(words[3], words[4])
        return ''
    if words[0] == 'sleep':
        scene = scene_of(create=False)
        if scene is None:
            time.sleep(float(words[1]))
        else:
            scene.spin_for(float(words[1]))
        return ''
    raise AssertionError(f'the test cannot run {line!r}: mark the block <!-- not run: ... -->')


def run_shell(block, cwd):
    """Run a shell block scene by scene; return what it printed."""
    printed = []
    for scene_lines in commands(block.text):
        scenes = []

        def scene_of(create=True):
            if not scenes and create:
                pytest.importorskip('rclpy')
                from support.ros_cli import Scene
                scenes.append(Scene(cwd, BIN))
            return scenes[0] if scenes else None
        try:
            for line in scene_lines:
                printed.append(run_command(line, cwd, scene_of))
        finally:
            if scenes:
                scenes[0].close()
    return ''.join(printed)


def run_block(block, cwd):
    """Run, write or compare one block; return what it printed."""
    if block.note == 'file':
        target = cwd / block.argument
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(block.text + '\n')
        return ''
    if block.note == 'same as':
        assert yaml.safe_load(block.text) == load_yaml(REPO / block.argument), \
            f'{block.where}: differs from {block.argument}'
        return ''
    if not block.runs:
        return ''
    if block.language == 'python':
        script = cwd / f'example_{block.path.stem}_{block.line}.py'
        script.write_text(block.text + '\n')
        done = subprocess.run([sys.executable, str(script)], cwd=cwd, capture_output=True,
                              text=True, timeout=TIMEOUT)
        assert done.returncode == 0, f'{block.where}: {done.stderr}'
        return done.stdout
    return run_shell(block, cwd)


@pytest.mark.parametrize('page', PAGES)
def test_the_examples_run_as_written(page, scratch):
    for block in blocks(REPO / page):
        try:
            printed = run_block(block, scratch)
        except AssertionError as error:
            raise AssertionError(f'{block.where}: {error}') from None
        for pattern in block.expected():
            assert any(re.search(pattern, line) for line in printed.splitlines()), \
                f'{block.where}: no line of its output matches {pattern!r}:\n{printed}'


def test_a_block_is_split_into_scenes_and_commands():
    text = 'a \\\n  b  # note\n# comment\nc "x # y"\n\nd\n'
    assert commands(text) == [['a b', 'c "x # y"'], ['d']]
    block = Block(Path('x.md'), 3, 'bash', 'hydro-sdp x', 'expect', '2.15 | (0.85|0.86)')
    assert block.runs and block.expected() == ['2.15', '(0.85|0.86)']
