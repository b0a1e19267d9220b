"""Ctrl-C at any moment of a command: no traceback, exit code 130, no temporary left behind."""

import os
from pathlib import Path
import signal
import subprocess
import sys
import threading
import time

from conftest import REPO
from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.cli import main as main_module
from hydro_sdp.core.model.records import Record
from hydro_sdp.io.atomic import atomic_directory, atomic_write_bytes, interrupts_deferred
import numpy as np
import pytest
from support.startup import loading_extensions
import yaml

# The console script's code, run with this interpreter (installed or not), started as an
# interactive shell starts it: Ctrl-C acted on. A suite started as a background job of a
# non-interactive shell holds SIGINT ignored (POSIX), and a child inherits that (a blocked
# SIGINT too): the command would never see the signal and run to its end.
COMMAND = [sys.executable, '-c',
           'import signal; signal.signal(signal.SIGINT, signal.default_int_handler); '
           'signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT}); '
           'from hydro_sdp.cli.main import entry_point; entry_point()']
#: What the plant node logs when the demo's wear scenario wears its valve: nodes are running.
NODES_RUNNING = 'dead-zone edges moved'


def _leftovers(folder):
    """Temporaries of atomic writes (.<name>.<random>.tmp) anywhere under ``folder``."""
    return sorted(str(p.relative_to(folder)) for p in Path(folder).rglob('*')
                  if p.name.endswith('.tmp') or p.name.startswith('.'))


