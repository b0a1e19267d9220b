"""The inverse dead-zone (IDZ) of a joint model: chords or the map's table (methods 5.4, 5.6)."""

from __future__ import annotations

from dataclasses import replace
from typing import get_args, Literal

from hydro_sdp.core.control.design_plant import model_lag, plant_for_model
from hydro_sdp.core.control.idz import IdzMode, InverseDeadZone
from hydro_sdp.core.control.idz_table import Idz, TableInverseDeadZone
from hydro_sdp.core.control.idz_table_design import DEFAULT_NOISE, table_beta, table_idz
from hydro_sdp.core.control.pip_design import DiscretePlant, lq_design, PipGains
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.model.command_span import command_span
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import (
    chord_commands, CHORD_SPEED_FRACTION, linearise, LinearMap, SdpDzMap, SdpMap)
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: How the IDZ inverts the map.
IdzForm = Literal['chord', 'table']
IDZ_FORMS: tuple[IdzForm, ...] = get_args(IdzForm)
#: Default u limits of an ``sdp`` model's chord IDZ, as a multiple of its saturation speed.
U_LIMIT_MARGIN = 1.25
#: Default chatter band of a chord IDZ, degrees per control sample ([W18]).
CHORD_BETA = 0.05
#: Speed, as a fraction of the speed at the end of the span, that the chord of a
#: convex map passes through on its way to the two-thirds point.
CREEP_SPEED_FRACTION = 0.02
#: Fade-in band a design takes when its IDZ pulses at hold, in chatter bands.
FADE_MULTIPLE = 2.0


def idz_form(value: object) -> IdzForm:
    """Return ``value`` as an IDZ form name, or raise :class:`ConfigurationError`."""
    for form in IDZ_FORMS:
        if value == form:
            return form
    raise ConfigurationError(f"IDZ form must be one of {', '.join(IDZ_FORMS)}, got {value!r}")


def default_form(model: JointModel) -> IdzForm:
    """Return ``chord`` for ``sdp``, ``sdp_dz`` and ``linear`` models, ``table`` otherwise."""
    return 'chord' if isinstance(model.static_map, (SdpMap, SdpDzMap, LinearMap)) else 'table'


def chord_map(model: JointModel, span: tuple[float, float]) -> SdpDzMap:
    """
    SDP-DZ chords of any monotone map, as the IDZ of an ``sdp`` map (docs/methods.md 3.3).

    ``span``: commands the map is trusted over (the measured levels), input units.
    """
    rest = model.rest_command
    edges, slopes = [], []
    for end, sign in ((span[0], -1.0), (span[1], 1.0)):
        v = np.linspace(rest, end, 2001)
        speed = sign * model.rate(v)
        top = float(speed[-1])
        if not (sign * (end - rest) > 0.0 and top > 0.0):
            raise DataError(f'the {model.kind} map does not move the joint '
                            f'{"down" if sign < 0 else "up"} within the commands measured')
        leaves = float(v[max(int(np.argmax(speed > 1e-3 * top)) - 1, 0)])
        creep = float(v[int(np.argmax(speed >= CREEP_SPEED_FRACTION * top))])
        reach = float(v[int(np.argmax(speed >= CHORD_SPEED_FRACTION * top))])
        secant = (CHORD_SPEED_FRACTION - CREEP_SPEED_FRACTION) * top / max(
            abs(reach - creep), 1e-12)
        meets = creep - sign * CREEP_SPEED_FRACTION * top / secant
        edge = leaves if sign * (leaves - meets) >= 0.0 else meets
        edges.append(edge)
        slopes.append(CHORD_SPEED_FRACTION * top / max(abs(reach - edge), 1e-12))
    return SdpDzMap(dead_zone=(edges[0], edges[1]), slope=(slopes[0], slopes[1]))


