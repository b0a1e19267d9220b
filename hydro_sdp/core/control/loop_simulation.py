"""Offline closed-loop simulation of PIP-IDZ controlled joints, and step metrics (methods 4.6)."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.control.pip_controller import PipIdzController
from hydro_sdp.core.control.scheduling import ControlSchedule, seconds_to_ns
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.sample_period import control_steps
from hydro_sdp.core.model.simulation import JointSimulator
from hydro_sdp.core.model.timing import command_in_force, SamplePeriod
import numpy as np


@dataclass(frozen=True, eq=False)
class LoopJoint:
    """
    One joint in a closed loop.

    Attributes
    ----------
    setpoint : FloatArray
        Desired angle at every plant sample, degrees.
    y0 : float
        Starting angle, degrees.
    feedforward : FloatArray or None
        Feed-forward at every plant sample, degrees per control sample (used at the control
        instants, see :meth:`PipIdzController.step`); ``None``: none.

    """

    model: JointModel
    controller: PipIdzController
    setpoint: FloatArray
    y0: float = 0.0
    feedforward: FloatArray | None = None


@dataclass(frozen=True, eq=False)
class LoopTrace:
    """
    What happened to one joint.

    Attributes
    ----------
    t : FloatArray
        Plant sample times, s.
    y : FloatArray
        True angle, degrees.
    measured : FloatArray
        Angle the controller saw (with noise), degrees.
    v : FloatArray
        Valve command in force over the interval ending at each sample (as in a
        :class:`~hydro_sdp.core.model.records.Record`): the controller's answer to ``y_j`` is
        ``v[j + 1]``.
    u : FloatArray
        Controller increment alongside ``v``, degrees per control sample.
    setpoint : FloatArray
        Desired angle, degrees.

    """

    joint: str
    t: FloatArray
    y: FloatArray
    measured: FloatArray
    v: FloatArray
    u: FloatArray
    setpoint: FloatArray


def run_closed_loop(joints: Sequence[LoopJoint], *, dt: SamplePeriod,
                    control_period: SamplePeriod,
                    noise_std: float = 0.0, seed: int = 0,
                    on_sample: Callable[[int, int], None] | None = None) -> list[LoopTrace]:
    """
    Simulate joints under PIP-IDZ control.

    ``joints``: the joints; all set-point arrays have the same length (the run's samples).
    ``dt``: plant sample period, s.
    ``control_period``: controller period, s: a whole multiple of ``dt`` (within
    :data:`~hydro_sdp.core.model.sample_period.PERIOD_TOLERANCE`: the controller steps every that
    many samples).
    ``noise_std``: standard deviation of the angle measurement noise, degrees.
    ``on_sample``: called as ``on_sample(done, total)`` every 1000 samples (progress).
    Returns: one trace per joint.
    """
    every = control_steps(control_period, dt)
    if not joints:
        raise ConfigurationError('no joints to simulate')
    samples = len(joints[0].setpoint)
    if any(len(joint.setpoint) != samples for joint in joints):
        raise ConfigurationError('every joint needs a set-point for every sample')
    if any(joint.feedforward is not None and len(joint.feedforward) != samples
           for joint in joints):
        raise ConfigurationError('a feed-forward needs a value for every sample')
    if not noise_std >= 0.0 or not math.isfinite(noise_std):
        raise ConfigurationError(f'noise_std must be >= 0, got {noise_std}')
    # One stream per joint, seeded [seed, index]: the plant node draws the same numbers
    # one sample at a time.
    noise = np.array([np.random.default_rng([seed, index]).normal(0.0, noise_std, samples)
                      if noise_std > 0 else np.zeros(samples) for index in range(len(joints))])
    dt_ns = seconds_to_ns(dt)
    stamps = np.arange(samples, dtype=np.int64) * dt_ns
    traces = []
    for index, joint in enumerate(joints):
        simulator = JointSimulator(joint.model, dt, joint.y0, v_before=joint.controller.last_v)
        setpoint = np.asarray(joint.setpoint, dtype=np.float64)
        feedforward = (None if joint.feedforward is None
                       else np.asarray(joint.feedforward, dtype=np.float64))
        y = np.empty(samples)
        measured = np.empty(samples)
        # The controller acts at the node's control instants; offline the valve is never
        # closed by a watchdog, so a 'resume' tick is a plain step (the controller may come
        # with a history to continue from).
        schedule = ControlSchedule(every * dt_ns)
        issued: list[int] = []
        answers = [(joint.controller.last_u, joint.controller.last_v)]
        command = joint.controller.last_v
        for j in range(samples):
            y[j] = simulator.angle
            measured[j] = y[j] + noise[index, j]
            if schedule.tick(int(stamps[j])) != 'wait':
                if feedforward is None:
                    answer = joint.controller.step(float(setpoint[j]), measured[j])
                else:
                    answer = joint.controller.step(float(setpoint[j]), measured[j],
                                                   float(feedforward[j]))
                schedule.stepped(int(stamps[j]))
                issued.append(int(stamps[j]))
                answers.append(answer)
                command = answer[1]
            simulator.step(command)
            if on_sample is not None and j % 1000 == 0:
                on_sample(index * samples + j, len(joints) * samples)
        # v_j is the answer in force over the interval ending at sample j: the last one
        # issued before t_j (index 0 of ``answers`` is what was in force before the run).
        u, v = np.array(answers)[command_in_force(stamps, np.array(issued, dtype=np.int64)) + 1].T
        traces.append(LoopTrace(joint.model.joint, np.arange(samples) * dt, y, measured, v, u,
                                setpoint))
    return traces


def step_setpoints(levels: Sequence[float], hold: float, dt: SamplePeriod) -> FloatArray:
    """Set-point array holding each level for ``hold`` seconds."""
    if not levels:
        raise ConfigurationError('at least one set-point is needed')
    if not (math.isfinite(hold) and hold > 0.0):
        raise ConfigurationError(f'hold must be a positive number of seconds, got {hold!r}')
    per_level = max(1, int(round(hold / dt)))
    return np.repeat(np.asarray(levels, dtype=np.float64), per_level)


@dataclass(frozen=True)
class StepMetrics:
    """
    Response to one set-point step.

    Parameters
    ----------
    start : float
        Time of the step, s.
    size : float
        Step size, degrees.
    settling_time : float
        Time from the step until the error stays inside the band, s (``inf``: never).
    overshoot : float
        Largest excursion beyond the new set-point, percent of the step size.
    steady_error : float
        Mean error over the last second before the next step, degrees.

    """

    start: float
    size: float
    settling_time: float
    overshoot: float
    steady_error: float


def step_metrics(trace: LoopTrace, *, band: float = 0.5, initial: float | None = None,
                 tail: float = 1.0) -> list[StepMetrics]:
    """
    Settling time, overshoot and steady error of every set-point step in a trace.

    ``band``: settling band around the set-point, degrees.
    ``initial``: angle before the first set-point (default: the first angle), so that the first
    level counts as a step too.
    ``tail``: seconds at the end of each hold averaged for the steady error.
    Returns: one per step.
    """
    setpoint = trace.setpoint
    changes = np.flatnonzero(np.diff(setpoint)) + 1
    starts = np.r_[0, changes]
    ends = np.r_[changes, setpoint.size]
    previous = trace.y[0] if initial is None else initial
    dt = float(trace.t[1] - trace.t[0]) if trace.t.size > 1 else 1.0
    metrics = []
    for start, end in zip(starts.tolist(), ends.tolist()):
        target = float(setpoint[start])
        size = target - previous
        previous = target
        if size == 0.0:
            continue
        error = trace.y[start:end] - target
        outside = np.flatnonzero(np.abs(error) > band)
        if outside.size == 0:
            settling = 0.0
        elif outside[-1] == error.size - 1:
            settling = math.inf
        else:
            settling = (outside[-1] + 1) * dt
        beyond = np.max(np.sign(size) * error)
        overshoot = max(0.0, 100.0 * beyond / abs(size))
        last = max(1, int(round(tail / dt)))
        metrics.append(StepMetrics(float(trace.t[start]), size, settling, overshoot,
                                   float(np.mean(error[-last:]))))
    return metrics


def valve_reversals(v: FloatArray, rest: float = 0.0) -> int:
    """Count how often the valve command changes side of ``rest`` (docs/methods.md section 5.2)."""
    side = np.sign(np.asarray(v, dtype=np.float64) - rest)
    side = side[side != 0]
    return int(np.count_nonzero(np.diff(side)))
