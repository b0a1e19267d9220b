"""Online identification of the SDP map (docs/methods.md section 7), one sample at a time."""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Any

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.identification.scalar_kalman import (
    add_to_diagonal, boxed, diagonal, downdated, packed, Six, times, unpacked)
from hydro_sdp.core.identification.soft_edges import map_and_soft_gradient
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import SdpMap
from hydro_sdp.core.model.timing import DelayLine, SamplePeriod
from hydro_sdp.core.validation import require_positive_fields
import numpy as np

#: With a valve lag, a sample counts only while the command lagged by it is within this
#: share of ``change_gate`` of the command (the valve has nearly settled).
STEADY = 0.5
#: Process noise of the random walk, as a ratio to the measurement noise variance.
NOISE_VARIANCE_RATIOS = (1e-6, 1e-5, 1e-5, 1e-6, 1e-5, 1e-5)


@dataclass(frozen=True)
class OnlineSettings:
    """
    Tuning of the online identifier (defaults from docs/methods.md 7.2, for +-10 V commands).

    Every command-side setting is in input units, used as given; for another command
    range build the settings with :meth:`for_input_limits`, which scales them once.

    Attributes
    ----------
    noise_std : float
        Angle measurement noise, degrees.
    kappa : float
        Width of the soft edges of the gradient, input units (0.05 V).
    change_gate : float
        Command change that suspends updates, input units (0.5 V).
    margin : float
        Distance from an end stop inside which updates stop, degrees.
    outlier : float
        Normalised innovation beyond which a sample is an outlier.
    input_scale : float
        Size of the command range relative to +-10 V (1 for volts); scales the start covariance,
        the random walk and the box of the edges and curvatures.
    change_level : float
        Mean normalised innovation squared (about 1 while the model holds) above which the joint is
        taken to have changed and the covariance is reset.
    change_memory : float
        Samples the mean of the normalised innovation squared remembers.
    cusum_drift : float
        Drift ``k`` of the CUSUM tests on the normalised innovations.
    cusum_limit : float
        Threshold ``h`` of those tests (the mean run length between false alarms grows roughly as
        ``exp(2 k h)``).

    """

    noise_std: float = 0.03
    kappa: float = 0.05
    change_gate: float = 0.5
    hold_off: int = 3
    margin: float = 1.0
    outlier: float = 6.0
    input_scale: float = 1.0
    change_level: float = 4.0
    change_memory: float = 100.0
    cusum_drift: float = 0.5
    cusum_limit: float = 15.0

    def __post_init__(self) -> None:
        require_positive_fields(self, ('noise_std', 'kappa', 'change_gate', 'margin', 'outlier',
                                       'input_scale', 'change_level', 'change_memory',
                                       'cusum_drift', 'cusum_limit'))
        if self.hold_off < 0:
            raise ConfigurationError(f'hold_off must be >= 0, got {self.hold_off}')

    @classmethod
    def for_input_limits(cls, input_limits: tuple[float, float] | None,
                         **overrides: Any) -> OnlineSettings:
        """
        Return the defaults scaled to a command range (the one place they are scaled).

        ``input_limits``: the valve's command range, input units (e.g. ``(0, 100)`` % duty: scale
        10); None for +-10 V.
        ``**overrides``: other settings (``noise_std``...), in input units where they are commands.
        """
        scale = input_scale(input_limits)
        values: dict[str, Any] = {'kappa': cls.kappa * scale,
                                  'change_gate': cls.change_gate * scale,
                                  'input_scale': scale}
        values.update(overrides)
        return cls(**values)


def input_scale(input_limits: tuple[float, float] | None) -> float:
    """
    Size of a command range relative to +-10 V.

    ``input_limits``: command range, input units; None for +-10 V.
    Returns: the largest command magnitude over 10 (1 for +-10 V, 10 for 0..100 %).
    """
    if input_limits is None:
        return 1.0
    scale = max(abs(input_limits[0]), abs(input_limits[1])) / 10.0
    if not (math.isfinite(scale) and scale > 0.0):
        raise ConfigurationError(f'input_limits must hold a non-zero finite command, '
                                 f'got {list(input_limits)}')
    return scale


