"""
Online identification of the dead-zone edges and the speeds near them, for any map family.

The reasoning is in docs/methods.md sections 7.6, 7.2.

"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.identification.online import (
    EstimatedEdges, NOISE_VARIANCE_RATIOS, OnlineMapFilter, OnlineSdpIdentifier, OnlineSettings)
from hydro_sdp.core.identification.scalar_kalman import Six
from hydro_sdp.core.model.command_span import command_span
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import (
    PowerSatMap, PwlMap, SdpDzMap, SdpMap, StaticMap)
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Points of the tabulated map on each side of the dead-zone.
GRID = 512
#: Every how many grid points a ``pwl`` estimate keeps a knot.
KNOT_EVERY = 8
#: Share of a side's largest speed whose chord floors the slope an edge's shift sees.
BAND_SHARE = 1.0 / 3.0


@dataclass(frozen=True)
class EdgeEstimate(EstimatedEdges):
    """
    The online estimate of a map's edges and the speeds near them, with standard deviations.

    Each ``<name>_std`` is the standard deviation of ``<name>``, in its units.

    Attributes
    ----------
    dead_zone_lower, dead_zone_upper : float
        Dead-zone edges, input units.
    speed_scale_negative, speed_scale_positive : float
        Speeds beyond each edge relative to the model's (1: unchanged).

    """

    dead_zone_lower: float
    dead_zone_upper: float
    speed_scale_negative: float
    speed_scale_positive: float
    dead_zone_lower_std: float
    dead_zone_upper_std: float
    speed_scale_negative_std: float
    speed_scale_positive_std: float


def _side(model: JointModel, rest: float, end: float,
          dt: SamplePeriod) -> tuple[float, np.ndarray, float]:
    """Return one side's edge, its increments ``Q`` on the grid (signed) and the grid's reach."""
    sign = 1.0 if end > rest else -1.0
    v = np.linspace(rest, end, 4001)
    speed = np.maximum.accumulate(np.clip(sign * model.rate(v), 0.0, None))
    moving = np.flatnonzero(speed > 0.0)
    if not moving.size:
        raise ConfigurationError(f'the {model.kind} map does not move the joint '
                                 f'{"down" if sign < 0 else "up"} within the commands '
                                 f'{sorted([rest, end])}')
    dead_zone = model.dead_zone
    edge = float(v[max(int(moving[0]) - 1, 0)])
    if dead_zone is not None:
        edge = min(max(dead_zone[1] if sign > 0 else dead_zone[0], min(rest, end)),
                   max(rest, end))
    reach = abs(end - edge)
    x = np.linspace(0.0, reach, GRID)
    q = np.maximum.accumulate(np.clip(sign * model.rate(edge + sign * x), 0.0, None))
    q[0] = 0.0
    return edge, sign * dt * q, reach


def _edge_slopes(table: np.ndarray, step: float) -> list[float]:
    """Return each segment's slope, near the edge at least the chord to a third of the top."""
    slopes = np.diff(table) / step if step > 0.0 else np.zeros(table.size - 1)
    top = float(table[-1])
    reach = int(np.argmax(np.abs(table) >= BAND_SHARE * abs(top)))
    if reach > 0:
        chord = float(table[reach]) / (reach * step)
        near = slopes[:reach]
        slopes[:reach] = np.where(np.abs(near) < abs(chord), chord, near)
    return [float(x) for x in np.r_[slopes, 0.0]]


def command_reach(model: JointModel, scale: float) -> tuple[float, float]:
    """Return the commands the tabulated map covers: a table IDZ's, else ``rest +- 10 scale``."""
    try:
        return command_span(model)
    except ConfigurationError:
        rest = model.rest_command
        return rest - 10.0 * scale, rest + 10.0 * scale


