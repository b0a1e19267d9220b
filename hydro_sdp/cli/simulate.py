"""``hydro-sdp simulate``: open-loop experiments on a model, recorded as a bag."""

from __future__ import annotations

import argparse

from hydro_sdp.bags import STORAGES, write_bag
from hydro_sdp.cli.common import finite_float, non_negative_float, Outcome, positive_float
from hydro_sdp.core.model import JointModel
from hydro_sdp.core.programs import random_program, start_angle, step_program
from hydro_sdp.core.records import Record
from hydro_sdp.core.simulation import simulate
from hydro_sdp.files import load_model
import numpy as np

HELP = 'open-loop step or random-level experiments on a model, recorded as a bag'
DESCRIPTION = """\
Simulate open-loop experiments on a joint model and record them as a rosbag2 bag
with /joint_states (radians) and /<joint>/valve_command, ready for `identify`.

programs:
  steps    steps from rest of increasing size, alternating in sign, separated by
           rests (the step experiments of West et al. 2018, Fig. 1)
  random   random levels held for random times (their evaluation runs, Fig. 4)
Both take the command range from the model and keep the joint off its end stops.

example:
  hydro-sdp simulate config/brokk_j2.yaml --program steps --out steps_bag --seed 1
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``simulate`` command to the command line."""
    parser = subparsers.add_parser('simulate', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('model', help='model file (YAML, hydro_sdp/model/v1)')
    parser.add_argument('--program', choices=('steps', 'random'), required=True,
                        help='input program')
    parser.add_argument('--out', required=True, help='bag folder to write (replaced if present)')
    parser.add_argument('--seed', type=int, default=0, help='random seed (default: 0)')
    parser.add_argument('--duration', type=positive_float,
                        help='length in s (default: 40 steps of about 3 s; 60 s for random)')
    parser.add_argument('--sample-period', type=positive_float, default=0.01,
                        help='sample period in s (default: 0.01)')
    parser.add_argument('--noise', type=non_negative_float, default=0.03,
                        help='std of the angle measurement noise, deg (default: 0.03)')
    parser.add_argument('--y0', type=finite_float,
                        help='starting angle, deg (default: middle of the end stops)')
    parser.add_argument('--storage', choices=STORAGES, default='sqlite3',
                        help='rosbag2 storage (default: sqlite3)')
    parser.set_defaults(run=run)


def experiment_record(model: JointModel, program: str, *, dt: float = 0.01, seed: int = 0,
                      duration: float | None = None, noise: float = 0.03,
                      y0: float | None = None) -> Record:
    """
    Simulate one open-loop program on ``model`` with measurement noise.

    Parameters
    ----------
    model : JointModel
        The joint.
    program : str
        ``steps`` or ``random``.
    dt : float
        Sample period, s.
    seed : int
        Seed for the program and the noise.
    duration : float or None
        Length in s; default 40 steps, or 60 s of random levels.
    noise : float
        Standard deviation of the measurement noise, degrees.
    y0 : float or None
        Starting angle; default: the middle of the end stops.

    Returns
    -------
    Record
        The noisy record, ``t`` starting at ``dt``.

    """
    start = start_angle(model) if y0 is None else y0
    if program == 'steps':
        steps = 40 if duration is None else max(2, int(duration // 3.0))
        v = step_program(model, dt, steps=steps, y0=start)
    else:
        v = random_program(model, dt, 60.0 if duration is None else duration, seed=seed,
                           y0=start)
    y = simulate(model, v, dt, start)
    rng = np.random.default_rng([seed, 1])
    measured = y + rng.normal(0.0, noise, y.size) if noise > 0.0 else y
    # Time starts one period in, so that v_0 has a (non-negative) time to be sent at.
    return Record(np.arange(1, v.size + 1) * dt, v, measured, joint=model.joint)


def run(args: argparse.Namespace) -> Outcome:
    """Run ``simulate``."""
    model = load_model(args.model)
    record = experiment_record(model, args.program, dt=args.sample_period, seed=args.seed,
                               duration=args.duration, noise=args.noise, y0=args.y0)
    bag = write_bag(args.out, [record], storage=args.storage)
    payload = {'bag': str(bag), 'samples': len(record), 'joint': model.joint,
               'program': args.program, 'seed': args.seed, 'duration': record.duration,
               'sample_period': args.sample_period}
    lines = [f'wrote {bag} ({args.storage}): {len(record)} samples of joint {model.joint}, '
             f'{record.duration:.1f} s of the {args.program} program']
    return Outcome(payload, lines)
