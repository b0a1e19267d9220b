"""
Simulation of a joint model at any sample period (methods 3.1-3.4).

:func:`simulate` runs a whole command sequence; :class:`JointSimulator` steps the
same equations one sample at a time. ``v_k`` is the command in force over the
interval that ends at ``t_k`` (methods 3.4).
"""

from __future__ import annotations

from dataclasses import replace
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.angle_recursion import integrate_angle_dependent
from hydro_sdp.core.model.bounded_sum import bounded_cumsum
from hydro_sdp.core.model.effects import (
    AngleDependentVelocity, Backlash, DirectionDependentDelay, FlowSharing, LoadDependence,
    Oscillation, StrokeGeometry, ValveLag)
from hydro_sdp.core.model.exogenous_signals import Exogenous, exogenous_factor
from hydro_sdp.core.model.first_order import first_order
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.link_mode import LinkMode, LinkState
from hydro_sdp.core.model.static_maps import StaticMap
from hydro_sdp.core.model.timing import delay_samples, delayed, DelayLine, SamplePeriod
import numpy as np


def _rate_of_levels(model: JointModel, v: FloatArray) -> FloatArray:
    """Evaluate the static map once per held level rather than once per sample."""
    starts = np.flatnonzero(np.diff(v)) + 1
    if 2 * (starts.size + 1) > v.size:
        return model.rate(v)
    starts = np.r_[0, starts]
    return np.repeat(model.rate(v[starts]), np.diff(np.r_[starts, v.size]))


def _limits(model: JointModel) -> tuple[float, float]:
    if model.angle_limits is None:
        return -math.inf, math.inf
    return model.angle_limits


def _check_commands(v: FloatArray) -> FloatArray:
    v = np.asarray(v, dtype=np.float64)
    if v.ndim != 1:
        raise DataError(f'commands must be a 1-D sequence, got shape {v.shape}')
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        raise DataError(f'{bad.size} commands are not finite (first at sample {bad[0]})')
    return v


def simulate(model: JointModel, v: FloatArray, dt: float, y0: float,
             *, v_before: float = 0.0, start: int = 0,
             backlash_offset: float = 0.0, exogenous: Exogenous | None = None) -> FloatArray:
    """
    Simulate the joint's angle for a command sequence.

    Parameters
    ----------
    model : JointModel
        The joint.
    v : FloatArray
        Command at each sample (held over the sample period), input units.
    dt : float
        Sample period, s.
    y0 : float
        Angle at sample ``start``, degrees (clamped into the end stops).
    v_before : float
        Command assumed before the first sample (fills the delay line).
    start : int
        Sample the simulation starts from; the commands before it are history
        (a measured record is best simulated from ``start`` = its delay, where
        the delayed commands are all known).
    backlash_offset : float
        Sensor angle minus actuator angle at the start, within +-play/2 (with backlash).
    exogenous : Exogenous or None
        The record's load and other joints' speeds (``load_dependence``, ``flow_sharing``).

    Returns
    -------
    FloatArray
        Angle at each sample, degrees; ``y[start]`` is ``y0`` and the samples
        before ``start`` repeat it.

    See Also
    --------
    evaluate : simulation against measured records.

    Examples
    --------
    >>> import numpy as np
    >>> from hydro_sdp import load_model, simulate
    >>> model = load_model('config/brokk_j2.yaml')
    >>> y = simulate(model, np.full(200, 4.0), 0.01, 30.0)
    >>> bool(y[-1] > y[0])
    True

    """
    dt = SamplePeriod(dt)
    v = _check_commands(v)
    if v.size == 0:
        return np.empty(0)
    speed = speed_profile(model, v, dt, v_before=v_before, exogenous=exogenous)
    if not 0 <= start < v.size:
        raise DataError(f'start must be a sample index below {v.size}, got {start}')
    y = integrate_speed(model, speed[start:], dt, y0, backlash_offset)
    return np.r_[np.full(start, y[0]), y] if start else y


def integrate_speed(model: JointModel, speed: FloatArray, dt: SamplePeriod, y0: float,
                    backlash_offset: float) -> FloatArray:
    """Return the angles from ``y0`` under ``speed`` (its first value is of no interval)."""
    low, high = _limits(model)
    gravity, geometry = _angle_effects(model)
    play = model.effect(Backlash.name)
    half = 0.5 * play.play if isinstance(play, Backlash) else 0.0
    # The sensor reads the actuator plus the play's offset e in [-b, b]: the actuator
    # starts e away from the angle read, and it is the actuator that meets the stops.
    initial = min(max(backlash_offset, -half), half)
    mode = _link_mode(model, dt)
    # With the link's mode the actuator starts where a link settled at the first speed
    # trails it from (the angle read).
    lead = 0.0 if mode is None or speed.size == 0 else mode.lead * float(speed[0])
    if gravity is not None or geometry is not None:
        y = integrate_angle_dependent(speed, dt, y0 - initial + lead, low, high, gravity,
                                      geometry)
    else:
        y = bounded_cumsum(y0 - initial + lead, dt * speed[1:], low, high)
    if mode is not None:
        y = mode.ring(y, dt, float(speed[0]))
    if half > 0.0:
        # e_k = clamp(e_{k-1} - dy_k): the sensor lags the actuator's motion.
        offset = bounded_cumsum(initial, -np.diff(y), -half, half)
        y = np.clip(y + offset, low, high)
    elif mode is not None:
        y = np.clip(y, low, high)
    return y


