"""The ``main()`` every hydro_sdp node shares (the Jazzy pattern of demo_nodes_py)."""

from __future__ import annotations

import sys
from typing import Callable

from hydro_sdp.core.errors import HydroSdpError
import rclpy
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node


def run_node(node_cls: Callable[[], Node], args: list[str] | None = None) -> None:
    """
    Initialise rclpy, spin one node of ``node_cls`` and always clean up.

    A configuration error (a bad parameter or file) ends the process with one
    line on stderr and exit code 2, not a traceback.

    Parameters
    ----------
    node_cls : callable returning Node
        Node class constructed with no arguments.
    args : list[str] or None
        Command-line arguments (``--ros-args`` included) passed to ``rclpy.init``.

    """
    rclpy.init(args=args)
    node = None
    code = 0
    try:
        node = node_cls()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (HydroSdpError, OSError, ParameterException, NameValidationException) as error:
        sys.stderr.write(f'error: {error}\n')
        code = 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    if code:
        sys.exit(code)
