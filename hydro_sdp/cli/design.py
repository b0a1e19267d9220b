"""``hydro-sdp design``: a PIP-IDZ controller for a joint model."""

from __future__ import annotations

import argparse

from hydro_sdp.cli.common import finite_float, non_negative_float, Outcome, positive_float, table
from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model, format_pole
from hydro_sdp.core.control.idz import IDZ_MODES
from hydro_sdp.core.control.pip_design import LqWeights
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.io.controller_files import save_controller
from hydro_sdp.io.model_files import load_model

HELP = 'design a PIP controller with inverse dead-zone for a joint model'
DESCRIPTION = """\
Design a Proportional-Integral-Plus (PIP) controller with an inverse dead-zone
(IDZ) for a joint model, as in West et al. (2018) section 5.

The IDZ inverts the chord of the model's velocity map between each dead-zone edge
and the command where the speed reaches two thirds of saturation (--v-range to
choose), so the controller sees y_k = y_{k-1} + u_{k-tau} with tau the delay in
control samples. The gains come from LQ design (default weights: the paper's
design, dominant poles 0.94 +- 0.05i) or from pole assignment (--poles: n + m
poles, complex ones in conjugate pairs, zeros allowed and repeated).

examples:
  hydro-sdp design config/brokk_j2.yaml --out j2_controller.yaml
  hydro-sdp design config/brokk_j2.yaml --poles 0.94+0.05j 0.94-0.05j 0 0 \\
      --v-range -2.2 1.75 --u-limits -2.5 2.5 --out j2_paper.yaml
"""


def complex_pole(text: str) -> complex:
    """Argparse type: a pole as a Python complex literal (``0.94+0.05j``)."""
    try:
        return complex(text.replace(' ', ''))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f'expected a complex number such as 0.94+0.05j, got {text!r}') from None


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``design`` command to the command line."""
    parser = subparsers.add_parser('design', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('model', help='model file (YAML, hydro_sdp/model/v1)')
    parser.add_argument('--poles', nargs='+', type=complex_pole, metavar='P',
                        help='closed-loop poles for pole assignment (default: LQ design)')
    parser.add_argument('--weights', nargs=3, type=non_negative_float,
                        metavar=('W_Y', 'W_U', 'W_E'),
                        help='LQ weights on output, input and integral of error '
                             '(default: 1.6567e-3 1 4.1993e-5)')
    parser.add_argument('--control-period', type=positive_float, default=0.05,
                        help='control period in s (default: 0.05)')
    parser.add_argument('--u-limits', nargs=2, type=finite_float, metavar=('LOW', 'HIGH'),
                        help='limits of u, deg per control sample (default: 1.25 x the '
                             'saturation speeds, or the chord at the input limits)')
    parser.add_argument('--v-range', nargs=2, type=finite_float, metavar=('V_MIN', 'V_MAX'),
                        help='commands where the IDZ chords meet an sdp map')
    parser.add_argument('--beta', type=non_negative_float,
                        help='IDZ chatter band, deg per control sample (default: 0.05)')
    parser.add_argument('--idz-mode', choices=IDZ_MODES, default='zero',
                        help='IDZ near u = 0: zero band (paper), smooth blend or hysteresis')
    parser.add_argument('--out', help='controller file to write (YAML)')
    parser.add_argument('--plot', help="PNG of the IDZ approximation (the paper's Fig. 6)")
    parser.set_defaults(run=run)


def describe(spec: ControllerSpec) -> dict:
    """Return the ``--json`` keys of a controller."""
    idz = spec.idz
    return {
        'joint': spec.joint,
        'f': list(spec.gains.f),
        'g': list(spec.gains.g),
        'kI': spec.gains.k_i,
        'poles': [format_pole(p) for p in spec.poles],
        'control_period': spec.control_period,
        'delay_samples': spec.delay_samples,
        'slopes': None if idz is None else list(idz.slopes),
        'dead_zone': None if idz is None else list(idz.dead_zone),
        'beta': None if idz is None else idz.beta,
        'idz_mode': None if idz is None else idz.mode,
        'u_limits': None if spec.u_limits is None else list(spec.u_limits),
        'v_limits': None if spec.v_limits is None else list(spec.v_limits),
        'design': dict(spec.design),
    }


def run(args: argparse.Namespace) -> Outcome:
    """Run ``design``."""
    model = load_model(args.model)
    weights = LqWeights(*args.weights) if args.weights else None
    spec = design_from_model(
        model, control_period=args.control_period, poles=args.poles, weights=weights,
        u_limits=tuple(args.u_limits) if args.u_limits else None, beta=args.beta,
        mode=args.idz_mode, v_range=tuple(args.v_range) if args.v_range else None)
    payload = describe(spec)
    if args.out:
        payload['controller'] = str(save_controller(spec, args.out))
    if args.plot:
        if spec.idz is None:
            raise ConfigurationError('--plot draws the inverse dead-zone, and this model has none')
        from hydro_sdp.plots import plot_idz, save_figure

        payload['plot'] = str(save_figure(plot_idz(model, spec.idz, spec.control_period,
                                                   u_limits=spec.u_limits),
                                          args.plot))
    rows = [['f', ', '.join(f'{x:.4f}' for x in spec.gains.f)],
            ['g', ', '.join(f'{x:.4f}' for x in spec.gains.g) or '-'],
            ['kI', f'{spec.gains.k_i:.4f}'],
            ['poles', ', '.join(payload['poles'])],
            ['delay', f'{spec.delay_samples} samples of {spec.control_period:g} s']]
    if spec.idz is not None:
        rows += [['IDZ edges', ', '.join(f'{x:.4f}' for x in spec.idz.dead_zone)],
                 ['IDZ slopes', ', '.join(f'{x:.4f}' for x in spec.idz.slopes)
                  + ' deg/sample per unit'],
                 ['chatter band', f'{spec.idz.beta:g} ({spec.idz.mode})']]
    if spec.u_limits is not None:
        rows.append(['u limits', ', '.join(f'{x:.4f}' for x in spec.u_limits)])
    lines = [f'PIP-IDZ controller for joint {spec.joint} ({spec.design["method"]} design)']
    lines += table(rows, ['', 'value'])
    if args.out:
        lines.append(f'wrote {payload["controller"]}')
    return Outcome(payload, lines)