def _link_mode(model: JointModel, dt: SamplePeriod) -> LinkMode | None:
    """Return the model's link mode at ``dt``, or None without ``oscillation``."""
    effect = model.effect(Oscillation.name)
    return LinkMode.of(effect, dt) if isinstance(effect, Oscillation) else None


def speed_profile(model: JointModel, v: FloatArray, dt: SamplePeriod, *,
                  v_before: float = 0.0, exogenous: Exogenous | None = None) -> FloatArray:
    """
    Speed ``w_k`` (deg/s) from ``y_{k-1}`` to ``y_k``, before end stops (methods 3.6).

    ``dt``: sample period, s.
    ``v_before``: command assumed before the first sample.
    ``exogenous``: the record's load and other joints' speeds.
    Returns: one speed per sample (``w_0`` belongs to no interval).
    """
    v = _check_commands(v)
    rates = _rate_of_levels(model, v)
    rate_before = float(model.rate(np.array([v_before]))[0])
    split = model.effect(DirectionDependentDelay.name)
    speed: FloatArray
    if isinstance(split, DirectionDependentDelay):
        speed = (delayed(np.maximum(rates, 0.0), delay_samples(split.positive, dt),
                         max(rate_before, 0.0))
                 + delayed(np.minimum(rates, 0.0), delay_samples(split.negative, dt),
                           min(rate_before, 0.0)))
    else:
        speed = delayed(rates, model.delay_samples(dt), rate_before)
    lag = model.effect(ValveLag.name)
    if isinstance(lag, ValveLag):
        p = math.exp(-dt / lag.time_constant)
        speed = first_order(speed, p, 1.0 - p, rate_before)
    factor = exogenous_factor(model, speed, exogenous)
    return speed if factor is None else speed * factor


def one_step_increments(model: JointModel, v: FloatArray, y: FloatArray, dt: SamplePeriod, *,
                        start: int = 0, v_before: float = 0.0,
                        exogenous: Exogenous | None = None) -> FloatArray:
    """
    Return the increments ``y^_k - y_{k-1}`` predicted from each measured angle (methods 8.1).

    ``y``: measured angles, degrees.
    ``start``: first sample whose delayed commands are known.
    Returns: predicted increments for samples ``start + 1 ..``.
    """
    mode = model.effect(Oscillation.name)
    steps = OneStep(model.without_effect(Oscillation.name) if mode is not None else model, v, y,
                    dt, start=start, v_before=v_before, exogenous=exogenous,
                    from_start=mode is None)
    return steps.increments(mode if isinstance(mode, Oscillation) else None)


class OneStep:
    """
    The one-step increments of a model for any link mode added to it.

    ``from_start``: whether only the increments from ``start`` are needed (no mode will be added).
    """

    def __init__(self, model: JointModel, v: FloatArray, y: FloatArray, dt: SamplePeriod, *,
                 start: int = 0, v_before: float = 0.0, exogenous: Exogenous | None = None,
                 from_start: bool = False) -> None:
        self.model, self.dt, self.start = model, dt, start
        profile = speed_profile(model, v, dt, v_before=v_before, exogenous=exogenous)
        self.y = np.asarray(y, dtype=np.float64)
        # The mode's state depends on the motion before ``start``: it runs from the
        # record's start (settled there), so that a link still ringing at ``start`` is
        # predicted.
        self.first = start if from_start else 0
        self.before = float(profile[self.first]) if profile.size else 0.0
        self.actuator = _actuator_increments(model, profile[self.first + 1:],
                                             self.y[self.first:-1], dt)

    def increments(self, mode: Oscillation | None = None) -> FloatArray:
        """Return the predicted increments for samples ``start + 1 ..`` with ``mode`` added."""
        model, start, first = self.model, self.start, self.first
        low, high = _limits(model)
        increment = self.actuator
        if mode is not None and increment.size:
            if first != 0:
                raise ValueError("a mode needs the increments from the record's start")
            increment = _ringing_increments(LinkMode.of(mode, self.dt), increment,
                                            self.y[:-1], self.dt, self.before, low, high)
        increment = increment[start - first:]
        previous = self.y[start:-1]
        play = model.effect(Backlash.name)
        if isinstance(play, Backlash) and play.play > 0.0:
            half = 0.5 * play.play
            offset = bounded_cumsum(0.0, -increment, -half, half)
            increment = increment + np.diff(offset)
        return np.clip(previous + increment, low, high) - previous


