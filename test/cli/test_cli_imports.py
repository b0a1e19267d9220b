"""The command line loads what a command needs: no matplotlib without plots, a light --help."""

import json
import os
import subprocess
import sys
from typing import NamedTuple

from conftest import REPO
from hydro_sdp.bags import write_bag
from hydro_sdp.cli.main import build_parser, COMMANDS, main
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
import pytest

# Runs commands in turn in one fresh interpreter; after each prints its exit code, its
# stdout and every module loaded so far. Modules only accumulate, so what a command loads
# is among those listed after it, and a module absent after the last was loaded by none.
PROBE = """
from contextlib import redirect_stdout
import io, json, sys
from hydro_sdp.cli.main import main
for argv in json.loads(sys.argv[1]):
    out = io.StringIO()
    with redirect_stdout(out):
        try:
            code = main(argv)
        except SystemExit as stop:      # --help
            code = stop.code
    print(json.dumps({'code': code, 'out': out.getvalue(), 'loaded': sorted(sys.modules)}))
"""
HEAVY = ('matplotlib', 'scipy', 'rosbags', 'rclpy')


class Run(NamedTuple):
    """One command of a probe: its exit code, its stdout and the modules loaded so far."""

    code: int
    out: str
    modules: set[str]

    @property
    def loaded(self) -> set[str]:
        """Return the top-level packages loaded so far."""
        return {name.split('.')[0] for name in self.modules}


def _probe(*argvs, cwd):
    """Run the command lines ``argvs`` in turn in one fresh interpreter."""
    done = subprocess.run([sys.executable, '-c', PROBE, json.dumps([list(a) for a in argvs])],
                          capture_output=True, text=True, cwd=cwd,
                          env=dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND='Agg'),
                          check=True, timeout=300)
    lines = done.stdout.strip().splitlines()[-len(argvs):]
    return [Run(r['code'], r['out'], set(r['loaded'])) for r in map(json.loads, lines)]


@pytest.fixture(scope='module')
def steps_bag(tmp_path_factory, j2):
    folder = tmp_path_factory.mktemp('imports')
    record = experiment_record(j2, 'steps', seed=1, duration=60.0)
    return write_bag(folder / 'steps', [record])


@pytest.fixture(scope='module')
def identify_runs(steps_bag, tmp_path_factory):
    """Run identify without plots, then with them, in one interpreter; return the figures too."""
    folder = tmp_path_factory.mktemp('identify_probe')
    figures = folder / 'figures'
    plain, plotted = _probe(['identify', str(steps_bag), '--json'],
                            ['identify', str(steps_bag), '--json', '--plot-dir', str(figures)],
                            cwd=folder)
    return plain, plotted, figures


def test_identify_without_plots_does_not_load_matplotlib(identify_runs):
    plain, _, _ = identify_runs
    assert plain.code == 0
    assert 'matplotlib' not in plain.loaded
    assert 'scipy' in plain.loaded        # the probe sees what identify does load
    assert 'rosbags' not in plain.loaded  # a plain sqlite3 bag folder is read without it


def test_identify_with_plots_loads_matplotlib_and_draws(identify_runs):
    _, plotted, figures = identify_runs
    assert plotted.code == 0
    assert 'matplotlib' in plotted.loaded
    assert sorted(p.name for p in figures.iterdir()) == [
        'gains.png', 'step_responses.png', 'velocity_map.png']


HELP = (['--help'], ['--version'], ['demo', '--help'], ['calibrate', '--help'],
        ['evaluate', '--help'])


def test_help_loads_no_scipy_matplotlib_or_rosbags(tmp_path):
    runs = _probe(*HELP, cwd=tmp_path)
    for argv, run in zip(HELP, runs):
        assert run.code == 0, argv
        assert not run.loaded & set(HEAVY), (argv, sorted(run.loaded & set(HEAVY)))


def test_the_light_parser_lists_every_command_as_the_full_one():
    assert build_parser('').format_help() == build_parser().format_help()
    full = build_parser()
    for command in COMMANDS:
        light = build_parser(command)
        # The command asked for gets the same options and description as in the full parser.
        assert _subparser(light, command).format_help() == \
            _subparser(full, command).format_help()


def _subparser(parser, command):
    action = next(a for a in parser._actions if a.dest == 'command')
    return action.choices[command]


