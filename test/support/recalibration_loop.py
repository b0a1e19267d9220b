"""
The measured-table arm whose dead-zone narrows while its loop runs, recalibrated online.

The true joint is :class:`support.table_valve_joint.TableJoint` (a measured table,
0.28 s dead time, 0.15 s spool lag before the table); at ``wear_at`` each side
of its table moves ``narrowing`` percent of duty toward rest. The controller is a
controller file run by :class:`support.independent_loop.FileController`, which
takes new IDZ edges and slopes as the controller node does. What is under test
comes from the package: the online identifier of the model
(:func:`hydro_sdp.core.identification.online_edges.online_identifier`) fed with
the command in force and the angle read at every sample, and the recalibration
decision, asked every ``publish`` seconds as the identifier node asks it.
:func:`arm_model` is the arm as a user's identification would give it in the
``power_sat`` family: fitted here to the table's speeds, with the joint's dead time
and lag.

"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Sequence

from hydro_sdp.core.control.idz_recalibration import (
    recalibrated_idz, Recalibration, RecalibrationPolicy)
from hydro_sdp.core.identification.online import OnlineSettings
from hydro_sdp.core.identification.online_edges import online_identifier
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PowerSatMap
import numpy as np
from scipy.optimize import least_squares
from support.independent_loop import FileController, openings
from support.table_valve_joint import TableJoint, TableJointSimulator

DT = 0.01
#: Set-points of the run, degrees, each held :data:`HOLD` s.
LEVELS = (-20.0, 5.0, 25.0, 0.0, -25.0, -5.0, 15.0, -10.0, 20.0, -15.0)
HOLD = 8.0


def narrowed(joint: TableJoint, by: float) -> TableJoint:
    """Return the joint with each side of its table moved ``by`` percent of duty toward rest."""
    return replace(joint, duty=tuple(d + by if d < 0.0 else d - by for d in joint.duty))


def arm_model(joint: TableJoint) -> JointModel:
    """Return the arm's ``power_sat`` model: each side fitted to the table, dead time and lag."""
    sides = []
    for sign, edge in ((-1.0, joint.closed[0]), (1.0, joint.closed[1])):
        duty = edge + sign * np.linspace(0.0, 100.0 - abs(edge), 200)
        speed = joint.speed_at(duty)

        def residual(p, x=np.abs(duty - edge), s=speed):
            return p[0] * -np.expm1(-(p[1] * x) ** p[2]) - s
        fit = least_squares(residual, [sign * 25.0, 0.03, 2.0],
                            bounds=([-60.0 if sign < 0 else 1.0, 1e-3, 1.0],
                                    [-1.0 if sign < 0 else 60.0, 1.0, 5.0]))
        sides.append(fit.x)
    low, high = (float(x) for x in joint.command(np.array(joint.closed)))
    scale = joint.units_per_percent
    static = PowerSatMap(dead_zone=(low, high),
                         saturation_velocity=(float(sides[0][0]), float(sides[1][0])),
                         curvature=(float(sides[0][1]) / scale, float(sides[1][1]) / scale),
                         exponent=(float(sides[0][2]), float(sides[1][2])))
    return JointModel('arm', static, joint.dead_time, angle_limits=joint.stroke,
                      input_limits=joint.command_limits, effects=(ValveLag(joint.lag),))


@dataclass
class WearRun:
    """What happened: the recalibrations, the estimate and each hold on the true joint."""

    #: ``(time, edges, slopes)`` of every recalibration the controller took.
    recalibrations: list[tuple[float, tuple[float, float], tuple[float, float]]]
    #: Final edge estimate, input units.
    edges: tuple[float, float]
    #: Per level after the first: start (s), settling (s), pulses at hold, time held (s).
    holds: list[tuple[float, float, int, float]]
    #: The true edges after the wear, input units.
    worn_edges: tuple[float, float]


def run_wear(model: JointModel, controller_file: str | Path, joint: TableJoint, *,
             narrowing: float, wear_at: float, recalibrate: bool = True,
             levels: Sequence[float] = LEVELS, hold: float = HOLD, publish: float = 0.1,
             seed: int = 5) -> WearRun:
    """Run the loop on the joint, narrowed at ``wear_at``, with the online recalibration."""
    worn = narrowed(joint, narrowing)
    controller = FileController.read(controller_file)
    settings = OnlineSettings.for_input_limits(model.input_limits, noise_std=joint.noise)
    identifier = online_identifier(model, DT, settings)
    decision = Recalibration(identifier.named_estimate().edges,
                             RecalibrationPolicy(min_change=0.03 * settings.input_scale))
    setpoint = np.repeat(np.asarray(levels, dtype=float), int(round(hold / DT)))
    plant = TableJointSimulator(joint, DT, levels[0], seed=seed)
    every = int(round(controller.period / DT))
    publish_every = int(round(publish / DT))
    y, v = np.empty(setpoint.size), np.empty(setpoint.size)
    command = in_force = controller.rest
    taken = []
    for j in range(setpoint.size):
        t = j * DT
        if j == int(round(wear_at / DT)):
            plant.joint = worn
        reading = plant.angle
        y[j] = plant.true_angle
        identifier.update(in_force, reading)
        if recalibrate and j % publish_every == 0:
            answer = decision.observe(t, identifier.named_estimate())
            if answer.due:
                idz = recalibrated_idz(identifier.estimate(), answer.edges, controller.period,
                                       form='table')
                controller.recalibrate(idz.dead_zone, idz.slopes)
                decision.attempted(t)
                decision.accepted(idz.dead_zone)
                taken.append((t, idz.dead_zone, idz.slopes))
        if j % every == 0:
            command = controller.step(float(setpoint[j]), reading)
        v[j] = in_force = command
        plant.step(command)
    worn_edges = tuple(sorted(float(x) for x in worn.command(np.array(worn.closed))))
    true_edges = tuple(sorted(float(x) for x in joint.command(np.array(joint.closed))))
    per_level = int(round(hold / DT))
    holds = []
    for i in range(1, len(levels)):
        begin, end = i * per_level, (i + 1) * per_level
        outside = np.flatnonzero(np.abs(y[begin:end] - setpoint[begin:end]) > 0.5)
        settled = begin + (int(outside[-1]) + 1 if outside.size else 0)
        edges = worn_edges if begin * DT >= wear_at else true_edges
        pulses = openings(v[settled:end], edges, controller.rest) if end - settled > 1 else 0
        holds.append((begin * DT, (settled - begin) * DT, pulses, (end - settled) * DT))
    estimate = identifier.named_estimate().edges
    return WearRun(taken, estimate, holds, (worn_edges[0], worn_edges[1]))
