"""
Joints whose valves rise convexly from a wide dead-zone and saturate, and their logs.

Two kinds of truth, neither an SDP model: the measured-table joint of
:mod:`support.table_valve_joint` (signed percent, or percent resting at 50) and
the physics plant's arm presets (``config/physics_arm.yaml``, signed percent;
``config/physics_arm_pwm.yaml``, a PWM resting at 50 with a 0.28 s dead time
and a 0.15 s spool lag), and the boom presets (``config/physics_boom.yaml`` and
the same boom ringing on its oil column, ``config/physics_boom_compressible.yaml``,
signed percent). Each is logged as a machine's user would: one
constant duty driven from stop to stop and back, identified on 40, 60, 80 and
100 % and validated on 50, 70 and 90 %.

Run as a script, it calibrates each joint with whichever ``hydro_sdp`` is
importable and prints, per joint, the closed-loop check of the first and of
the written design and the written controller file run on the true joint in
:mod:`support.independent_loop`: settling into +-0.5 deg, overshoot, the
holds that end in a limit cycle and the valve's pulses across the true
dead-zone per second of hold::

    .venv/bin/python test/support/real_valve_joints.py [joint ...]

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path
import sys
import tempfile
from typing import Callable

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from support.independent_loop import FileController, judge, run_loop, StepResult  # noqa: E402
from support.table_valve_joint import (  # noqa: E402
    stroke_run, TableJoint, TableJointSimulator, write_log)

DT = 0.01
ESTIMATION = (40, 60, 80, 100)
VALIDATION = (50, 70, 90)
#: Set-points of the loop on the true joint, degrees: steps of 20-25 deg in the stroke.
LEVELS = (-20.0, 5.0, 25.0, 0.0, -25.0, -5.0, 15.0)
#: Steps of 15-25 deg in the boom's stroke (-20 to 35 deg).
BOOM_LEVELS = (-10.0, 10.0, 30.0, 5.0, -15.0, 0.0, 20.0)
HOLD = 12.0
#: Settling bound of the loop on the true joint, s.
SETTLE = 8.0


class PhysicsJoint:
    """The physics plant's first joint as a plant of :func:`support.independent_loop.run_loop`."""

    def __init__(self, machine, y0: float, seed: int = 5) -> None:
        from hydro_sdp.core.synthetic.physics import PlantSimulator
        self.sim = PlantSimulator(machine, DT, angles0=[y0],
                                  command_before=[machine.joints[0].valve.neutral], seed=seed)
        self.angle = self.sim.angles[0]

    def step(self, command: float) -> None:
        self.angle = self.sim.step([command])[0]


@dataclass
class Case:
    """One joint: how to log it (CSV files or bags) and how to run the truth."""

    name: str
    input_limits: tuple[float, float]
    write: Callable[[Path], tuple[list[str], list[str], list[str]]]
    plant: Callable[[float], object]
    #: The true valve's dead-zone edges, valve units.
    edges: tuple[float, float]
    #: Set-points of the loop on the true joint, degrees.
    levels: tuple[float, ...] = LEVELS


def _table_case(name: str, joint: TableJoint) -> Case:
    def write(folder: Path) -> tuple[list[str], list[str], list[str]]:
        paths = {}
        for seed, duty in enumerate(sorted(ESTIMATION + VALIDATION)):
            commands, angles = stroke_run(joint, duty, DT, seed=seed)
            paths[duty] = str(write_log(folder / f'duty_{duty}.csv', commands, angles, DT))
        options = ['--joint', 'arm', '--time', 't', '--angle', 'arm_deg', '--command', 'duty']
        return [paths[d] for d in ESTIMATION], [paths[d] for d in VALIDATION], options
    edges = sorted(float(x) for x in joint.command(list(joint.closed)))
    return Case(name, joint.command_limits, write,
                lambda y0: TableJointSimulator(joint, DT, y0, seed=5), (edges[0], edges[1]))


def _physics_case(name: str, preset: str, levels: tuple[float, ...] = LEVELS) -> Case:
    from hydro_sdp.io.documents import shipped_config
    from hydro_sdp.io.plant_files import load_machine
    machine = load_machine(shipped_config(preset))

    def write(folder: Path) -> tuple[list[str], list[str], list[str]]:
        from hydro_sdp.bags import write_bag
        from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs
        paths: dict[int, list[str]] = {}
        for duty in ESTIMATION + VALIDATION:
            runs = full_stroke_runs(machine, DT, (duty,), seed=duty)
            paths[duty] = [str(write_bag(folder / f'duty_{duty}_{i}', [run]))
                           for i, run in enumerate(runs)]
        return ([p for d in ESTIMATION for p in paths[d]],
                [p for d in VALIDATION for p in paths[d]], [])
    valve = machine.joints[0].valve
    # The spool's overlap, as commands (the spool travel is linear on each side of neutral).
    edges = (valve.neutral - valve.overlap * (valve.neutral - valve.limits[0]),
             valve.neutral + valve.overlap * (valve.limits[1] - valve.neutral))
    return Case(name, (float(valve.limits[0]), float(valve.limits[1])), write,
                lambda y0: PhysicsJoint(machine, y0), edges, levels)


