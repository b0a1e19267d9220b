"""Spinning a test's client node by hand until what it waits for has happened."""

from __future__ import annotations

import time
from typing import Callable, Protocol


class Spinnable(Protocol):
    """An rclpy executor, as far as spinning it once goes."""

    def spin_once(self, timeout_sec: float | None = None) -> None:
        """Run one callback, or wait up to ``timeout_sec`` s for one."""


def spin_until(executor: Spinnable, predicate: Callable[[], object], timeout: float,
               step: float) -> bool:
    """Spin ``executor`` ``step`` s at a time until ``predicate()`` holds; False at ``timeout``."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            return False
        executor.spin_once(timeout_sec=step)
    return True
