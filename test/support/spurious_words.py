"""
The words calibrate names on joints that have none beyond their map, delay and lag.

The measured-table arm of :mod:`support.table_valve_joint` (convex curve, 36 % dead-zone,
0.28 s dead time, 0.15 s spool lag) and the physics plant's arm without linkage effects
(``config/physics_arm.yaml``), each logged one duty per run from stop to stop and back,
identified on 40/60/80/100 % and validated on 50/70/90 %, with the noise drawn from
several seeds. Neither joint has a stroke geometry, a load, another joint on its supply
nor play: any word calibrate adds beyond ``valve_lag``, ``time_delay`` and ``angle_limits``
is one the joint lacks. Prints one row per joint and seed::

    .venv/bin/python test/support/spurious_words.py [seeds] [joint ...]

"""

from __future__ import annotations

from pathlib import Path
import sys

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from support.real_valve_joints import DT, ESTIMATION, VALIDATION  # noqa: E402
from support.table_valve_joint import stroke_run, TableJoint  # noqa: E402

#: Words a joint with a dead-zone, a delay, a spool lag and end stops may be given.
OWN = frozenset({'valve_lag', 'time_delay', 'direction_dependent_delay', 'angle_limits'})


def table_records(seed: int):
    """Return the table arm's estimation and validation records for ``seed``."""
    from hydro_sdp.core.model.records import Record
    joint = TableJoint()

    def one(duty: int):
        commands, angles = stroke_run(joint, duty, DT, seed=1000 * seed + duty)
        t = DT * __import__('numpy').arange(commands.size)
        return Record(t=t, v=commands, y=angles, joint='arm', source=f'duty_{duty}')
    return [one(d) for d in ESTIMATION], [one(d) for d in VALIDATION], joint.command_limits


def without_linkage(machine):
    """
    Return the machine's first joint with a flat linkage, no cushions and no payload.

    The rod-end pivot 1.5 m from the joint and the base pivot 3 m away, the cylinder
    perpendicular to the link at mid-stroke: the link swings +-7 deg and the moment arm
    varies by about 1 %.
    """
    from dataclasses import replace
    import math
    joint = machine.joints[0]
    base, rod = 3000.0, 1500.0
    middle = math.sqrt(base * base - rod * rod)
    joint = replace(joint, linkage=replace(joint.linkage, base_distance=base, rod_distance=rod,
                                           angle_offset=math.degrees(math.acos(rod / base))),
                    cylinder=replace(joint.cylinder, cushion_length=0.0,
                                     min_length=middle - joint.cylinder.stroke / 2.0),
                    load=replace(joint.load, payload=0.0))
    return replace(machine, joints=(joint,) + tuple(machine.joints[1:]))


def physics_records(seed: int, preset: str = 'physics_arm.yaml', estimation=ESTIMATION,
                    validation=VALIDATION, linkage: bool = False):
    """Return the physics arm's estimation and validation records for ``seed``."""
    from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs
    from hydro_sdp.io.documents import shipped_config
    from hydro_sdp.io.plant_files import load_machine
    machine = load_machine(shipped_config(preset))
    machine = machine if linkage else without_linkage(machine)

    def runs(duties):
        return [run for d in duties
                for run in full_stroke_runs(machine, DT, (d,), seed=1000 * seed + d)]
    valve = machine.joints[0].valve
    limits = (float(valve.limits[0]), float(valve.limits[1]))
    return runs(estimation), runs(validation), limits


JOINTS = {'table': table_records, 'physics': physics_records}


def words(joint: str, seed: int) -> tuple[tuple[str, ...], str]:
    """Return the words calibrate names for ``joint`` at ``seed`` and its ledger."""
    from hydro_sdp.core.calibration import calibrate, CalibrationSettings
    estimation, validation, limits = JOINTS[joint](seed)
    result = calibrate(estimation, validation, CalibrationSettings(input_limits=limits))
    ledger = '; '.join(f'{s.effect} {s.mae_before:.3g}->{s.mae_after:.3g}'
                       for s in result.diagnosis.ledger)
    return result.effects, ledger


def main(seeds: int, joints: list[str]) -> None:
    """Print the words per joint and seed and the count of words the joint lacks."""
    for joint in joints:
        lacking = 0
        for seed in range(seeds):
            found, ledger = words(joint, seed)
            extra = [w for w in found if w not in OWN]
            lacking += bool(extra)
            print(f'{joint} seed {seed}: {", ".join(found) or "none"} | lacks: '
                  f'{", ".join(extra) or "-"} | {ledger}', flush=True)
        print(f'{joint}: {lacking} of {seeds} seeds name a word the joint lacks', flush=True)


if __name__ == '__main__':
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5, sys.argv[2:] or list(JOINTS))