class OnlineEdgeIdentifier(OnlineMapFilter):
    """
    The filter of :class:`.online.OnlineSdpIdentifier` on the model's own map, moved per side.

    ``theta = (k_n, 1, a3, k_p, 1, a6)``: speed scale and edge below the dead-zone,
    then above it (module docstring).

    ``model``: the model to start from (any map family), with the delay and end stops to use.
    ``dt``: sample period of the incoming samples, s.
    """

    def __init__(self, model: JointModel, dt: SamplePeriod,
                 settings: OnlineSettings = OnlineSettings()) -> None:
        rest = model.rest_command
        low, high = command_reach(model, settings.input_scale)
        negative = _side(model, rest, low, dt)
        positive = _side(model, rest, high, dt)
        self._edges0 = (negative[0], positive[0])
        self._tables = (negative[1], positive[1])
        self._steps = (negative[2] / (GRID - 1), positive[2] / (GRID - 1))
        # The per-sample lookups read Python floats: the values, and the slopes an edge's
        # shift sees (each segment's, at least the chord to a third of the top speed).
        self._qn = [float(x) for x in negative[1]]
        self._qp = [float(x) for x in positive[1]]
        self._dn, self._dp = (_edge_slopes(table, step)
                              for table, step in zip(self._tables, self._steps))
        self._hn, self._hp = (1.0 / h if h > 0.0 else 0.0 for h in self._steps)
        super().__init__(model, dt, settings)

    def _start(self) -> tuple[Six, Six, Six, Six, Six]:
        s = self.settings.input_scale
        speed = (self.dt / 0.01) ** 2
        low, high = self._edges0
        top_n, top_p = (float(abs(table[-1])) for table in self._tables)
        # Eq. (5)'s variances of a1, a3 (and a4, a6), relative to this map's speed
        # (methods.md 7.6); the curvatures' places hold 1, fixed.
        variances = (0.01 * speed / top_n ** 2, 0.0, 0.5 * s ** 2,
                     0.01 * speed / top_p ** 2, 0.0, 0.5 * s ** 2)
        units = (speed / top_n ** 2, 0.0, s ** 2, speed / top_p ** 2, 0.0, s ** 2)
        r0, r1, r2, r3, r4, r5 = (ratio * unit
                                  for ratio, unit in zip(NOISE_VARIANCE_RATIOS, units))
        lower = (0.0, 1.0, -4.0 * s * max(1.0, abs(low)), 0.0, 1.0, low)
        upper = (5.0, 1.0, high, 5.0, 1.0, 4.0 * s * max(1.0, abs(high)))
        return (1.0, 1.0, low, 1.0, 1.0, high), variances, (r0, r1, r2, r3, r4, r5), lower, upper

    def _map_and_gradient(self, u: float, theta: list[float],
                          kappa: float) -> tuple[float, Six]:
        """Return the moved map at ``u`` and the gradient of its soft-edged form."""
        kn, _, a3, kp, _, a6 = theta
        qn, qp, dn, dp, hn, hp = self._qn, self._qp, self._dn, self._dp, self._hn, self._hp
        last = GRID - 1
        below = a3 - u
        above = u - a6
        # Soft distances beyond each edge: softplus of width kappa, free of overflow.
        z_below, z_above = below / kappa, above / kappa
        soft_below = (kappa * (z_below + math.log1p(math.exp(-z_below))) if z_below > 0.0
                      else kappa * math.log1p(math.exp(z_below)))
        soft_above = (kappa * (z_above + math.log1p(math.exp(-z_above))) if z_above > 0.0
                      else kappa * math.log1p(math.exp(z_above)))
        sigma_below = 1.0 / (1.0 + math.exp(700.0 if 700.0 < -z_below else -z_below))
        sigma_above = 1.0 / (1.0 + math.exp(700.0 if 700.0 < -z_above else -z_above))
        # Each side at its soft distance: the value, and the slope an edge's shift sees.
        x = soft_below * hn
        i = int(x)
        if i < last:
            value_n = qn[i] + (x - i) * (qn[i + 1] - qn[i])
            slope_n = dn[i]
        else:
            value_n, slope_n = qn[last], 0.0
        x = soft_above * hp
        i = int(x)
        if i < last:
            value_p = qp[i] + (x - i) * (qp[i + 1] - qp[i])
            slope_p = dp[i]
        else:
            value_p, slope_p = qp[last], 0.0
        # The exact map: the sides only beyond the edges.
        q = 0.0
        if below > 0.0:
            x = below * hn
            i = int(x)
            q += kn * (qn[i] + (x - i) * (qn[i + 1] - qn[i]) if i < last else qn[last])
        if above > 0.0:
            x = above * hp
            i = int(x)
            q += kp * (qp[i] + (x - i) * (qp[i + 1] - qp[i]) if i < last else qp[last])
        return q, (value_n, 0.0, kn * slope_n * sigma_below,
                   value_p, 0.0, -kp * slope_p * sigma_above)

    def static_map(self, edges: tuple[float, float] | None = None) -> StaticMap:
        """
        Return the current estimate as a map of the model's family (a ``pwl`` for others).

        ``edges``: edges to use instead of the estimated ones, input units.
        """
        kn, _, a3, kp, _, a6 = self._theta
        if edges is not None:
            a3, a6 = edges
        if a3 > a6:                         # the edges crossed: meet half-way
            a3 = a6 = 0.5 * (a3 + a6)
        nominal = self.model.static_map
        if isinstance(nominal, (SdpMap, PowerSatMap)):
            vn, vp = nominal.saturation_velocity
            return replace(nominal, dead_zone=(a3, a6), saturation_velocity=(kn * vn, kp * vp))
        if isinstance(nominal, SdpDzMap):
            return replace(nominal, dead_zone=(a3, a6),
                           slope=(kn * nominal.slope[0], kp * nominal.slope[1]))
        keep = np.r_[np.arange(0, GRID - 1, KNOT_EVERY), GRID - 1]
        x = keep * self._steps[0]
        knots_n = (a3 - x[::-1]).tolist()
        speeds_n = (kn * self._tables[0][keep][::-1] / self.dt).tolist()
        x = keep * self._steps[1]
        knots_p = (a6 + x).tolist()
        speeds_p = (kp * self._tables[1][keep] / self.dt).tolist()
        if a3 == a6:
            knots_p, speeds_p = knots_p[1:], speeds_p[1:]
        return PwlMap(knots=tuple(knots_n + knots_p), speeds=tuple(speeds_n + speeds_p))

    def estimate(self, edges: tuple[float, float] | None = None) -> JointModel:
        """Return the model with the current estimate of its map (optionally other edges)."""
        return replace(self.model, static_map=self.static_map(edges))

    def named_estimate(self) -> EdgeEstimate:
        """Return the current estimate and its standard deviations by name."""
        kn, _, a3, kp, _, a6 = self._theta
        s1, _, s3, s4, _, s6 = (float(s) for s in self.standard_errors)
        return EdgeEstimate(a3, a6, kn, kp, s3, s6, s1, s4)


#: An online estimator of either kind.
OnlineIdentifier = OnlineSdpIdentifier | OnlineEdgeIdentifier


def online_identifier(model: JointModel, dt: SamplePeriod,
                      settings: OnlineSettings = OnlineSettings()) -> OnlineIdentifier:
    """
    Return the online identifier of a model: eq. (5)'s own for ``sdp``, the edges' for others.

    ``dt``: sample period of the incoming samples, s.
    """
    if isinstance(model.static_map, SdpMap):
        return OnlineSdpIdentifier(model, dt, settings)
    return OnlineEdgeIdentifier(model, dt, settings)
