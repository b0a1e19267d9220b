"""
The speed along the delayed command, without a map family, and what it was never shown.

The reasoning is in docs/methods.md section 15.4.

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.routine.increments import Increments
from hydro_sdp.core.identification.state_dependence import backfit, Term
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Fewest increments on one side of rest for its gain to be estimated.
MIN_SIDE_SAMPLES = 20
#: A point shows motion when its speed is this many standard errors from zero and
#: this share of the fastest point's speed.
MOVING_SIGMAS = 3.0
MOVING_SHARE = 0.05


def speed_points(data: Increments, dt: SamplePeriod, rest: float) -> tuple[LevelSpeed, ...]:
    """
    Speed at every distinct delayed command, by the SDP smoother of the gain.

    ``dt``: sample period, s.
    Returns: one point per distinct command away from rest (pooled when there are very many),
    sorted by command; empty when no side has enough samples.
    """
    drive = data.command - rest
    terms = [Term(name, part, data.command, test=False)
             for name, part in (('b-', np.minimum(drive, 0.0)), ('b+', np.maximum(drive, 0.0)))
             if np.count_nonzero(part) >= MIN_SIDE_SAMPLES]
    if not terms:
        return ()
    fit = backfit(data.increment, terms, replicates=0)
    points = []
    for estimate in fit.terms:
        counts = np.bincount(estimate.ordering.group, minlength=estimate.ordering.groups)
        distance = estimate.values - rest
        for level, gain, error, away, count in zip(estimate.values, estimate.estimate,
                                                   estimate.standard_error, distance, counts):
            points.append(LevelSpeed(float(level), float(gain * away / dt),
                                     float(error * abs(away) / dt), int(count), float(gain)))
    return tuple(sorted(points, key=lambda p: p.level))


def moving(points: Sequence[LevelSpeed]) -> np.ndarray:
    """Tell which points show motion: away from zero and a share of the fastest."""
    speeds = np.array([p.speed for p in points])
    errors = np.array([p.standard_error for p in points])
    peak = float(np.max(np.abs(speeds), initial=0.0))
    return (np.abs(speeds) > MOVING_SIGMAS * errors) & (np.abs(speeds) > MOVING_SHARE * peak) \
        & (peak > 0.0)


def check_coverage(points: Sequence[LevelSpeed], seen: tuple[float, float], rest: float,
                   input_limits: tuple[float, float] | None = None) -> None:
    """
    Refuse routine data that cannot place a dead-zone edge, naming the commands never seen.

    ``input_limits``: the valve's range, when given (the message then names the range never seen).
    Raises DataError when the joint never moved, or never moved one way.
    """
    levels = np.array([p.level for p in points])
    speeds = np.array([p.speed for p in points])
    go = moving(points) if points else np.zeros(0, dtype=bool)
    span = f'commands seen {seen[0]:.4g} .. {seen[1]:.4g}'
    if not np.any(go):
        raise DataError(f'no excitation: the joint never moved ({span}, rest {rest:g}; are '
                        'they all inside the dead-zone?)')
    for sign, way, beyond in ((-1.0, 'down', 'below'), (1.0, 'up', 'above')):
        side = sign * (levels - rest) > 0.0
        if np.any(go & side & (sign * speeds > 0.0)):
            continue
        limit = None if input_limits is None else input_limits[0 if sign < 0 else 1]
        outermost = seen[0] if sign < 0 else seen[1]
        if sign * (outermost - rest) <= 0.0:
            found = f'no command {beyond} rest {rest:g} was seen ({span})'
            outermost = rest
        else:
            found = (f'the commands {beyond} rest reached only {outermost:.4g} and never '
                     f'moved it measurably; commands {beyond} {outermost:.4g} were never seen')
        if limit is not None:
            found += (f'; commands from {outermost:.4g} to the valve limit {limit:g} were '
                      'never seen')
        raise DataError(f'the joint never moved {way}: {found}, so the dead-zone edge '
                        f'{beyond} rest cannot be placed: record operation that drives it '
                        f'{way} beyond the dead-zone')
