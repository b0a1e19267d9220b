"""Entry point of the ``hydro-sdp`` command line."""

from __future__ import annotations

import argparse
import importlib
import json
import os
import signal
import sys
import threading
import traceback
from types import FrameType
from typing import Any, Callable

from hydro_sdp import __version__

#: BLAS threads of a command unless OPENBLAS_NUM_THREADS says otherwise. Its products are
#: tall and thin (a row per sample, a column per parameter), where OpenBLAS's threads wait
#: more than they work: ``identify`` on a one-hour bag takes twice the CPU time with them.
BLAS_THREADS = '1'

#: Commands and their modules in hydro_sdp.cli, in the order of ``--help``.
COMMANDS = {'simulate': 'simulate', 'import': 'import_logs', 'identify': 'identify',
            'evaluate': 'evaluate', 'diagnose': 'diagnose', 'sdp': 'sdp', 'design': 'design',
            'closed-loop': 'closed_loop', 'calibrate': 'calibrate', 'demo': 'demo.command',
            'reindex': 'reindex'}

DESCRIPTION = """\
Identify, control and diagnose hydraulic manipulator joints with state-dependent
parameter (SDP) models.

Every command takes --json (one JSON object on stdout), exits 0 on success, 2 on
bad input (with a one-line `error: ...`), 1 on an internal failure. Angles are in
degrees, time in seconds, commands in the valve's own units.

start with:
  hydro-sdp demo --out demo_output
"""


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """
    Build the argument parser with every command.

    ``only``: give only this command its options and description; the others are listed by name,
    and with their one-line help (all ``hydro-sdp --help`` shows) unless ``only`` names a command;
    default: every command in full.
    """
    parser = argparse.ArgumentParser(
        prog='hydro-sdp', description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--version', action='version', version=f'hydro-sdp {__version__}')
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument('--json', action='store_true',
                        help='print one JSON object on stdout and nothing else there')
    subparsers = parser.add_subparsers(dest='command', metavar='COMMAND', required=True)
    original = subparsers.add_parser

    def add_parser(name: str, **kwargs: Any) -> argparse.ArgumentParser:
        kwargs.setdefault('parents', [common])
        return original(name, **kwargs)

    subparsers.add_parser = add_parser  # type: ignore[method-assign]  # all get --json
    for command, name in COMMANDS.items():
        if only is None or only == command:
            importlib.import_module(f'hydro_sdp.cli.{name}').register(subparsers)
        elif only in COMMANDS:
            subparsers.add_parser(command)      # the list is shown only without a command
        else:
            module = importlib.import_module(f'hydro_sdp.cli.{name}')
            subparsers.add_parser(command, help=module.HELP)
    return parser


def _asked(argv: list[str]) -> str:
    """Return the command ``argv`` starts with ('' when it starts with an option)."""
    return argv[0] if argv and not argv[0].startswith('-') else ''


def _fail(message: str, code: int) -> int:
    sys.stderr.write(f'error: {message}\n')
    return code


def _internal_failure(error: Exception) -> int:
    if os.environ.get('HYDRO_SDP_DEBUG'):
        traceback.print_exc()
    return _fail(f'internal failure ({type(error).__name__}: {error}); '
                 'set HYDRO_SDP_DEBUG=1 for a traceback', 1)


class _Interrupts:
    """Note every Ctrl-C (SIGINT) while a command runs, and raise KeyboardInterrupt as usual."""

    def __init__(self) -> None:
        self.seen = False
        self._previous: Callable[[int, FrameType | None], object] | int | None = None

    def __enter__(self) -> _Interrupts:
        if threading.current_thread() is threading.main_thread() and \
                signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            self._previous = signal.signal(signal.SIGINT, self._note)
        return self

    def _note(self, signum: int, frame: object) -> None:
        self.seen = True
        raise KeyboardInterrupt

    def __exit__(self, *exc: object) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)


def main(argv: list[str] | None = None) -> int:
    """
    Run one ``hydro-sdp`` command.

    ``argv``: arguments without the program name; default ``sys.argv[1:]``.
    """
    with _Interrupts() as interrupts:
        return _main(argv, interrupts)


def _main(argv: list[str] | None, interrupts: _Interrupts) -> int:
    # Only before numpy loads OpenBLAS (a fresh process: the console script), where it
    # is read; a value the user set is kept.
    if 'numpy' not in sys.modules:
        os.environ.setdefault('OPENBLAS_NUM_THREADS', BLAS_THREADS)
    try:
        words = sys.argv[1:] if argv is None else argv
        # Imported here, where a Ctrl-C already ends in 130, not before main runs.
        from hydro_sdp.io.atomic import interrupts_deferred
        # The commands' modules load with Ctrl-C held back to the end: one landing inside an
        # extension module's import (numpy's) would come out as that module's ImportError.
        with interrupts_deferred():
            args = build_parser(_asked(words)).parse_args(words)
            from hydro_sdp.cli.common import to_json
            from hydro_sdp.core.errors import HydroSdpError
    except KeyboardInterrupt:
        return _fail('interrupted', 130)
    except Exception as error:  # noqa: B902 - no traceback from loading the commands either
        return _internal_failure(error)
    try:
        outcome = args.run(args)
        text = json.dumps(to_json(outcome.payload)) + '\n' if args.json else \
            ''.join(line + '\n' for line in outcome.lines)
    except KeyboardInterrupt:
        return _fail('interrupted; nothing partial was written', 130)
    except (HydroSdpError, OSError) as error:
        return _fail(str(error).replace('\n', ' '), 2)
    except Exception as error:  # noqa: B902 - the last line of defence: no traceback
        if interrupts.seen:
            return _fail('interrupted; nothing partial was written', 130)
        return _internal_failure(error)
    try:
        sys.stdout.write(text)
    except KeyboardInterrupt:
        return _fail('interrupted', 130)
    return 0


def entry_point() -> None:
    """Console-script wrapper: exit with :func:`main`'s code."""
    try:
        code = main()
    except KeyboardInterrupt:
        # Between two handlers above (a Ctrl-C while one is being handled).
        code = _fail('interrupted', 130)
    sys.exit(code)