class EstimatedEdges:
    """The dead-zone edges of an online estimate, and their standard deviations."""

    dead_zone_lower: float
    dead_zone_upper: float
    dead_zone_lower_std: float
    dead_zone_upper_std: float

    @property
    def edges(self) -> tuple[float, float]:
        """Return the dead-zone edges, input units."""
        return self.dead_zone_lower, self.dead_zone_upper

    @property
    def edges_std(self) -> tuple[float, float]:
        """Return the standard deviations of the edges, input units."""
        return self.dead_zone_lower_std, self.dead_zone_upper_std


@dataclass(frozen=True)
class SdpEstimate(EstimatedEdges):
    """
    The online estimate of an SDP map by name, with standard deviations.

    Each ``<name>_std`` is the standard deviation of ``<name>``, in its units.

    Attributes
    ----------
    dead_zone_lower, dead_zone_upper : float
        Dead-zone edges, input units.
    saturation_negative, saturation_positive : float
        Saturation speeds, deg/s.
    curvature_negative, curvature_positive : float
        Curvatures, 1/input unit.

    """

    dead_zone_lower: float
    dead_zone_upper: float
    saturation_negative: float
    saturation_positive: float
    curvature_negative: float
    curvature_positive: float
    dead_zone_lower_std: float
    dead_zone_upper_std: float
    saturation_negative_std: float
    saturation_positive_std: float
    curvature_negative_std: float
    curvature_positive_std: float


