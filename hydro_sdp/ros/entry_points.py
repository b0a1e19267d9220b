"""Console-script entry points of the nodes (``ros2 run hydro_sdp plant_node`` ...)."""

from __future__ import annotations

import signal
import sys


def _run(module: str) -> None:
    import importlib

    # Installed before anything slow is imported: a Ctrl-C from here on is only noted.
    interrupted: list[int] = []
    previous = signal.getsignal(signal.SIGINT)
    # A shell's background job ignores SIGINT; that choice is kept.
    if previous is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, lambda signum, frame: interrupted.append(signum))
    try:
        main = importlib.import_module(f'hydro_sdp.ros.{module}').main
    except KeyboardInterrupt:
        sys.exit(130)
    finally:
        # None: a handler installed from C, which Python cannot put back; the default then.
        signal.signal(signal.SIGINT, signal.default_int_handler if previous is None
                      else previous)
    if interrupted:
        sys.exit(130)
    main()


def plant_node() -> None:
    """Run the plant node."""
    _run('plant_node')


def controller_node() -> None:
    """Run the PIP-IDZ controller node."""
    _run('controller_node')


def identifier_node() -> None:
    """Run the online identifier node."""
    _run('identifier_node')


def bag_recorder() -> None:
    """Run the bag recorder node."""
    _run('bag_recorder')


def bag_player() -> None:
    """Run the bag player node."""
    _run('bag_player')
