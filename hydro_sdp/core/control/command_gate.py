"""Which valve commands a valve takes: one source, in range and rate, fresh (methods 4.11)."""

from __future__ import annotations

import math
from typing import Sequence

from hydro_sdp.core.errors import ConfigurationError, DataError

#: Commands a source may send at once above the rate limit.
BURST = 10


class CommandGate:
    """
    The acceptance rule of one joint's valve commands.

    ``limits``: valve range, input units (commands are clamped to it).
    ``source``: fully qualified name of the only node allowed (``/pip_controller``); '' allows any
    one node, as long as it is the only publisher.
    ``rate_limit``: most commands per second taken (> 0).
    ``timeout_ns``: silence of the source after which the valve is closed, ns (0: never).
    """

    def __init__(self, limits: tuple[float, float] | None, *, source: str = '',
                 rate_limit: float = 1000.0, timeout_ns: int = 0, burst: int = BURST) -> None:
        if not (math.isfinite(rate_limit) and rate_limit > 0.0):
            raise ConfigurationError(f'command_rate_limit must be > 0 per s, got {rate_limit}')
        if timeout_ns < 0:
            raise ConfigurationError(f'command_timeout must be >= 0 s, got {timeout_ns * 1e-9}')
        self.limits = limits
        self.source = source
        self.rate_limit = float(rate_limit)
        self.timeout_ns = int(timeout_ns)
        self.burst = burst
        self._tokens = float(burst)
        self._refilled_ns: int | None = None
        self.last_accepted_ns: int | None = None

    def admit(self, value: float, now_ns: int, publishers: Sequence[str]) -> float | None:
        """
        Decide on one command.

        ``value``: the command, input units.
        ``now_ns``: the caller's clock, ns.
        ``publishers``: the publishers of the command topic now: fully qualified node names ('' for
        one whose name is not known; with no source named, only their number counts).
        Returns: the command to put in force (clamped to the range), or None to drop it (above the
        rate limit: the command in force stays).
        Raises DataError if the command is not finite or its publishers are not the one source: the
        caller closes the valve.
        """
        if not math.isfinite(value):
            raise DataError(f'a command that is not finite ({value})')
        names = sorted(publishers)
        if self.source:
            if not names or any(name != self.source for name in names):
                shown = [name or 'unknown' for name in names] or 'none known'
                raise DataError(f'publishers {shown}: only {self.source} may command this '
                                'valve')
        elif len(names) != 1:
            known = [name for name in names if name]
            raise DataError(f"{len(names)} publishers{f' {known}' if known else ''}: a valve "
                            'takes commands from one node')
        if self._refilled_ns is not None:
            elapsed = max(now_ns - self._refilled_ns, 0) * 1e-9
            self._tokens = min(float(self.burst), self._tokens + elapsed * self.rate_limit)
        self._refilled_ns = now_ns
        if self._tokens < 1.0:
            return None
        self._tokens -= 1.0
        self.last_accepted_ns = now_ns
        limits = self.limits
        return value if limits is None else min(max(value, limits[0]), limits[1])

    def silent(self, now_ns: int) -> bool:
        """Return whether the source has sent nothing taken for longer than the timeout."""
        last = self.last_accepted_ns
        return self.timeout_ns > 0 and last is not None and now_ns - last > self.timeout_ns