def chord_idz(model: JointModel, control_period: SamplePeriod, *, beta: float | None = None,
              mode: IdzMode = 'zero',
              v_range: tuple[float, float] | None = None) -> InverseDeadZone:
    """
    Return the paper's chord IDZ of a model at the control period (docs/methods.md section 3.3).

    ``control_period``: control period, s.
    ``beta``: chatter band, degrees per control sample; default 0.05 for maps with a dead-zone (the
    paper's value) and 0 for a linear map.
    ``v_range``: for an ``sdp`` map, ``(v_min, v_max)`` where the chords meet it (default: where
    its speed reaches two thirds of saturation; J2 in the paper: -2.2, 1.75); for ``pwl``, ``poly``
    and ``power_sat`` maps the commands whose speeds the chords of :func:`chord_map` refer to
    (default :func:`command_span`).
    Returns: slopes in degrees per control sample per input unit.
    """
    static_map = model.static_map
    if isinstance(static_map, SdpMap):
        v_min, v_max = v_range if v_range is not None else chord_commands(static_map)
        chord = linearise(static_map, v_min, v_max)
        dead_zone, slopes = chord.dead_zone, chord.slope
    elif isinstance(static_map, SdpDzMap):
        dead_zone, slopes = static_map.dead_zone, static_map.slope
    elif isinstance(static_map, LinearMap):
        dead_zone, slopes = (0.0, 0.0), (static_map.gain, static_map.gain)
    else:
        chord = chord_map(model, command_span(model, v_range))
        dead_zone, slopes = chord.dead_zone, chord.slope
        model = replace(model, static_map=chord)
    if beta is None:
        beta = 0.0 if isinstance(static_map, LinearMap) else CHORD_BETA
    return InverseDeadZone(dead_zone=dead_zone,
                           slopes=(slopes[0] * control_period, slopes[1] * control_period),
                           beta=beta, mode=mode, rest=model.rest_command)


def idz_for_model(model: JointModel, control_period: SamplePeriod, *,
                  form: IdzForm | None = None,
                  beta: float | None = None, mode: IdzMode = 'zero',
                  v_range: tuple[float, float] | None = None,
                  design: tuple[DiscretePlant, PipGains, float | None] | None = None,
                  noise_std: float = DEFAULT_NOISE) -> Idz:
    """
    Return the IDZ of a model in either form (default :func:`default_form`).

    ``control_period``: control period, s.
    ``form``: ``chord`` or ``table``.
    ``beta``: chatter band; default 0.05 for chords (0 for a linear map) and
    :func:`.idz_table_design.table_beta` for a table.
    ``v_range``: as in :func:`chord_idz` and :func:`.idz_table_design.table_idz`.
    ``design``: ``(plant, gains, valve lag)`` of the design, for a table's default band (default:
    the model's plant with the default LQ gains).
    ``noise_std``: angle noise the controller reads, degrees, for a table's default band.
    """
    form = default_form(model) if form is None else idz_form(form)
    if form == 'chord':
        return chord_idz(model, control_period, beta=beta, mode=mode, v_range=v_range)
    table = table_idz(model, control_period, beta=0.0, mode=mode, v_range=v_range)
    if beta is None:
        if design is None:
            plant = plant_for_model(model, control_period)
            design = (plant, lq_design(plant), model_lag(model))
        beta = table_beta(table.dead_zone, design[0], design[1], design[2], control_period,
                          noise_std)
    return replace(table, beta=beta)


def faded(idz: Idz) -> Idz:
    """Return the IDZ with the fade-in band a design takes when it pulses at hold (methods 5.2)."""
    return replace(idz, mode='zero', fade=FADE_MULTIPLE * idz.beta)


def default_u_limits(model: JointModel, idz: Idz,
                     control_period: SamplePeriod) -> tuple[float, float] | None:
    """
    Return the default limits of ``u`` for a model and its IDZ.

    ``control_period``: control period, s.
    Returns: ``(u_min, u_max)`` in degrees per control sample.
    """
    if isinstance(idz, TableInverseDeadZone):
        return idz.u_range
    static_map = model.static_map
    if isinstance(static_map, SdpMap):
        negative, positive = static_map.saturation_velocity
        return (U_LIMIT_MARGIN * negative * control_period,
                U_LIMIT_MARGIN * positive * control_period)
    if model.input_limits is None:
        return None
    low, high = model.input_limits
    return idz.increment(low), idz.increment(high)
