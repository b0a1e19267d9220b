"""``hydro-sdp simulate``: open-loop experiments on a model, recorded as a bag."""

from __future__ import annotations

import argparse

from hydro_sdp.bags import STORAGES, write_bag
from hydro_sdp.cli.common import (
    finite_float, non_negative_float, Outcome, period_seconds, positive_float)
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.model_files import load_model

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
    parser.add_argument('--sample-period', type=period_seconds, default=SamplePeriod(0.01),
                        help='sample period in s (default: 0.01)')
    parser.add_argument('--noise', type=non_negative_float, default=0.03,
                        help='std of the angle measurement noise, deg (default: 0.03)')
    parser.add_argument('--y0', type=finite_float,
                        help='starting angle, deg (default: middle of the end stops)')
    parser.add_argument('--storage', choices=STORAGES, default='sqlite3',
                        help='rosbag2 storage (default: sqlite3)')
    parser.set_defaults(run=run)


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