def cases() -> dict[str, Case]:
    """Return the joints by short name."""
    return {
        'table_signed': _table_case('measured table, signed %', TableJoint()),
        'table_rest50': _table_case('measured table, % resting at 50',
                                    TableJoint(rest=50.0, units_per_percent=0.5)),
        'physics_arm': _physics_case('physics arm, signed %', 'physics_arm.yaml'),
        'physics_pwm': _physics_case('physics arm, PWM resting at 50, 0.28 s + 0.15 s',
                                     'physics_arm_pwm.yaml'),
        'physics_boom': _physics_case('physics boom, signed %', 'physics_boom.yaml',
                                      BOOM_LEVELS),
        # The boom ringing on its oil column at about 2 Hz, as the LUCIE boom did.
        'physics_boom_ringing': _physics_case(
            'physics boom on its oil column, signed %', 'physics_boom_compressible.yaml',
            BOOM_LEVELS),
    }


def truth_loop(case: Case, controller_file: str | Path) -> list[StepResult]:
    """Run a controller file on the true joint over the case's levels; judge every step."""
    controller = FileController.read(controller_file)
    run = run_loop(controller, case.plant(case.levels[0]), DT, case.levels, HOLD)
    return judge(run, rest=controller.rest, edges=case.edges)


def pulse_rate(results: list[StepResult]) -> float:
    """Return the valve's openings across the true dead-zone per second of hold, pooled."""
    held = sum(r.held for r in results)
    return sum(r.pulses for r in results) / held if held > 0.0 else 0.0


def cycles(results: list[StepResult], band: float = 0.5) -> int:
    """Count the holds whose end hunts (4 or more reversals) or wanders more than the band."""
    return sum(1 for r in results if r.reversals >= 4 or r.wander > band)


def settles(results: list[StepResult]) -> bool:
    """Whether every step settles within :data:`SETTLE`, overshoots at most 10 % and holds."""
    return all(r.settling <= SETTLE and r.overshoot <= 10.0 for r in results) and \
        not cycles(results)


def _row(settling: list[float], overshoot: list[float], limit_cycles: int,
         pulses: float) -> str:
    def seconds(x: float) -> str:
        return 'never' if not math.isfinite(x) else f'{x:.2f}'
    low, high = seconds(min(settling)), seconds(max(settling))
    span = low if low == high else f'{low}-{high}'
    return (f'{span}{"" if span == "never" else " s"} | '
            f'{min(overshoot):.1f}-{max(overshoot):.1f} % | {limit_cycles} | {pulses:.2f}')


def main(names: list[str]) -> None:
    """Calibrate each joint and print the table of the module docstring."""
    from contextlib import redirect_stdout
    import io
    import json

    from hydro_sdp.cli.main import main as cli
    print('| joint | what | settling | overshoot | limit cycles | pulses/s at hold |')
    print('|---|---|---|---|---|---|')
    for key in names or list(cases()):
        case = cases()[key]
        with tempfile.TemporaryDirectory() as folder:
            estimation, validation, options = case.write(Path(folder))
            out = Path(folder) / 'out'
            text = io.StringIO()
            with redirect_stdout(text):
                cli(['calibrate', *estimation, '--validation', *validation, *options,
                     '--input-limits', *[str(x) for x in case.input_limits],
                     '--out', str(out), '--json'])
            payload = json.loads(text.getvalue())
            loop = payload['closed_loop']
            forms = ', '.join(loop.get('idz_forms', ['chord'] * len(loop['designs'])))
            settling = [math.inf if x is None else x for x in loop['settling_time']]
            print(f'| {case.name} | calibrate\'s check: {"passed" if loop["passed"] else "FAILED"}'
                  f' after {len(loop["designs"])} design(s) ({forms}) | '
                  + _row(settling, loop['overshoot'], loop['limit_cycles'],
                         loop['chatter']['pulse_rate']) + ' |')
            results = truth_loop(case, out / 'controller.yaml')
            verdict = 'settles' if settles(results) else 'fails'
            print(f'| | its controller file on the true joint ({verdict}) | '
                  + _row([r.settling for r in results], [r.overshoot for r in results],
                         cycles(results), pulse_rate(results)) + ' |')


if __name__ == '__main__':
    main(sys.argv[1:])
