"""``hydro-sdp diagnose``: name what a model misses, add it, show the gap shrink."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
import textwrap
from typing import TYPE_CHECKING

from hydro_sdp.cli.common import (
    add_bag_options, json_number, Outcome, Payload, read_records, table)
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.io.model_files import load_model, save_model

if TYPE_CHECKING:
    from hydro_sdp.core.diagnosis import Diagnosis

HELP = 'find where a model and the data disagree, name the missing effect, add it'
#: Width the evidence is wrapped to in the terminal table.
EVIDENCE_WIDTH = 60
#: Filled with the vocabulary when the parser is built (the detectors load scipy).
DESCRIPTION = """\
Hold a model against measured bags, name what it misses and add it.

The measured commands are replayed through the model; the velocity residual
(measured increments against the model's one-step predictions) localises the
disagreement, and the SDP analysis of what the model misses against the command,
the angle, the time since a command change, the travel since a reversal, the
other joints' speed and the load says which state explains it: the data name the
effect (see `hydro-sdp sdp`). Every effect of the vocabulary is added in turn and
fitted:

{words}

Each is judged on held-out data (--validation, else every third bag when there
are three or more): an effect is named when it lowers the simulation error over
2-second windows by at least 10 % and its reduction of the squared residual is
significant under a block bootstrap (p <= 0.01), which weighs a large effect
seen for a few seconds as much as a small one seen throughout; one that removes
half the residual is never dismissed. The first accepted is added (a stop the
joint is held at while driven beyond its dead-zone first, then the words of the
state the data name), and the search repeats until none is accepted: `none`.
The augmented model is a normal model file.

Two words need more than the joint's own command and angle. `flow_sharing`
uses the other joints of the same JointState (read whenever the bags have
them): the joint slowing while another moves is fitted as a shared pump-flow
limit. `load_dependence` uses a measured load when --load-topic names a Float64
topic (a load pressure, held between messages like the command): the speed
follows the load as the SDP analysis draws it, a smooth factor per direction of
either sign (a valve without compensation, a pump whose power binds), or an
overrunning load that speeds the joint up as the root of the load pressure,
whichever the data show. Without it, each record gets its own speed
scale per direction, named only when the records' scales at the same command
differ beyond their noise; those factors hold for the bags they were fitted on.
`flow_sharing` is not applicable without other joints, nor the measured-load
forms without --load-topic; `evaluate` reads the same signals.

example:
  hydro-sdp diagnose run1 run2 --model j2_model.yaml --validation run3 \\
      --out j2_augmented.yaml --report diagnosis
  hydro-sdp diagnose light heavy --model arm.yaml --load-topic /arm/pressure
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``diagnose`` command to the command line."""
    from hydro_sdp.core.diagnosis import DETECTORS

    width = max(len(d.word) for d in DETECTORS)
    words = '\n'.join(f'  {d.word:{width}}  {d.description}' for d in DETECTORS)
    parser = subparsers.add_parser('diagnose', help=HELP,
                                   description=DESCRIPTION.format(words=words),
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', metavar='BAG', help='measured bags (estimation)')
    parser.add_argument('--model', required=True, help='model file to hold against them')
    parser.add_argument('--validation', nargs='+', metavar='BAG', default=[],
                        help='held-out bags for the MAE before and after (default: the '
                             'estimation bags)')
    add_bag_options(parser)
    parser.add_argument('--load-topic', metavar='TOPIC',
                        help='Float64 topic of a measured load (e.g. a cylinder pressure) for '
                             'load_dependence; the augmented model remembers it (default: the '
                             "model file's load_topic, else per-record speed scales)")
    parser.add_argument('--iterations', type=int, default=4,
                        help='most effects added (default: 4)')
    parser.add_argument('--out', help='augmented model file to write')
    parser.add_argument('--report', help='folder for figures and summary.md')
    parser.set_defaults(run=run)


def describe(result: Diagnosis) -> Payload:
    """Return the ``--json`` object of a diagnosis."""
    return {
        'effect': result.effect,
        'candidates': [{'effect': c.effect, 'applicable': c.applicable, 'gain': c.gain,
                        't': json_number(c.t), 'p_value': c.p_value,
                        'significant': c.significant, 'held_out': c.held_out,
                        'accepted': c.accepted, 'state': c.state,
                        'named_by_data': c.named_by_data, 'parameters': c.parameters,
                        'windowed_before': c.window_before, 'windowed_after': c.window_after,
                        'own_before': json_number(c.own_before),
                        'own_after': json_number(c.own_after),
                        'carries_over': c.carries_over, 'refused': c.refused,
                        'evidence': c.evidence}
                       for c in result.candidates],
        'ledger': [{'effect': s.effect, 'parameters': s.parameters,
                    'mae_before': s.mae_before, 'mae_after': s.mae_after,
                    'windowed_before': s.window_before, 'windowed_after': s.window_after}
                   for s in result.ledger],
        'mae_before': result.mae_before,
        'mae_after': result.mae_after,
        'validation': result.validation,
        'states': dict(result.shares),
        'model': result.model.to_mapping(),
    }


def run(args: argparse.Namespace) -> Outcome:
    """Run ``diagnose``."""
    from hydro_sdp.core.diagnosis import diagnose, VOCABULARY
    from hydro_sdp.report.diagnosis import write_report

    model = load_model(args.model)
    # Without --command-topic the bags are read from the topic the model remembers.
    joint = args.joint or model.joint
    # With the other joints and the load: the signals flow_sharing and load_dependence need.
    load_topic = args.load_topic or model.load_topic
    records = read_records(args.bags, joint, args.command_topic,
                           preferred_topic=model.command_topic, load_topic=load_topic,
                           others=True)
    validation = read_records(
        args.validation, joint, args.command_topic, 'reading validation bags',
        preferred_topic=model.command_topic, load_topic=load_topic,
        others=True) if args.validation else []
    effects = list(VOCABULARY)
    with ProgressBar('diagnose', len(effects) * args.iterations) as bar:
        done = [0]

        def tick(name: str) -> None:
            done[0] += 1
            bar.update(done[0])
        result = diagnose(records, model, validation=validation or None,
                          max_iterations=args.iterations, progress=tick)
    if load_topic and result.model.effect('load_dependence') is not None:
        # The model remembers the load its effect was fitted on, as it does the command.
        result = replace(result, model=replace(result.model, load_topic=load_topic))
    payload = describe(result)
    if args.out:
        payload['model_file'] = str(save_model(result.model, args.out))
    if args.report:
        payload['report'] = write_report(Path(args.report), result)
    lines = [f'named effect: {result.effect}; validation MAE {result.mae_before:.4g} -> '
             f'{result.mae_after:.4g} deg']
    if result.ledger:
        lines += table([[str(i), s.effect, f'{s.mae_before:.4g}', f'{s.mae_after:.4g}',
                         ', '.join(f'{k}={_short(v)}' for k, v in s.parameters.items())]
                        for i, s in enumerate(result.ledger, start=1)],
                       ['step', 'effect', 'MAE before', 'MAE after', 'parameters'])
    lines.append(f'candidates (first round, judged on {result.validation}):')
    rows = []
    for c in result.candidates:
        if not c.applicable:
            continue
        # The evidence wrapped, not cut: its lines below the candidate's row.
        evidence = textwrap.wrap(c.evidence, EVIDENCE_WIDTH) or ['']
        rows.append([c.effect, 'yes' if c.accepted else 'no', f'{100 * c.held_out:.1f}',
                     f'{100 * c.gain:.1f}', f'{c.t:.3g}', evidence[0]])
        rows += [['', '', '', '', '', line] for line in evidence[1:]]
    lines += table(rows, ['effect', 'accepted', 'held-out %', 'residual %', 'z', 'evidence'])
    # A word the records hold no cause for, and why.
    lines += [f'refused: {c.effect}: {c.refused}' for c in result.candidates if c.refused]
    if args.out:
        lines.append(f'wrote {payload["model_file"]}')
    return Outcome(payload, lines)


def _short(value: object) -> str:
    if isinstance(value, float):
        return f'{value:.4g}'
    if isinstance(value, list):
        return '[' + ', '.join(_short(v) for v in value) + ']'
    return str(value)
