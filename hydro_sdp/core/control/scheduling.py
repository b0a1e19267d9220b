"""When a controller may use a feedback sample and when it acts (methods 4.8)."""

from __future__ import annotations

from typing import Literal

from hydro_sdp.core.errors import ConfigurationError, DataError

#: What a gate says of a sample: ``ignored`` (not newer than the last one),
#: ``accepted``, or ``resumed`` (accepted, and the first one after the watchdog fired).
Admission = Literal['ignored', 'accepted', 'resumed']
#: What the watchdog says: ``fed`` (valid feedback within the timeout), ``lost`` (the
#: timeout just passed) or ``blind`` (still nothing valid).
WatchdogState = Literal['fed', 'lost', 'blind']
#: What a schedule says of an admitted sample: ``wait`` (no control instant reached),
#: ``step``, or ``resume`` (step, from rest: forget the controller's history first).
Tick = Literal['wait', 'step', 'resume']


def _positive_ns(value: int, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise ConfigurationError(f'{name} must be a positive whole number of ns, got {value!r}')
    return value


def seconds_to_ns(seconds: float) -> int:
    """Return a duration in seconds as whole nanoseconds (nearest)."""
    return int(round(float(seconds) * 1e9))


class FeedbackGate:
    """
    Admission of feedback samples by stamp, and the feedback watchdog.

    ``timeout_ns``: longest accepted age of a stamp, and longest silence before the watchdog fires,
    ns.
    ``now_ns``: clock reading at creation, ns (the silence is counted from here).
    ``lead_ns``: longest accepted lead of a stamp over the clock, ns (default ``timeout_ns``).
    """

    def __init__(self, timeout_ns: int, now_ns: int, lead_ns: int | None = None) -> None:
        self._timeout_ns = _positive_ns(timeout_ns, 'timeout_ns')
        self.lead_ns = self._timeout_ns if lead_ns is None else _positive_ns(lead_ns, 'lead_ns')
        self.last_stamp: int | None = None
        self.last_valid_ns = int(now_ns)
        #: Steady-clock reading of the last valid sample (None: none since creation).
        self.last_valid_steady_ns: int | None = None
        self.blind = False

    @property
    def timeout_ns(self) -> int:
        """Feedback timeout, ns (settable; applies from the next call)."""
        return self._timeout_ns

    @timeout_ns.setter
    def timeout_ns(self, value: int) -> None:
        self._timeout_ns = _positive_ns(value, 'timeout_ns')

    def admit(self, stamp_ns: int, now_ns: int, steady_ns: int | None = None) -> Admission:
        """
        Decide on one sample stamped ``stamp_ns`` arriving at clock reading ``now_ns``.

        ``stamp_ns``: stamp of the sample, ns.
        ``now_ns``: reader's clock, ns; 0 means simulated time has not started, and the freshness
        check is skipped.
        ``steady_ns``: a steady clock's reading, ns, for the watchdog (None: not kept).
        Returns: ``ignored`` for a duplicate or overtaken sample (nothing changes), ``accepted``,
        or ``resumed`` after a silence the watchdog reported.
        Raises DataError if the stamp is more than the timeout behind the clock, or more than
        ``lead_ns`` ahead of it (one from the future would make every later sample look old); the
        caller closes the valve.
        """
        if now_ns != 0:
            lead = stamp_ns - now_ns
            if lead > self.lead_ns or -lead > self._timeout_ns:
                ahead = lead > 0
                limit = self.lead_ns if ahead else self._timeout_ns
                where = 'ahead of' if ahead else 'behind'
                raise DataError(f'JointState stamp is {abs(lead) * 1e-9:.3f} s {where} the node '
                                f'clock (more than {limit * 1e-9:g} s; check the clocks and '
                                'use_sim_time on every node)')
            if self.last_stamp is not None and self.last_stamp > now_ns + self.lead_ns:
                self.last_stamp = None     # the clock went back (a simulation restarted)
        if self.last_stamp is not None and stamp_ns <= self.last_stamp:
            return 'ignored'
        self.last_stamp = stamp_ns
        self.last_valid_ns = now_ns
        if steady_ns is not None:
            self.last_valid_steady_ns = steady_ns
        if self.blind:
            self.blind = False
            return 'resumed'
        return 'accepted'

    def silence_ns(self, now_ns: int, steady_ns: int | None = None) -> int:
        """Return the time since the last valid sample (or creation), ns: the longer clock's."""
        silence = now_ns - self.last_valid_ns
        if steady_ns is not None and self.last_valid_steady_ns is not None:
            silence = max(silence, steady_ns - self.last_valid_steady_ns)
        return silence

    def watchdog(self, now_ns: int, steady_ns: int | None = None) -> WatchdogState:
        """
        Check the silence at clock reading ``now_ns`` (and steady reading ``steady_ns``).

        ``steady_ns``: steady clock reading, ns: once a sample was accepted with a steady reading,
        the silence is the longer of the two clocks' (a simulated clock that stops does not stop
        the watchdog).
        """
        if now_ns < self.last_valid_ns:
            self.last_valid_ns = now_ns
        if self.silence_ns(now_ns, steady_ns) <= self._timeout_ns:
            return 'fed'
        if self.blind:
            return 'blind'
        self.blind = True
        return 'lost'


def watchdog_period_ns(timeout_ns: int, longest_ns: int = 100_000_000) -> int:
    """Return how often to run a watchdog of ``timeout_ns``: half of it, at most ``longest_ns``."""
    return max(1, min(_positive_ns(timeout_ns, 'timeout_ns') // 2, longest_ns))


class ControlSchedule:
    """Control instants every ``period_ns`` from the first admitted sample."""

    def __init__(self, period_ns: int) -> None:
        self.period_ns = _positive_ns(period_ns, 'period_ns')
        self.next_instant: int | None = None
        self.missed = 0
        self._from_rest = True

    def tick(self, stamp_ns: int) -> Tick:
        """Decide whether the sample stamped ``stamp_ns`` is controlled."""
        if self.next_instant is None:
            self.next_instant = stamp_ns
        if stamp_ns < self.next_instant:
            return 'wait'
        return 'resume' if self._from_rest else 'step'

    def stepped(self, stamp_ns: int) -> int:
        """
        Record that the sample stamped ``stamp_ns`` was controlled; move to the next instant.

        ``stamp_ns``: stamp of the controlled sample, ns.
        Returns: control instants missed before this sample (0 on time).
        """
        if self.next_instant is None:
            self.next_instant = stamp_ns
        missed = max(0, (stamp_ns - self.next_instant) // self.period_ns)
        self.next_instant += (missed + 1) * self.period_ns
        self.missed += missed
        self._from_rest = False
        return missed

    def hold(self) -> None:
        """Note that the valve was closed: the next step starts from rest."""
        self._from_rest = True

    @property
    def holding(self) -> bool:
        """Whether the next step starts from rest."""
        return self._from_rest
