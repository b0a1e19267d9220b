"""``hydro-sdp design``: a PIP-IDZ controller for a joint model."""

from __future__ import annotations

import argparse
import math

from hydro_sdp.cli.common import (
    finite_float, non_negative_float, Outcome, Payload, period_seconds, table)
from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model, format_pole
from hydro_sdp.core.control.idz import IDZ_MODES
from hydro_sdp.core.control.idz_design import chord_idz, IDZ_FORMS
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.idz_table_design import DEFAULT_NOISE
from hydro_sdp.core.control.pip_design import LqWeights
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.sample_period import control_period_on
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.io.controller_files import save_controller
from hydro_sdp.io.model_files import load_model

HELP = 'design a PIP controller with inverse dead-zone for a joint model'
DESCRIPTION = """\
Design a Proportional-Integral-Plus (PIP) controller with an inverse dead-zone
(IDZ) for a joint model, as in West et al. (2018) section 5.

Every map family identify writes is accepted. The IDZ inverts the model's
velocity map in one of two forms (--idz-form):

  chord  the paper's IDZ: straight lines from each dead-zone edge to where the
         speed reaches two thirds of saturation (--v-range to choose); the
         default for sdp, sdp_dz and linear maps.
  table  the map itself, as a table of points from the PIP's u (deg per control
         sample) to the valve command over the valve's range (--v-range to
         choose): for valves whose speed rises convexly from a wide dead-zone
         and saturates, where a chord promises near the edge several times the
         speed the valve gives; the default for pwl, poly and power_sat maps.
         Its chatter band covers --noise-std and keeps the smallest correction
         small for the model's delay and lag.

With --idz-fade the compensation fades in from rest beyond the chatter band
instead of jumping across the dead-zone (zero mode), so that the valve does not
pulse while the joint holds; calibrate takes twice the band when its check
finds the valve pulsing.

The controller then sees the integrator with the model's delay and, when the
model has a valve_lag, that lag (one more pole), and with an oscillation the
link's mode (two more): the design plant, recorded in the controller file. The
gains come from LQ design (default weights: the paper's design, dominant poles
0.94 +- 0.05i) or from pole assignment (--poles: n + m poles, complex ones in
conjugate pairs, zeros allowed and repeated; n + m is 1 + the delay in control
samples, two more with a valve lag, four more with a mode, six with both).

A controller steps every whole number of the joint's samples: with
--sample-period S (the period identify printed) the control period is the
whole multiple of S nearest --control-period, so records 0.0099909 s apart
(a logger's clock, a DDS timer) get the gains of 0.01 s.

examples:
  hydro-sdp design config/brokk_j2.yaml --out j2_controller.yaml
  hydro-sdp design config/brokk_j2.yaml --poles 0.94+0.05j 0.94-0.05j 0 0 \\
      --v-range -2.2 1.75 --u-limits -2.5 2.5 --out j2_paper.yaml
  hydro-sdp design arm/model.yaml --idz-form table --noise-std 0.01 \\
      --out arm_controller.yaml --plot arm_idz.png
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
    parser.add_argument('--control-period', type=period_seconds, default=SamplePeriod(0.05),
                        help='control period in s (default: 0.05)')
    parser.add_argument('--sample-period', type=period_seconds, metavar='S',
                        help="the records' sample period, s (identify prints it): the control "
                             'period becomes the nearest whole multiple of it'),
    parser.add_argument('--u-limits', nargs=2, type=finite_float, metavar=('LOW', 'HIGH'),
                        help='limits of u, deg per control sample (default: 1.25 x the '
                             'saturation speeds, or the chord at the input limits)')
    parser.add_argument('--v-range', nargs=2, type=finite_float, metavar=('V_MIN', 'V_MAX'),
                        help='commands where the IDZ chords meet an sdp map; the commands a '
                             'table covers (default: the input limits)')
    parser.add_argument('--beta', type=non_negative_float,
                        help='IDZ chatter band, deg per control sample (default: 0.05)')
    parser.add_argument('--idz-mode', choices=IDZ_MODES, default='zero',
                        help='IDZ near u = 0: zero band (paper), smooth blend or hysteresis')
    parser.add_argument('--idz-fade', type=non_negative_float, default=0.0, metavar='FADE',
                        help='IDZ fade-in band beyond the chatter band, deg per control '
                             'sample: the command leaves rest as tanh((|u| - beta) / FADE) '
                             '(zero mode; default: 0, none)')
    parser.add_argument('--idz-form', choices=IDZ_FORMS,
                        help="chord: invert chords of the map (the paper's IDZ); table: invert "
                             'the map itself (default: chord for sdp, sdp_dz and linear, '
                             'table for pwl, poly and power_sat)')
    parser.add_argument('--noise-std', type=non_negative_float, default=DEFAULT_NOISE,
                        metavar='DEG',
                        help="angle noise the controller will read, deg: an IDZ table's "
                             'chatter band covers it (default: 0.03)')
    parser.add_argument('--out', help='controller file to write (YAML)')
    parser.add_argument('--plot', help="PNG of the IDZ approximation (the paper's Fig. 6; a "
                                       'table is drawn with the chords and the loop gain of '
                                       'each)')
    parser.set_defaults(run=run)


def describe(spec: ControllerSpec) -> Payload:
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
        'plant': {'a': list(spec.plant.a), 'b': list(spec.plant.b),
                  'valve_lag': spec.valve_lag,
                  'oscillation': None if spec.oscillation is None else dict(
                      zip(('frequency', 'damping'), spec.oscillation))},
        'idz_form': None if idz is None else (
            'table' if isinstance(idz, TableInverseDeadZone) else 'chord'),
        'slopes': None if idz is None else list(idz.slopes),
        'dead_zone': None if idz is None else list(idz.dead_zone),
        'beta': None if idz is None else idz.beta,
        'idz_mode': None if idz is None else idz.mode,
        'fade': None if idz is None else idz.fade,
        'u_limits': None if spec.u_limits is None else list(spec.u_limits),
        'v_limits': None if spec.v_limits is None else list(spec.v_limits),
        'design': dict(spec.design),
    }


def run(args: argparse.Namespace) -> Outcome:
    """Run ``design``."""
    model = load_model(args.model)
    weights = LqWeights(*args.weights) if args.weights else None
    control = (None if args.sample_period is None
               else control_period_on(args.control_period, args.sample_period))
    spec = design_from_model(
        model, control_period=args.control_period if control is None else control.seconds,
        poles=args.poles, weights=weights,
        u_limits=tuple(args.u_limits) if args.u_limits else None, beta=args.beta,
        mode=args.idz_mode, v_range=tuple(args.v_range) if args.v_range else None,
        form=args.idz_form, noise_std=args.noise_std, fade=args.idz_fade)
    payload = describe(spec)
    if control is not None:
        payload['control_samples'] = control.samples
    if args.out:
        payload['controller'] = str(save_controller(spec, args.out))
    if args.plot:
        if spec.idz is None:
            raise ConfigurationError('--plot draws the inverse dead-zone, and this model has none')
        from hydro_sdp.plots import plot_idz, plot_idz_table, save_figure

        if isinstance(spec.idz, TableInverseDeadZone):
            chord = chord_idz(model, spec.control_period, beta=spec.idz.beta)
            figure = plot_idz_table(model, spec.idz, chord, spec.control_period)
        else:
            figure = plot_idz(model, spec.idz, spec.control_period, u_limits=spec.u_limits)
        payload['plot'] = str(save_figure(figure, args.plot))
    rows = [['f', ', '.join(f'{x:.4f}' for x in spec.gains.f)],
            ['g', ', '.join(f'{x:.4f}' for x in spec.gains.g) or '-'],
            ['kI', f'{spec.gains.k_i:.4f}'],
            ['poles', ', '.join(payload['poles'])],
            ['delay', f'{spec.delay_samples} samples of {spec.control_period:.9g} s'],
            ['valve lag', '-' if spec.valve_lag is None else f'{spec.valve_lag:.4g} s (pole '
                          f'{math.exp(-spec.control_period / spec.valve_lag):.4f})'],
            ['link mode', '-' if spec.oscillation is None else
             f'{spec.oscillation[0]:.3g} Hz, damping {spec.oscillation[1]:.2g}']]
    if spec.idz is not None:
        rows += [['IDZ form', payload['idz_form'] + (
                     f' ({len(spec.idz.u)} points)' if isinstance(spec.idz, TableInverseDeadZone)
                     else '')],
                 ['IDZ edges', ', '.join(f'{x:.4f}' for x in spec.idz.dead_zone)],
                 ['IDZ slopes', ', '.join(f'{x:.4f}' for x in spec.idz.slopes)
                  + ' deg/sample per unit'],
                 ['chatter band', f'{spec.idz.beta:g} ({spec.idz.mode})'
                  + (f', fade-in {spec.idz.fade:g}' if spec.idz.fade else '')]]
    if spec.u_limits is not None:
        rows.append(['u limits', ', '.join(f'{x:.4f}' for x in spec.u_limits)])
    lines = [f'PIP-IDZ controller for joint {spec.joint} ({spec.design["method"]} design)']
    if control is not None:
        lines.append(f'control every {control.samples} samples of {args.sample_period:.9g} s: '
                     f'{control.seconds:.9g} s')
    lines += table(rows, ['', 'value'])
    lines += list(spec.notes)
    if args.out:
        lines.append(f'wrote {payload["controller"]}')
    if args.plot:
        lines.append(f'wrote {payload["plot"]}')
    return Outcome(payload, lines)