def _actuator_increments(model: JointModel, speed: FloatArray, previous: FloatArray,
                         dt: SamplePeriod) -> FloatArray:
    """Return ``dt`` times ``speed`` with the angle effects at the ``previous`` angles."""
    gravity, geometry = _angle_effects(model)
    if geometry is not None:
        speed = speed * geometry.factor(previous, speed)
    increment = dt * speed
    if gravity is not None:
        increment = increment + dt * gravity.amplitude * np.abs(speed) * np.cos(
            np.radians(previous + gravity.phase))
    return increment


def _ringing_increments(mode: LinkMode, increment: FloatArray, previous: FloatArray,
                        dt: SamplePeriod, before: float, low: float, high: float) -> FloatArray:
    """Return the link's increments for the actuator's; the mode starts settled at ``before``."""
    deviation, speed = mode.states(increment / dt, before)
    settled = mode.settled(before)
    out = increment + np.diff(np.concatenate(([settled[0]], deviation)))
    # Until the actuator first meets a stop this is the recursion of methods 3.6, all at once.
    actuator = previous - np.concatenate(([settled[0]], deviation[:-1]))
    meets = _meets(increment, actuator, low, high)
    if meets.size == 0:
        return out
    # From there the actuator alternates between moving freely and pressing a stop. The
    # mode is linear: a free stretch is the pass above plus the free ringing of the
    # difference of the states where the stretch starts, a pressed one the free ringing of
    # its own; only the samples that meet or leave a stop are stepped one at a time.
    pole, column, row = mode.modal
    powers = pole ** np.arange(1, min(_CHUNK, increment.size) + 1)
    towards = 2.0 * column[0] * powers, 2.0 * column[1] * powers

    def ringing(state: tuple[float, float], count: int) -> tuple[FloatArray, FloatArray]:
        modal = row[0] * state[0] + row[1] * state[1]
        return ((modal * towards[0][:count]).real, (modal * towards[1][:count]).real)

    k, size, pressed = int(meets[0]), increment.size, 0.0
    state = settled if k == 0 else (float(deviation[k - 1]), float(speed[k - 1]))
    while k < size:
        # A chunk at a time, so that a record that meets its stops often does not
        # follow its whole remainder at every meeting.
        limit = min(k + _CHUNK, size)
        if pressed:
            held = np.flatnonzero(pressed * increment[k:limit] <= 0.0)
            turns = held.size > 0
            end = k + int(held[0]) if turns else limit
            stop = high if pressed > 0.0 else low
            e, u = ringing(state, end - k)
            e_before = np.concatenate(([state[0]], e[:-1]))
            # The link swung beyond the stop, where the sensor cannot follow it.
            beyond = (stop + e_before < low) | (stop + e_before > high)
            out[k:end] = np.where(beyond, np.clip(stop + e, low, high) - previous[k:end],
                                  e - e_before)
            actuator_k = stop
        else:
            passed = settled if k == 0 else (deviation[k - 1], speed[k - 1])
            e, u = ringing((state[0] - passed[0], state[1] - passed[1]), limit - k)
            e, u = e + deviation[k:limit], u + speed[k:limit]
            e_before = np.concatenate(([state[0]], e[:-1]))
            meets = _meets(increment[k:limit], previous[k:limit] - e_before, low, high)
            turns = meets.size > 0
            end = k + int(meets[0]) if turns else limit
            out[k:end] = increment[k:end] + e[:end - k] - e_before[:end - k]
            actuator_k = float(previous[end] - e_before[end - k]) if turns else 0.0
        if end > k:
            state = (float(e[end - k - 1]), float(u[end - k - 1]))
        k = end
        if not turns:
            continue
        # The sample that meets (or leaves) a stop, as the recursion steps it.
        step, angle = float(increment[k]), float(previous[k])
        moved, pressed = step, 0.0
        if step > 0.0 and actuator_k + step >= high:
            moved, pressed = max(high - actuator_k, 0.0), 1.0
        elif step < 0.0 and actuator_k + step <= low:
            moved, pressed = min(low - actuator_k, 0.0), -1.0
        link = LinkState(mode, 0.0, state)
        swung = link.step(moved / dt)
        stop = high if pressed > 0.0 else low
        if pressed and not low <= stop + state[0] <= high:
            out[k] = min(max(stop + swung, low), high) - angle
        else:
            out[k] = moved + swung - state[0]
        state = (link.e, link.u)
        k += 1
    return out


#: Samples followed at once between the meetings with a stop.
_CHUNK = 256


