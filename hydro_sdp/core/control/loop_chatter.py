"""How much the valve works while a joint holds its set-point (methods 5.7)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.control.idz_table import Idz
from hydro_sdp.core.control.loop_simulation import LoopTrace
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np

#: Most pulses per second of hold: one in the check's 2-s watch window of a hold.
MAX_PULSE_RATE = 0.5
#: Most valve travel per second of hold, in dead-zone widths: one swing across and back.
MAX_TRAVEL_WIDTHS = 2.0
#: Shortest settled part of a level that counts as a hold, s.
MIN_HOLD = 1.0
#: State of a command inside the dead-zone but outside its inner half (keeps the last).
BETWEEN = 2


def valve_states(v: FloatArray, edges: tuple[float, float], rest: float) -> np.ndarray:
    """
    Return the state of each command: -1 or +1 open beyond an edge, 0 closed, 2 between.

    ``edges``: the valve's dead-zone edges ``(a3, a6)``, input units.
    Returns: one state per command (closed: within the inner half of the dead-zone around rest).
    """
    v = np.asarray(v, dtype=np.float64)
    low, high = edges
    states = np.full(v.shape, BETWEEN, dtype=np.int8)
    states[(v >= rest - 0.5 * (rest - low)) & (v <= rest + 0.5 * (high - rest))] = 0
    states[v < low] = -1
    states[v > high] = 1
    return states


def pulse_starts(states: np.ndarray) -> np.ndarray:
    """Return where the valve opens in a sequence of :func:`valve_states`."""
    known = np.flatnonzero(states != BETWEEN)
    side = states[known]
    return known[1:][(side[1:] != 0) & (side[1:] != side[:-1])]


@dataclass(frozen=True)
class Hold:
    """
    One hold of a run.

    Attributes
    ----------
    start : float
        When the joint settled into its band, s.
    duration : float
        Settled time to the end of the level, s.
    travel : float
        Sum of the command's changes during the hold, input units.

    """

    start: float
    duration: float
    pulses: int
    travel: float


def hold_starts(trace: LoopTrace, band: float = 0.5) -> list[tuple[int, int]]:
    """
    Return each hold of a run as samples ``(settled, end)``: a level after the joint settled.

    ``band``: band around the set-point, degrees.
    Levels that never settle, or settle for less than :data:`MIN_HOLD`, are left out.
    """
    setpoint = trace.setpoint
    dt = float(trace.t[1] - trace.t[0]) if trace.t.size > 1 else 1.0
    changes = np.r_[0, np.flatnonzero(np.diff(setpoint)) + 1, setpoint.size]
    found = []
    for begin, end in zip(changes[:-1].tolist(), changes[1:].tolist()):
        outside = np.flatnonzero(np.abs(trace.y[begin:end] - setpoint[begin:end]) > band)
        start = begin + (int(outside[-1]) + 1 if outside.size else 0)
        if (end - start) * dt >= MIN_HOLD:
            found.append((start, end))
    return found


def hold_pulses(trace: LoopTrace, edges: tuple[float, float], rest: float, *,
                band: float = 0.5) -> np.ndarray:
    """Return the samples where the valve opens across the dead-zone during the holds."""
    states = valve_states(trace.v, edges, rest)
    return np.array([start + int(k) for start, end in hold_starts(trace, band)
                     for k in pulse_starts(states[start:end])], dtype=np.int64)


def holds(trace: LoopTrace, edges: tuple[float, float], rest: float, *,
          band: float = 0.5) -> list[Hold]:
    """Return the holds of a run: each level's part after the joint settled, if long enough."""
    dt = float(trace.t[1] - trace.t[0]) if trace.t.size > 1 else 1.0
    states = valve_states(trace.v, edges, rest)
    return [Hold(float(trace.t[start]), (end - start) * dt,
                 int(pulse_starts(states[start:end]).size),
                 float(np.sum(np.abs(np.diff(trace.v[start:end])))))
            for start, end in hold_starts(trace, band)]


