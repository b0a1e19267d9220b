"""
Cases the diagnosis once got wrong, on data shaped like the machines' (docs/methods.md 8.7).

* :func:`rare_stop`: a model identified from steps that never reached a stop, held
  against a one-minute run of random levels in which the joint meets its stop for about
  two seconds (the independent generator).
* :func:`dead_zone_linear`: a linear model of a joint with a wide dead-zone and a speed
  that levels off (a ``tanh`` rise, none of the model's families), random levels up to
  3 V (the independent generator).
* :func:`resisting_load`: the boom on a pump whose power binds, its valve without
  pressure compensation (``config/physics_boom_power.yaml``), identified lifting nothing,
  held against runs lifting nothing and 600 kg with the piston-side pressure logged as
  the load (the physics plant).

Each returns the model and the estimation and validation records.

"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.static_maps import LinearMap
from hydro_sdp.core.synthetic.physics.plant import Machine as Plant, with_payload
from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs, random_levels
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
from support.joint_generator import Joint, Machine, record, SpeedMap

DT = 0.01


class Case(NamedTuple):
    """A model, the records it is diagnosed on and those it is judged on."""

    model: JointModel
    estimation: list[Record]
    validation: list[Record]


#: The joint of :func:`rare_stop`: stops at -40 and 55 deg.
STOPPED = Joint(SpeedMap('exp', (-0.8, 0.9), (35.0, 45.0), (0.45, 0.55)), delay=0.12,
                stops=(-40.0, 55.0), noise=0.02)


def _random_level(joint: Joint, rng: np.random.Generator, y: float,
                  magnitudes: tuple[float, float], margin: float) -> tuple[float, int, float]:
    """
    Draw a level, more likely towards the farther stop, held 0.5-2.5 s.

    The hold is cut short where the joint would come within ``margin`` deg of a
    stop. Return the level, the samples it is held and the angle after them.
    """
    assert joint.stops is not None
    low, high = joint.stops
    up = rng.random() > (y - low) / (high - low)
    level = (1.0 if up else -1.0) * float(rng.uniform(*magnitudes))
    speed = joint.speed_map.speed(level)
    room = (high - margin - y) if speed > 0 else (y - low - margin)
    hold = min(float(rng.uniform(0.5, 2.5)), max(room, 0.0) / max(abs(speed), 1e-6))
    m = max(1, int(round(hold / DT)))
    return level, m, y + speed * m * DT


def _rare_program(joint: Joint, seed: int, seconds: float) -> FloatArray:
    """Random levels that turn back 12 deg before the stops, and once drive into the top one."""
    rng = np.random.default_rng(seed)
    n = int(round(seconds / DT))
    v = np.zeros(n)
    k, y = 100, 0.0
    hit = float(rng.uniform(0.35, 0.6)) * seconds
    done = False
    assert joint.stops is not None
    high = joint.stops[1]
    while k < n:
        if not done and k * DT > hit:
            # Into the top stop, and held against it about two seconds.
            speed = joint.speed_map.speed(6.0)
            hold = int(round(((high - y) / speed + 2.0) / DT))
            v[k:k + hold] = 6.0
            k, y, done = k + hold, high, True
            continue
        level, m, y = _random_level(joint, rng, y, (1.5, 7.0), margin=12.0)
        v[k:k + m] = level
        k += m
    return v


def rare_stop(seconds: float = 60.0) -> Case:
    """Return the model identified from steps; a run that meets the stop once, and another."""
    machine = Machine((STOPPED,))
    # Each step up is followed by one down that takes the joint back: they never drift
    # to the stops (-40, 55).
    parts = [np.zeros(100)]
    for size in [1.0, 1.3, 1.6, 2.0, 2.5, 3.0, 4.0, 5.0, 6.5, 8.0]:
        up, down = STOPPED.speed_map.speed(size), -STOPPED.speed_map.speed(-size)
        hold = int(round(40.0 / up / DT)) if up * 1.5 > 40.0 else 150
        parts += [np.full(hold, size), np.zeros(60),
                  np.full(int(round(hold * up / down)), -size), np.zeros(60)]
    steps = record(machine, np.concatenate(parts)[:, None], angles0=[0.0], seed=1,
                   source='steps')
    model = identify([steps], kind='sdp').model
    runs = [record(machine, _rare_program(STOPPED, seed, seconds)[:, None], angles0=[0.0],
                   seed=seed, source=f'levels {seed}') for seed in (11, 12)]
    return Case(model, runs[:1], runs[1:])


#: The joint of :func:`dead_zone_linear`: nothing moves within [-1.1, 1.0] V, the speed
#: rises at 30 and 36 deg/s per V beyond and levels off at 35 and 40 deg/s.
WIDE = Joint(SpeedMap('tanh', (-1.1, 1.0), (35.0, 40.0), (30.0, 36.0)), delay=0.1,
             stops=(-60.0, 70.0), noise=0.02)


def _levels(joint: Joint, seed: int, seconds: float, largest: float) -> FloatArray:
    """Random levels up to ``largest`` held 0.5-2.5 s, turning back 10 deg before the stops."""
    rng = np.random.default_rng([seed, 7])
    n = int(round(seconds / DT))
    v = np.zeros(n)
    k, y = 0, 0.0
    while k < n:
        level, m, y = _random_level(joint, rng, y, (0.2, largest), margin=10.0)
        v[k:k + m] = level
        k += m
    return v


def dead_zone_linear(seconds: float = 60.0) -> Case:
    """Return a linear model (least-squares gain of speed on command), random levels to 3 V."""
    machine = Machine((WIDE,))
    runs = [record(machine, _levels(WIDE, seed, seconds, 3.0)[:, None], angles0=[0.0],
                   seed=seed, source=f'levels {seed}') for seed in (1, 2, 3)]
    estimation = runs[:2]
    increments = np.concatenate([np.diff(r.y) / DT for r in estimation])
    commands = np.concatenate([r.v[1:] for r in estimation])
    gain = float(np.dot(commands, increments) / np.dot(commands, commands))
    model = JointModel('joint', LinearMap(gain), delay=0.1, angle_limits=WIDE.stops,
                       input_limits=(-10.0, 10.0))
    return Case(model, estimation, runs[2:])


def resisting_load(seconds: float = 30.0) -> Case:
    """Return the boom identified lifting nothing; runs with 0 and 600 kg, pressure logged."""
    boom = load_machine(shipped_config('physics_boom_power.yaml'))
    light, heavy = with_payload(boom, 0.0), with_payload(boom, 600.0)
    model = identify(full_stroke_runs(light, DT, (45, 70, 100), seed=1, longest=30.0),
                     kind='sdp').model

    def runs(machine: Plant, seed: int, tag: str) -> Record:
        levels = random_levels(machine, DT, seconds, seed=seed, pressure=True)
        return replace(levels, source=f'{tag} {seed}')
    return Case(model, [runs(light, 11, 'light'), runs(heavy, 12, '600 kg')],
                [runs(light, 13, 'light'), runs(heavy, 14, '600 kg')])
