"""
Console-script entry points of the nodes (``ros2 run hydro_sdp plant_node`` ...).

Loading a node's modules (rclpy, numpy) takes a good part of a second; a Ctrl-C in
that time would otherwise end in a ``KeyboardInterrupt`` traceback. Here the
module is imported under a handler, so the process ends quietly with 130, as
the command line does; once the node runs, :func:`hydro_sdp.ros.runner.run_node`
handles signals.

"""

import importlib
import sys


def _run(module: str) -> None:
    try:
        main = importlib.import_module(f'hydro_sdp.ros.{module}').main
    except KeyboardInterrupt:
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