def _meets(increment: FloatArray, actuator: FloatArray, low: float,
           high: float) -> np.ndarray:
    """Return where an actuator at ``actuator`` meets a stop over its ``increment``."""
    return np.flatnonzero(((increment > 0.0) & (actuator + increment >= high))
                          | ((increment < 0.0) & (actuator + increment <= low)))


AngleEffects = tuple[AngleDependentVelocity | None, StrokeGeometry | None]


def _angle_effects(model: JointModel) -> AngleEffects:
    gravity = model.effect(AngleDependentVelocity.name)
    geometry = model.effect(StrokeGeometry.name)
    return (gravity if isinstance(gravity, AngleDependentVelocity) else None,
            geometry if isinstance(geometry, StrokeGeometry) else None)


class JointSimulator:
    """
    Step a joint model one sample at a time; :meth:`step` takes ``v_{k+1}``.

    ``dt``: sample period, s.
    ``y0``: angle at the first sample, degrees.
    ``v_before``: command in force up to and including the first sample.
    """

    def __init__(self, model: JointModel, dt: SamplePeriod, y0: float, *,
                 v_before: float = 0.0) -> None:
        self.model = model
        self.dt = dt
        self._low, self._high = _limits(model)
        split = model.effect(DirectionDependentDelay.name)
        if isinstance(split, DirectionDependentDelay):
            self._tau_pos = delay_samples(split.positive, self.dt)
            self._tau_neg = delay_samples(split.negative, self.dt)
        else:
            self._tau_pos = self._tau_neg = model.delay_samples(self.dt)
        rate_before = float(model.rate(np.array([v_before]))[0])
        # Speeds of v_{k+1}, v_k, ...: delayed(tau) is rate(v_{k+1-tau}).
        self._rates = DelayLine(max(self._tau_pos, self._tau_neg), rate_before)
        lag = model.effect(ValveLag.name)
        self._lag_p = math.exp(-self.dt / lag.time_constant) if isinstance(lag, ValveLag) else None
        self._lag_state = rate_before
        self._gravity, self._geometry = _angle_effects(model)
        self._exogenous = any(model.effect(name) is not None
                              for name in (FlowSharing.name, LoadDependence.name))
        play = model.effect(Backlash.name)
        self._half_play = 0.5 * play.play if isinstance(play, Backlash) else 0.0
        mode = _link_mode(model, self.dt)
        self._link = None if mode is None else LinkState(mode, rate_before)
        # The link reads y0 and trails the actuator (its deviation e, settled).
        self._deviation = 0.0 if self._link is None else self._link.e
        self._actuator = min(max(float(y0) - self._deviation, self._low), self._high)
        self._offset = 0.0
        self.samples = 0

    def set_static_map(self, static_map: StaticMap) -> None:
        """Swap the command-to-speed map; commands in the delay line keep their speeds."""
        self.model = replace(self.model, static_map=static_map)

    @property
    def angle(self) -> float:
        """Return the angle the sensor reads now, degrees."""
        return min(max(self._actuator + self._deviation + self._offset, self._low), self._high)

    def step(self, v: float) -> float:
        """
        Issue command ``v`` now and advance one sample.

        ``v``: command in force over the next sample, input units (must be finite).
        Returns: angle at the next sample, degrees.
        """
        if not math.isfinite(v):
            raise DataError(f'command must be finite, got {v}')
        self._rates.push(float(self.model.rate(np.array([v]))[0]))
        if self._tau_pos == self._tau_neg:
            speed = self._rates.delayed(self._tau_pos)
        else:
            speed = (max(self._rates.delayed(self._tau_pos), 0.0)
                     + min(self._rates.delayed(self._tau_neg), 0.0))
        if self._lag_p is not None:
            # The lag's recursion, sample by sample (first_order runs it over arrays).
            self._lag_state = (1.0 - self._lag_p) * speed + self._lag_p * self._lag_state
            speed = self._lag_state
        if self._exogenous:
            # No signals here: no load factor, the other joints still.
            factor = exogenous_factor(self.model, np.array([speed]))
            speed *= 1.0 if factor is None else float(factor[0])
        previous = self._actuator
        if self._geometry is not None:
            speed *= self._geometry.factor_at(previous, speed)
        if self._gravity is not None:
            phase = math.radians(self._gravity.phase)
            speed += self._gravity.amplitude * abs(speed) * math.cos(
                math.radians(previous) + phase)
        self._actuator = min(max(previous + self.dt * speed, self._low), self._high)
        moved = self._actuator - previous
        if self._link is not None:
            deviation = self._deviation
            self._deviation = self._link.step(moved / self.dt)
            moved += self._deviation - deviation
        if self._half_play > 0.0:
            self._offset = min(max(self._offset - moved, -self._half_play), self._half_play)
        self.samples += 1
        return self.angle