def _start(arguments, cwd):
    environment = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND='Agg')
    return subprocess.Popen([*COMMAND, *arguments], cwd=cwd, env=environment,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _interrupt(arguments, delay, cwd):
    """Send SIGINT ``delay`` s after the command's own imports begin; return code and stderr."""
    process = _start(arguments, cwd)
    assert loading_extensions(process.pid), 'the command never started importing'
    time.sleep(delay)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    return process.returncode, stderr


def _check_interrupted(code, stderr):
    assert 'Traceback' not in stderr, stderr
    # 130 with one line; 0 if it finished first; killed by the signal if it landed after the
    # command's end, while the interpreter shut down (its handlers the default again).
    assert code in (130, 0, -signal.SIGINT), (code, stderr)
    if code == 130:
        assert stderr.splitlines()[-1].startswith('error: interrupted'), stderr


@pytest.fixture
def ctrl_c_to_this_process():
    """
    Python's own Ctrl-C handling in this test process while a test sends SIGINT to itself.

    These tests are about what the code does under Python's default handler; a test
    worker has run other modules before (middleware threads, nodes in process), so the
    handler is set and SIGINT unblocked in this thread, and the handler put back after.
    """
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    yield
    if previous is not None:
        signal.signal(signal.SIGINT, previous)


def test_sigint_inside_a_deferred_block_arrives_when_it_ends(ctrl_c_to_this_process):
    steps = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts_deferred():
            os.kill(os.getpid(), signal.SIGINT)
            steps.append('after the signal')      # still runs: the signal waits
        steps.append('after the block')           # never runs: it arrived at the end
    assert steps == ['after the signal']


def test_a_ctrl_c_while_the_commands_load_waits_for_them_and_ends_in_130(
        ctrl_c_to_this_process, monkeypatch, capsys, tmp_path):
    # Inside numpy's C import a KeyboardInterrupt would become an ImportError ("PyCapsule_Import
    # could not import module ..."): the loading is not interrupted, the Ctrl-C is acted on
    # once it is done.
    loaded = []
    build_parser = main_module.build_parser

    def loading_the_commands(only=None):
        signal.raise_signal(signal.SIGINT)
        time.sleep(0.2)                          # a handler would have run by now
        loaded.append(only)
        return build_parser(only)
    monkeypatch.setattr(main_module, 'build_parser', loading_the_commands)
    assert main_module.main(['simulate', str(REPO / 'config' / 'brokk_j2.yaml'), '--program',
                             'steps', '--out', str(tmp_path / 'bag')]) == 130
    assert loaded == ['simulate'] and list(tmp_path.iterdir()) == []
    assert capsys.readouterr().err == 'error: interrupted\n'


def test_an_interrupted_directory_leaves_the_old_one_and_nothing_else(tmp_path):
    target = tmp_path / 'bag'
    record = Record(np.arange(1, 21) * 0.01, np.zeros(20), np.ones(20), joint='j2')
    write_bag(target, [record])
    before = {p.name: p.read_bytes() for p in target.iterdir()}
    with pytest.raises(KeyboardInterrupt):
        with atomic_directory(target) as building:
            building.mkdir()
            (building / 'half.db3').write_bytes(b'half')
            raise KeyboardInterrupt
    assert {p.name: p.read_bytes() for p in target.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bag']


def test_an_interrupted_file_write_leaves_nothing(tmp_path, monkeypatch):
    def interrupted(*args):
        raise KeyboardInterrupt
    monkeypatch.setattr(os, 'fsync', interrupted)
    with pytest.raises(KeyboardInterrupt):
        atomic_write_bytes(tmp_path / 'model.yaml', b'joint: j2\n')
    assert list(tmp_path.iterdir()) == []


def test_written_files_get_the_usual_mode(tmp_path):
    mask = os.umask(0o022)
    os.umask(mask)
    path = atomic_write_bytes(tmp_path / 'model.yaml', b'joint: j2\n')
    assert path.stat().st_mode & 0o777 == 0o666 & ~mask


@pytest.mark.slow
# From inside the commands' loading (numpy's import) to inside the simulation.
@pytest.mark.parametrize('delay', [0.0, 0.4, 0.8, 2.3])
def test_sigint_during_simulate(tmp_path, delay):
    code, stderr = _interrupt(['simulate', str(REPO / 'config' / 'brokk_j2.yaml'),
                               '--program', 'steps', '--out', 'out/bag'], delay, tmp_path)
    _check_interrupted(code, stderr)
    assert _leftovers(tmp_path) == []
    bag = tmp_path / 'out' / 'bag'
    # The bag is there whole, or not at all; an interrupt that lands after the bag was
    # renamed into place still ends the run with 130 (or, after the command's end, the
    # interpreter's shutdown), and the bag stays whole.
    if code in (0, -signal.SIGINT) or bag.exists():
        # Whole: the storage holds every sample its metadata counts.
        info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
        counted = next(topic['message_count'] for topic in info['topics_with_message_count']
                       if topic['topic_metadata']['name'] == '/joint_states')
        assert read_bag(bag).record().t.size == counted > 0
    else:
        assert not bag.exists()


def _check_demo_cut_short(code, stderr, folder):
    """Check that Ctrl-C ended the demo (130): each file it wrote whole, the summary (last) not."""
    _check_interrupted(code, stderr)
    assert code == 130, stderr
    assert _leftovers(folder) == [] and not (folder / 'report' / 'summary.md').exists()


@pytest.mark.slow
def test_sigint_while_the_demo_identifies(tmp_path):
    # 3 s in: the demo (15 s of CPU) is simulating and identifying, far from its end.
    code, stderr = _interrupt(['demo', '--short', '--out', 'report'], 3.0, tmp_path)
    _check_demo_cut_short(code, stderr, tmp_path)


@pytest.mark.slow
def test_sigint_while_the_demos_nodes_run(tmp_path):
    # Ctrl-C while rclpy's nodes run in the process (the wear scenario has begun).
    process = _start(['demo', '--short', '--out', 'report'], tmp_path)
    # A demo that hangs silently is killed: its stderr then ends and the test fails.
    watchdog = threading.Timer(120.0, process.kill)
    watchdog.start()
    seen = []
    try:
        for line in process.stderr:
            seen.append(line)
            if NODES_RUNNING in line:
                break
        else:
            process.wait(timeout=120)
            pytest.fail('the demo ended without its nodes logging the wear: ' + ''.join(seen))
    finally:
        watchdog.cancel()
    process.send_signal(signal.SIGINT)
    _, rest = process.communicate(timeout=120)
    _check_demo_cut_short(process.returncode, ''.join(seen) + rest, tmp_path)


def test_a_ctrl_c_that_an_extension_turns_into_another_error_still_exits_130(
        ctrl_c_to_this_process, monkeypatch, capsys):
    # rclpy's pybind11 code can turn the KeyboardInterrupt of a Ctrl-C into a RuntimeError
    # (the demo's nodes); the command still ends as interrupted, not as an internal failure.
    from hydro_sdp.cli import reindex
    from hydro_sdp.cli.main import main

    def run(args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)
        except KeyboardInterrupt:
            raise RuntimeError('Unable to convert call argument to Python object') from None
    monkeypatch.setattr(reindex, 'run', run)
    assert main(['reindex', 'anything']) == 130
    assert capsys.readouterr().err.strip() == 'error: interrupted; nothing partial was written'
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_ctrl_c_while_the_command_is_imported_ends_it_in_one_line(tmp_path):
    # Held in the import for a second, as a loaded machine holds it, and interrupted there.
    slow = [sys.executable, '-c', 'import signal; '
            'signal.signal(signal.SIGINT, signal.default_int_handler); '
            'import hydro_sdp.cli, time; print("imported", flush=True); time.sleep(30)']
    process = subprocess.Popen(slow, cwd=tmp_path, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               env=dict(os.environ, PYTHONPATH=str(REPO)))
    assert process.stdout.readline() == 'imported\n'
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=30)
    assert (process.returncode, stderr) == (130, 'error: interrupted\n')