@dataclass(frozen=True)
class Chatter:
    """
    The valve's work at hold over a check's runs, and its verdict.

    Attributes
    ----------
    edges : tuple[float, float] or None
        The valve's dead-zone edges (None: the map has none, nothing is bounded).
    valve_range : tuple[float, float] or None
        The valve's command range, for the travel's share of it.

    """

    holds: tuple[Hold, ...]
    edges: tuple[float, float] | None
    valve_range: tuple[float, float] | None

    @property
    def duration(self) -> float:
        """Return the time held, s."""
        return float(sum(h.duration for h in self.holds))

    @property
    def pulse_rate(self) -> float:
        """Return the pulses per second of hold, pooled (0 without holds)."""
        return sum(h.pulses for h in self.holds) / self.duration if self.holds else 0.0

    @property
    def travel_rate(self) -> float:
        """Return the valve's travel per second of hold, input units (0 without holds)."""
        return sum(h.travel for h in self.holds) / self.duration if self.holds else 0.0

    @property
    def travel_share(self) -> float | None:
        """Return the travel per second as a share of the valve range (None: no range)."""
        if self.valve_range is None:
            return None
        return self.travel_rate / (self.valve_range[1] - self.valve_range[0])

    @property
    def travel_bound(self) -> float | None:
        """Return the most travel per second allowed, input units (None: no dead-zone)."""
        if self.edges is None or not self.edges[1] > self.edges[0]:
            return None
        return MAX_TRAVEL_WIDTHS * (self.edges[1] - self.edges[0])

    @property
    def failures(self) -> tuple[str, ...]:
        """Return why the valve works too hard at hold, one line each (empty: it does not)."""
        bound = self.travel_bound
        if bound is None or not self.holds:
            return ()
        share = self.travel_share
        travel = f'{self.travel_rate:.3g} input units/s' + (
            '' if share is None else f' ({100.0 * share:.0f} % of the valve range)')
        found = []
        if self.pulse_rate > MAX_PULSE_RATE:
            found.append(f'pulses at hold: {self.pulse_rate:.2f} reversals/s across the '
                         f'dead-zone (bound {MAX_PULSE_RATE:g}/s), valve travel {travel}')
        if self.travel_rate > bound:
            found.append(f'the valve travels {travel} at hold (bound {bound:.3g}, '
                         f'{MAX_TRAVEL_WIDTHS:g} dead-zone widths per s)')
        return tuple(found)


def chatter_edges(model: JointModel, idz: Idz | None) -> tuple[float, float] | None:
    """Return the dead-zone edges a joint's valve is judged by: the model's, else the IDZ's."""
    edges = model.dead_zone if model.dead_zone is not None else (
        None if idz is None else idz.dead_zone)
    if edges is None or not edges[1] > edges[0]:
        return None
    return float(edges[0]), float(edges[1])


def loop_chatter(traces: Sequence[LoopTrace], model: JointModel, idz: Idz | None,
                 valve_range: tuple[float, float] | None = None, *,
                 band: float = 0.5) -> Chatter:
    """
    Measure the valve's work at hold over closed-loop runs of a joint.

    ``model``: the joint they ran on (its dead-zone judges the pulses).
    ``idz``: the controller's IDZ (its rest command; its edges when the model has none).
    ``valve_range``: the valve range (default: the model's input limits).
    ``band``: band around the set-point, degrees.
    """
    edges = chatter_edges(model, idz)
    valve_range = valve_range if valve_range is not None else model.input_limits
    if edges is None:
        return Chatter((), None, valve_range)
    rest = idz.rest if idz is not None else model.rest_command
    if not edges[0] <= rest <= edges[1]:
        rest = min(max(rest, edges[0]), edges[1])
    found = [hold for trace in traces for hold in holds(trace, edges, rest, band=band)]
    return Chatter(tuple(found), edges, valve_range)