class OnlineMapFilter:
    """
    The random-walk Kalman filter of docs/methods.md 7.2-7.4 on six map coefficients.

    ``model``: starting point, and the delay and end stops to use.
    ``dt``: sample period of the incoming samples, s.
    """

    def __init__(self, model: JointModel, dt: SamplePeriod,
                 settings: OnlineSettings = OnlineSettings()) -> None:
        self.model = model
        self.dt = dt
        self.settings = settings
        self.delay = model.delay_samples(self.dt)
        # theta and the upper triangle of P as Python floats: the per-sample arithmetic on
        # six numbers is cheaper written out than as numpy calls (docs/methods.md 7.2).
        theta, variances, ratios, lower, upper = self._start()
        self._theta = list(theta)
        self._start_variances = variances
        self._p = packed(np.diag(self._start_variances))
        # Mean normalised innovation squared: about 1 while the model holds.
        self.nis = 1.0
        # Two-sided CUSUM of the normalised innovations, for commands below and above the
        # middle of the dead-zone: a moved edge or a changed speed biases one side.
        self._cusum = [0.0, 0.0, 0.0, 0.0]
        self.resets = 0
        self._since_reset = 0
        self._ratios = ratios
        self.r = 2.0 * settings.noise_std ** 2
        self._r_min = 0.25 * self.r
        self._lower, self._upper = lower, upper
        # The model's valve lag, if any: the joint's speed follows the map through it, so the
        # prediction and its gradient do too (their states, one sample old).
        lag = model.effect(ValveLag.name)
        self._lag_pole = (math.exp(-self.dt / lag.time_constant)
                          if isinstance(lag, ValveLag) else None)
        self._lag_speed = 0.0
        self._lag_command = math.nan
        # A command the delay may be off by: a quarter of it, newer than the delayed one.
        self._ahead = self.delay - (self.delay + 3) // 4
        self._lag_gradient: Six = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        # v_{k-tau} and v_{k-tau-1}: the gate needs the command before the delayed one too.
        self._commands = DelayLine(self.delay + 1, before=math.nan)
        self._pushed = 0
        self._last_angle: float | None = None
        self._quiet = 0
        self.samples = 0
        self.updates = 0

    def _start(self) -> tuple[Six, Six, Six, Six, Six]:
        """Return the starting ``theta``, start variances, random-walk ratios and the box."""
        raise NotImplementedError

    def _map_and_gradient(self, u: float, theta: list[float],
                          kappa: float) -> tuple[float, Six]:
        """Return the map at ``u`` and the gradient of its soft-edged form (section 7.2)."""
        raise NotImplementedError

    @property
    def theta(self) -> FloatArray:
        """Return the six coefficients, the edges third and sixth (a new array)."""
        return np.array(self._theta)

    @property
    def P(self) -> FloatArray:
        """Return the covariance of ``theta`` (a new 6 x 6 array)."""
        return unpacked(self._p)

    @property
    def standard_errors(self) -> FloatArray:
        """Return the standard deviations of ``theta``."""
        return np.sqrt(np.maximum(diagonal(self._p), 0.0))

    def update(self, v: float, y: float) -> bool:
        """
        Take one sample: the command in force up to ``t_k`` and the angle at ``t_k``.

        ``v``: command (input units).
        Returns: whether the sample updated the estimate (False when gated).
        """
        self.samples += 1
        settings = self.settings
        if not (math.isfinite(v) and math.isfinite(y)):
            self._quiet = settings.hold_off
            return False
        commands = self._commands
        commands.push(v)
        self._pushed += 1
        # A numpy scalar would carry numpy's slower scalar arithmetic through the whole step.
        y = float(y)
        previous, self._last_angle = self._last_angle, y
        delay = self.delay
        if previous is None or self._pushed < delay + 2:
            return False
        u = commands.delayed(delay)
        lagged = self._lag_pole is not None
        if lagged:
            # The valve lag's state runs on every sample, the gated ones too.
            q, psi = self._lagged(u)
            steady = STEADY * settings.change_gate
            if (abs(u - self._lag_command) > steady
                    or abs(u - commands.delayed(self._ahead)) > steady):
                return False
        if abs(u - commands.delayed(delay + 1)) > settings.change_gate:
            self._quiet = settings.hold_off
            return False
        if self._quiet > 0:
            self._quiet -= 1
            return False
        limits = self.model.angle_limits
        if limits is not None:
            low, high = limits[0] + settings.margin, limits[1] - settings.margin
            if y < low or previous < low or y > high or previous > high:
                return False
        # Time update of the random walk, in place: its diagonal grows.
        r = self.r
        p = self._p
        n0, n1, n2, n3, n4, n5 = self._ratios
        add_to_diagonal(p, (n0 * r, n1 * r, n2 * r, n3 * r, n4 * r, n5 * r))
        theta = self._theta
        if not lagged:
            q, psi = self._map_and_gradient(u, theta, settings.kappa)
        innovation = (y - previous) - q
        Ppsi, spread = times(p, psi)
        S = r + spread
        # A joint that changed (wear, a new valve) shows as innovations persistently larger
        # than the filter expects: then the covariance is reset so that it re-learns fast,
        # instead of creeping along its slow random walk (or rejecting the news as outliers).
        # (Comparisons stand for min/max: a builtin call per clip costs more than the clip.)
        z = innovation / math.sqrt(S)
        normalised = z * z
        normalised = 100.0 if 100.0 < normalised else normalised
        self.nis += (normalised - self.nis) / settings.change_memory
        cusum = self._cusum
        side = 0 if u < 0.5 * (theta[2] + theta[5]) else 2
        drift = settings.cusum_drift
        z = -10.0 if -10.0 > z else 10.0 if 10.0 < z else z
        rising = cusum[side] + z - drift
        falling = cusum[side + 1] - z - drift
        cusum[side] = rising if rising > 0.0 else 0.0
        cusum[side + 1] = falling if falling > 0.0 else 0.0
        self._since_reset += 1
        limit = settings.cusum_limit
        lower = cusum[0] > limit or cusum[1] > limit
        upper = cusum[2] > limit or cusum[3] > limit
        if self.nis > settings.change_level:
            lower = upper = True
        if (lower or upper) and self._since_reset > 5 * settings.change_memory:
            self._reset_covariance(lower, upper)
            Ppsi, spread = times(p, psi)
            S = r + spread
        elif self.updates > 100 and innovation * innovation > settings.outlier ** 2 * S:
            return False
        h0, h1, h2, h3, h4, h5 = Ppsi
        gain = (h0 / S, h1 / S, h2 / S, h3 / S, h4 / S, h5 / S)
        self._p = downdated(p, gain, Ppsi)
        self._theta = boxed(theta, gain, innovation, self._lower, self._upper)
        # Track the noise level slowly, never below a quarter of the start value.
        r = 0.999 * r + 0.001 * (innovation * innovation - spread)
        self.r = r if r > self._r_min else self._r_min
        self.updates += 1
        return True

    def _lagged(self, u: float) -> tuple[float, Six]:
        """Advance the valve lag on the map at ``u``: the increment and gradient it predicts."""
        q, psi = self._map_and_gradient(u, self._theta, self.settings.kappa)
        p = self._lag_pole
        assert p is not None
        c = 1.0 - p
        g0, g1, g2, g3, g4, g5 = self._lag_gradient
        d0, d1, d2, d3, d4, d5 = psi
        self._lag_speed = p * self._lag_speed + c * q
        command = self._lag_command
        self._lag_command = u if command != command else p * command + c * u   # NaN: first
        self._lag_gradient = (p * g0 + c * d0, p * g1 + c * d1, p * g2 + c * d2,
                              p * g3 + c * d3, p * g4 + c * d4, p * g5 + c * d5)
        return self._lag_speed, self._lag_gradient

    def _reset_covariance(self, lower: bool, upper: bool) -> None:
        """Add part of the start covariance back on the side(s) that changed (section 7.4)."""
        below = 1.0 if lower else 0.0
        above = 1.0 if upper else 0.0
        v = self._start_variances
        add_to_diagonal(self._p, (v[0] * 0.01 * below, v[1] * 0.01 * below, v[2] * below,
                                  v[3] * 0.01 * above, v[4] * 0.01 * above, v[5] * above))
        self.nis = 1.0
        self._cusum[:] = [0.0, 0.0, 0.0, 0.0]
        self._since_reset = 0
        self.resets += 1


