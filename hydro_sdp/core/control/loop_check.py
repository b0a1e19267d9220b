"""The closed-loop check of a controller on a model, and slower re-designs (methods 4.6, 10)."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, Sequence

from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.control.loop_chatter import Chatter, loop_chatter
from hydro_sdp.core.control.loop_simulation import (
    LoopJoint, LoopTrace, run_closed_loop, step_metrics, StepMetrics, valve_reversals)
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Fractions of the stroke (between the end stops) the check steps between.
STROKE_LEVELS = (0.2, 0.5, 0.8)
#: Largest overshoot allowed, percent of the step.
MAX_OVERSHOOT = 10.0
#: Valve reversals in the last seconds of a hold that make a limit cycle.
CYCLE_REVERSALS = 4


@dataclass(frozen=True)
class CheckSettings:
    """
    What the closed-loop check asks of a controller.

    Attributes
    ----------
    dt : SamplePeriod
        Plant sample period, s (a number is checked and wrapped).
    settling : float
        Settling time allowed on top of the travel at a quarter of full speed, s.
    band : float
        Settling band around the set-point, degrees.
    hold : float
        Time each set-point is held, s (at least the allowed settling plus ``tail``).
    tail : float
        Last seconds of each hold watched for a limit cycle, s.
    noise_std : float
        Angle measurement noise, standard deviation, degrees (``calibrate``: the noise identify
        found in the records).

    """

    dt: SamplePeriod = SamplePeriod(0.01)
    settling: float = 6.0
    band: float = 0.5
    hold: float = 10.0
    tail: float = 2.0
    noise_std: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, 'dt', SamplePeriod(self.dt))


@dataclass(frozen=True, eq=False)
class LoopCheck:
    """
    The verdict of one closed-loop check.

    Attributes
    ----------
    steps : tuple[StepMetrics, ...]
        Settling time and overshoot of each step across the stroke.
    bounds : tuple[float, ...]
        Settling time allowed for each step, s.
    ramp_error : float
        Largest tracking error while following the ramp, degrees.
    ramp_settling : float
        Settling time after the ramp ends, s (``inf``: never).
    failures : tuple[str, ...]
        Why it failed, one line each (empty when it passed).
    chatter : Chatter
        The valve's pulses and travel at hold over both runs.

    """

    passed: bool
    steps: tuple[StepMetrics, ...]
    bounds: tuple[float, ...]
    ramp_error: float
    ramp_settling: float
    cycles: int
    failures: tuple[str, ...]
    steps_trace: LoopTrace
    ramp_trace: LoopTrace
    chatter: Chatter

    @property
    def settling_range(self) -> tuple[float, float]:
        """Return the shortest and longest settling time of the steps, s."""
        times = [float(m.settling_time) for m in self.steps] or [math.nan]
        return min(times), max(times)


def stroke_levels(stroke: tuple[float, float]) -> tuple[float, ...]:
    """Return the set-points at 20, 50 and 80 % of the stroke, degrees."""
    low, high = stroke
    if not (math.isfinite(low) and math.isfinite(high) and high > low):
        raise ConfigurationError(f'the stroke must be an increasing pair, got {stroke}')
    return tuple(low + fraction * (high - low) for fraction in STROKE_LEVELS)


def full_speed(model: JointModel) -> float:
    """Slower of the two directions' largest speeds, deg/s."""
    saturation = getattr(model.static_map, 'saturation_velocity', None)
    if saturation is not None:
        return float(min(abs(saturation[0]), abs(saturation[1])))
    limits = model.input_limits
    if limits is None:
        rest = model.rest_command
        span = 10.0 if model.dead_zone is None else 4.0 * max(
            abs(model.dead_zone[0] - rest), abs(model.dead_zone[1] - rest), 1e-3)
        limits = (rest - span, rest + span)
    speeds = np.abs(model.rate(np.array(limits, dtype=np.float64)))
    return float(max(np.min(speeds), 1e-6))


def _cycles(trace: LoopTrace, ends: Sequence[int], settings: CheckSettings, rest: float) -> int:
    """Count the holds (ending at ``ends``) whose last ``tail`` seconds hunt or wander."""
    tail = max(2, int(round(settings.tail / settings.dt)))
    count = 0
    for end in ends:
        window = slice(max(0, end - tail), end)
        hunting = valve_reversals(trace.v[window], rest) >= CYCLE_REVERSALS
        wandering = float(np.ptp(trace.y[window])) > settings.band
        count += int(hunting or wandering)
    return count


