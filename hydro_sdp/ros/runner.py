"""The ``main()`` every hydro_sdp node shares (the Jazzy pattern of demo_nodes_py)."""

from __future__ import annotations

import faulthandler
import signal
import sys
from types import FrameType
from typing import Callable, Union

from hydro_sdp.core.errors import HydroSdpError
import rclpy
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import install_signal_handlers, SignalHandlerOptions, uninstall_signal_handlers

#: Longest wait of the executor before it checks for a stop, s (bounds the exit time).
WAKE_PERIOD = 0.1
#: Longest the middleware may take to let go of the node once its own work is done, s. Past
#: it the process ends anyway (exit 1, where every thread was). Fast DDS 2.14 deadlocks now
#: and then when it deletes the participant while a peer's endpoints vanish (nodes stopped
#: together): set_listener waits for a discovery callback that waits for its lock.
CLEANUP_LIMIT = 4.0
#: What ``signal.signal`` installs and returns: a handler, SIG_DFL or SIG_IGN, or None.
SignalHandler = Union[Callable[[int, FrameType | None], object], int, None]

_CONFIGURATION_ERRORS = (HydroSdpError, OSError, ParameterException, NameValidationException)


class _Stop:
    """The stop signals: SIGINT raises KeyboardInterrupt while the node is built, else records."""

    def __init__(self) -> None:
        self.signals: list[int] = []
        #: Off during the clean-up, which a second Ctrl-C must not cut short.
        self.interrupts = True

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        first = not self.signals
        self.signals.append(signum)
        if first and self.interrupts and signum == signal.SIGINT:
            raise KeyboardInterrupt

    def __bool__(self) -> bool:
        return bool(self.signals)


def _destroy(node: Node | None, executor: SingleThreadedExecutor | None, stop: _Stop) -> None:
    # After a signal the context may already be down: a failure to tidy up is then moot.
    try:
        if executor is not None:
            executor.shutdown(timeout_sec=WAKE_PERIOD)
        if node is not None:
            # The node's own last work (the recorder's bag) takes what it needs; the
            # middleware's part is bounded. faulthandler's watchdog is a thread of C that
            # needs no GIL, so it ends the process even when the hang holds it.
            close = getattr(node, 'close', None)
            if callable(close):
                close()
            faulthandler.dump_traceback_later(CLEANUP_LIMIT, exit=True)
            node.destroy_node()
    except Exception:
        if not stop:
            raise
    finally:
        rclpy.try_shutdown()
        uninstall_signal_handlers()


def run_node(node_cls: Callable[[], Node], args: list[str] | None = None) -> None:
    """
    Initialise rclpy, spin one node of ``node_cls`` and always clean up.

    ``args``: command-line arguments (``--ros-args`` included) passed to ``rclpy.init``.
    """
    # A crash in compiled code (rclpy, the middleware) prints where every thread was, the
    # first thing a bug report needs, instead of ending the process without a word.
    if not faulthandler.is_enabled():
        faulthandler.enable(all_threads=True)
    stop = _Stop()
    # Installed before rclpy.init, whose own handlers call the ones they replace.
    previous: dict[int, SignalHandler] = {
        signum: signal.signal(signum, stop) for signum in (signal.SIGINT, signal.SIGTERM)}
    node: Node | None = None
    executor: SingleThreadedExecutor | None = None
    code = 0
    try:
        # rclpy's handlers (which shut the context down) wait until the node is whole: a
        # SIGTERM during its construction is recorded and acted on once it is built (Ctrl-C
        # still interrupts a constructor at once).
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
        if not stop:
            node = node_cls()
            # Once the node is built, a signal only records the stop and rclpy's handler
            # shuts the context down: the loop below ends within WAKE_PERIOD. A
            # KeyboardInterrupt raised in the middle of the executor's wait, with entities
            # held for it, could leave rclpy to destroy them in use (a crash on Ctrl-C).
            stop.interrupts = False
            install_signal_handlers(SignalHandlerOptions.ALL)
            executor = SingleThreadedExecutor()
            executor.add_node(node)
            while not stop and executor.context.ok():
                executor.spin_once(timeout_sec=WAKE_PERIOD)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except _CONFIGURATION_ERRORS as error:
        if not stop:
            sys.stderr.write(f'error: {error}\n')
            code = 2 if executor is None else 3
    except Exception:
        if not stop:
            raise
    finally:
        stop.interrupts = False
        try:
            _destroy(node, executor, stop)
        except KeyboardInterrupt:
            pass
        finally:
            faulthandler.cancel_dump_traceback_later()
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    if code:
        sys.exit(code)