class OnlineSdpIdentifier(OnlineMapFilter):
    """
    Random-walk Kalman filter on the six coefficients ``(a1 .. a6)`` of eq. (5).

    ``model``: starting point (kind ``sdp``) and the delay and end stops to use.
    ``dt``: sample period of the incoming samples, s.
    """

    def __init__(self, model: JointModel, dt: SamplePeriod,
                 settings: OnlineSettings = OnlineSettings()) -> None:
        if not isinstance(model.static_map, SdpMap):
            raise ConfigurationError(f'OnlineSdpIdentifier tracks kind sdp models, not '
                                     f'{model.kind}: use online_identifier')
        super().__init__(model, dt, settings)

    def _start(self) -> tuple[Six, Six, Six, Six, Six]:
        s = self.settings.input_scale
        a1, a2, a3, a4, a5, a6 = (float(a) for a in self.model.alpha(self.dt))
        speed = (self.dt / 0.01) ** 2
        variances = (0.01 * speed, 1.0 / s ** 2, 0.5 * s ** 2,
                     0.01 * speed, 1.0 / s ** 2, 0.5 * s ** 2)
        scales = (speed, 1.0 / s ** 2, s ** 2, speed, 1.0 / s ** 2, s ** 2)
        r0, r1, r2, r3, r4, r5 = (ratio * scale
                                  for ratio, scale in zip(NOISE_VARIANCE_RATIOS, scales))
        lower = (5.0 * a1, 0.1 / s, -4.0 * s * max(1.0, abs(a3)), 0.0, 0.1 / s, a3)
        upper = (0.0, 10.0 / s, a6, 5.0 * a4, 10.0 / s, 4.0 * s * max(1.0, abs(a6)))
        return (a1, a2, a3, a4, a5, a6), variances, (r0, r1, r2, r3, r4, r5), lower, upper

    def _map_and_gradient(self, u: float, theta: list[float],
                          kappa: float) -> tuple[float, Six]:
        return map_and_soft_gradient(u, theta, kappa)

    def static_map(self) -> SdpMap:
        """Return the current estimate as a rate-based map."""
        return SdpMap.from_alpha(tuple(self._theta), self.dt)

    def estimate(self, edges: tuple[float, float] | None = None) -> JointModel:
        """Return the model with the current estimate of its map (optionally other edges)."""
        static_map = self.static_map()
        if edges is not None:
            static_map = replace(static_map, dead_zone=(float(edges[0]), float(edges[1])))
        return replace(self.model, static_map=static_map)

    def named_estimate(self) -> SdpEstimate:
        """Return the current estimate and its standard deviations by name."""
        a1, a2, a3, a4, a5, a6 = self._theta
        s1, s2, s3, s4, s5, s6 = (float(s) for s in self.standard_errors)
        dt = self.dt
        return SdpEstimate(a3, a6, a1 / dt, a4 / dt, a2, a5, s3, s6, s1 / dt, s4 / dt, s2, s5)