def check_loop(model: JointModel, spec: ControllerSpec, stroke: tuple[float, float], *,
               settings: CheckSettings | None = None,
               on_sample: Callable[[int, int], None] | None = None) -> LoopCheck:
    """
    Run a controller on a model over steps across the stroke and a ramp, and judge it.

    ``stroke``: range between the end stops (or the angles the joint was seen at), degrees.
    ``settings``: bounds and timing; default :class:`CheckSettings`.
    ``on_sample``: progress, as ``on_sample(done, total)``.
    """
    settings = settings if settings is not None else CheckSettings()
    low, middle, high = stroke_levels(stroke)
    speed = full_speed(model)
    rest = model.rest_command
    levels = [middle, high, middle, low]
    hold = max(settings.hold, settings.settling + settings.tail
               + abs(high - middle) / (0.25 * speed))
    per_level = int(round(hold / settings.dt))
    setpoint = np.repeat(np.array(levels), per_level)
    ramp_time = (high - low) / (0.25 * speed)
    t = np.arange(int(round((1.0 + ramp_time + hold) / settings.dt))) * settings.dt
    ramp = np.interp(t, [0.0, 1.0, 1.0 + ramp_time], [low, low, high])
    total = setpoint.size + ramp.size

    def progress(offset: int) -> Callable[[int, int], None] | None:
        if on_sample is None:
            return None
        return lambda done, _: on_sample(offset + done, total)

    steps_trace = run_closed_loop([LoopJoint(model, spec.controller(), setpoint, low)],
                                  dt=settings.dt, control_period=spec.control_period,
                                  noise_std=settings.noise_std, seed=settings.seed,
                                  on_sample=progress(0))[0]
    ramp_trace = run_closed_loop([LoopJoint(model, spec.controller(), ramp, low)],
                                 dt=settings.dt, control_period=spec.control_period,
                                 noise_std=settings.noise_std, seed=settings.seed + 1,
                                 on_sample=progress(setpoint.size))[0]
    metrics = tuple(step_metrics(steps_trace, band=settings.band, initial=low))
    bounds = tuple(settings.settling + abs(m.size) / (0.25 * speed) for m in metrics)
    ended = t >= 1.0 + ramp_time
    error = np.abs(ramp_trace.y - ramp_trace.setpoint)
    outside = np.flatnonzero(error[ended] > settings.band)
    if outside.size == 0:
        ramp_settling = 0.0
    elif outside[-1] == int(np.count_nonzero(ended)) - 1:
        ramp_settling = math.inf
    else:
        ramp_settling = (outside[-1] + 1) * settings.dt
    cycles = (_cycles(steps_trace, range(per_level, setpoint.size + 1, per_level), settings,
                      rest)
              + _cycles(ramp_trace, [ramp.size], settings, rest))
    failures = []
    for m, bound in zip(metrics, bounds):
        if not m.settling_time <= bound:
            failures.append(f'the {m.size:+.1f} deg step at {m.start:.0f} s does not settle into '
                            f'+-{settings.band:g} deg within {bound:.1f} s')
        if m.overshoot > MAX_OVERSHOOT:
            failures.append(f'the {m.size:+.1f} deg step at {m.start:.0f} s overshoots by '
                            f'{m.overshoot:.1f} %')
    ramp_bound = settings.settling
    if not ramp_settling <= ramp_bound:
        failures.append(f'the ramp does not settle within {ramp_bound:.1f} s of its end')
    if cycles:
        failures.append(f'{cycles} hold{"s" if cycles != 1 else ""} end in a limit cycle')
    chatter = loop_chatter([steps_trace, ramp_trace], model, spec.idz,
                           spec.v_limits or model.input_limits, band=settings.band)
    failures.extend(chatter.failures)
    return LoopCheck(not failures, metrics, bounds, float(np.max(error[~ended])),
                     ramp_settling, cycles, tuple(failures), steps_trace, ramp_trace, chatter)


def slower_poles(poles: Sequence[complex], factor: float = 0.7,
                 keep: Sequence[complex] = ()) -> list[complex]:
    """Move the dominant poles toward 1: ``p -> 1 - factor (1 - p)``."""
    if not 0.0 < factor < 1.0:
        raise ConfigurationError(f'the pole factor must be in (0, 1), got {factor}')
    values = [complex(p) for p in poles]
    largest = max((abs(p) for p in values), default=0.0)
    return [1.0 - factor * (1.0 - p) if abs(p) >= 0.5 * largest and largest > 0.0
            and not any(abs(p - k) < 1e-6 for k in keep) else p for p in values]