@pytest.mark.parametrize(('given', 'expected'), [(None, '1'), ('2', '2')])
def test_blas_runs_one_thread_unless_told(given, expected, tmp_path):
    environment = dict(os.environ, PYTHONPATH=str(REPO))
    environment.pop('OPENBLAS_NUM_THREADS', None)
    if given is not None:
        environment['OPENBLAS_NUM_THREADS'] = given
    probe = ('import os, sys\nfrom hydro_sdp.cli.main import main\n'
             'try:\n    main(["--version"])\nexcept SystemExit:\n    pass\n'
             'print(os.environ["OPENBLAS_NUM_THREADS"], file=sys.stderr)')
    done = subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True,
                          cwd=tmp_path, env=environment, timeout=120)
    assert done.stdout.startswith('hydro-sdp ')
    assert done.stderr.strip().splitlines()[-1] == expected


def test_a_command_loads_no_other_command_module(identify_runs):
    plain, _, _ = identify_runs
    assert json.loads(plain.out)['kind'] == 'sdp'
    assert sorted(m for m in plain.modules if m.startswith('hydro_sdp.cli.')) == [
        'hydro_sdp.cli.common', 'hydro_sdp.cli.identify', 'hydro_sdp.cli.main',
        'hydro_sdp.cli.progress']


@pytest.mark.parametrize('argv', [['--help', 'identify'], ['--help']])
def test_the_command_list_keeps_its_help_when_help_comes_first(argv, capsys):
    with pytest.raises(SystemExit):
        main(argv)
    listing = capsys.readouterr().out
    assert listing == build_parser().format_help()
    assert 'identify a joint model from experiments or routine operation' in listing


def test_blas_threads_are_left_alone_once_numpy_is_loaded(monkeypatch, capsys):
    monkeypatch.delenv('OPENBLAS_NUM_THREADS', raising=False)
    with pytest.raises(SystemExit):
        main(['--version'])
    assert 'OPENBLAS_NUM_THREADS' not in os.environ   # too late to matter: not set
    assert capsys.readouterr().out.startswith('hydro-sdp ')


# What identify's command path imports before it reads a bag (the cost of starting it).
IDENTIFY_IMPORTS = ('import hydro_sdp.cli.identify, hydro_sdp.core.identification.identify, '
                    'hydro_sdp.bags.reading')
TIMED = """
import sys, time
started = time.perf_counter()
exec(sys.argv[1])
print(time.perf_counter() - started)
print(' '.join(sorted(sys.modules)))
"""


def _import_time(statement):
    done = subprocess.run([sys.executable, '-c', TIMED, statement], capture_output=True,
                          text=True, env=dict(os.environ, PYTHONPATH=str(REPO)), check=True,
                          timeout=120)
    seconds, modules = done.stdout.strip().splitlines()
    return float(seconds), set(modules.split())


def test_identify_starts_without_scipy_signal_and_stats_and_stays_light():
    # scipy.signal (and scipy.stats with it) took 1.2 s of a 2 s identify; the lag filters
    # are a few lines of numpy now. The bound is a ratio to importing numpy, measured here
    # in turns (the best of four of each), so a busy machine slows both alike. Quiet, the
    # ratio is about 6.5; with the other test worker busy it reaches 11; scipy.signal and
    # scipy.stats back would make it 20 or more.
    numpy, runs = [], []
    for _ in range(4):
        numpy.append(_import_time('import numpy')[0])
        runs.append(_import_time(IDENTIFY_IMPORTS))
    _, modules = runs[0]
    assert not {'scipy.signal', 'scipy.stats', 'matplotlib', 'rosbags', 'rclpy'} & modules
    assert min(seconds for seconds, _ in runs) < 15.0 * min(numpy)


def test_design_runs_without_scipy_signal(tmp_path):
    # The noise gain of the IDZ band is a Gramian now; scipy.signal's import alone took
    # longer than the whole design.
    (run,) = _probe(['design', str(REPO / 'config' / 'physics_arm_model.yaml'),
                     '--noise-std', '0.01', '--out', str(tmp_path / 'controller.yaml')],
                    cwd=tmp_path)
    assert run.code == 0 and (tmp_path / 'controller.yaml').is_file()
    assert 'scipy.signal' not in run.modules


def test_calibrate_and_diagnose_start_without_scipy_stats():
    # scipy.stats cost them 0.7 s at start-up for one chi-square tail probability.
    _, modules = _import_time('import hydro_sdp.cli.calibrate, hydro_sdp.cli.diagnose, '
                              'hydro_sdp.core.calibration, hydro_sdp.core.diagnosis')
    assert 'scipy.stats' not in modules
