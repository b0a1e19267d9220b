"""
Controller specifications: PIP-IDZ design from a joint model, and the controller file.

:func:`design_from_model` turns a :class:`~hydro_sdp.core.model.joint_model.JointModel`
into a :class:`ControllerSpec` at a chosen control period: IDZ slopes from the
chord of the static map (docs/methods.md section 3.3), the delay in control samples, and
PIP gains for the plant the IDZ leaves behind, ``y_k = y_{k-1} + u_{k-tau}``.
The spec is what ``hydro-sdp design`` writes (format ``hydro_sdp/controller/v1``)
and what the controller node loads.

"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

from hydro_sdp.core.control.idz import IDZ_MODES, IdzMode, InverseDeadZone
from hydro_sdp.core.control.pip_controller import ControllerSettings, PipIdzController
from hydro_sdp.core.control.pip_design import (
    closed_loop_poles, DiscretePlant, lq_design, LqWeights, PipGains, pole_assignment)
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import chord_commands, linearise, LinearMap, SdpDzMap, SdpMap
from hydro_sdp.core.model.timing import check_sample_period
from hydro_sdp.core.validation import (
    read_document, require_float, require_float_list, require_ordered_pair, require_pair)
import numpy as np

CONTROLLER_FORMAT = 'hydro_sdp/controller/v1'
#: Default u limits of an ``sdp`` model, as a multiple of its saturation speed.
U_LIMIT_MARGIN = 1.25


@dataclass(frozen=True)
class ControllerSpec:
    """
    A designed PIP-IDZ controller for one joint.

    Parameters
    ----------
    joint : str
        Joint name.
    control_period : float
        Control period, s.
    plant : DiscretePlant
        Design plant at the control period.
    gains : PipGains
        PIP gains.
    idz : InverseDeadZone or None
        Inverse dead-zone (``None``: the valve gets ``u`` itself).
    u_limits : tuple[float, float] or None
        Limits of ``u``, degrees per control sample.
    v_limits : tuple[float, float] or None
        Valve command range, input units.
    design : Mapping[str, Any]
        How the gains were found (``method``: ``lq`` with ``weights``, or ``poles``).

    """

    joint: str
    control_period: float
    plant: DiscretePlant
    gains: PipGains
    idz: InverseDeadZone | None
    u_limits: tuple[float, float] | None
    v_limits: tuple[float, float] | None
    design: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_sample_period(self.control_period)
        if len(self.gains.f) != self.plant.n or len(self.gains.g) != self.plant.m - 1:
            raise ConfigurationError(
                f'gains ({len(self.gains.f)} f, {len(self.gains.g)} g) do not fit a plant with '
                f'n = {self.plant.n}, m = {self.plant.m}')
        poles = closed_loop_poles(self.plant, self.gains)
        if np.max(np.abs(poles)) >= 1.0:
            raise ConfigurationError(f'the closed loop is unstable: poles {np.round(poles, 4)}')
        self.settings()  # validates limits against the IDZ

    @property
    def delay_samples(self) -> int:
        """Delay of the design plant, control samples."""
        return self.plant.delay

    @property
    def poles(self) -> np.ndarray:
        """Closed-loop poles of the linear design (computed, not stored)."""
        return closed_loop_poles(self.plant, self.gains)

    def settings(self) -> ControllerSettings:
        """Return the run-time settings of the controller."""
        return ControllerSettings(self.gains, self.idz, self.u_limits, self.v_limits)

    def controller(self) -> PipIdzController:
        """Return a fresh run-time controller."""
        return PipIdzController(self.settings())

    def to_mapping(self) -> dict[str, Any]:
        """Return the controller file's content."""
        idz = None
        if self.idz is not None:
            idz = {'mode': self.idz.mode, 'beta': self.idz.beta,
                   'dead_zone': list(self.idz.dead_zone), 'slopes': list(self.idz.slopes),
                   'rest': self.idz.rest}
        return {
            'format': CONTROLLER_FORMAT,
            'joint': self.joint,
            'control_period': self.control_period,
            'delay_samples': self.delay_samples,
            'plant': {'a': list(self.plant.a), 'b': list(self.plant.b)},
            'f': list(self.gains.f),
            'g': list(self.gains.g),
            'kI': self.gains.k_i,
            'poles': [format_pole(p) for p in self.poles],
            'design': dict(self.design),
            'idz': idz,
            'u_limits': None if self.u_limits is None else list(self.u_limits),
            'v_limits': None if self.v_limits is None else list(self.v_limits),
        }

    @classmethod
    def from_mapping(cls, data: Any) -> ControllerSpec:
        """
        Validate a controller file's content and build the spec.

        Parameters
        ----------
        data : Any
            The parsed YAML document.

        Returns
        -------
        ControllerSpec
            The spec; its closed loop is checked to be stable.

        """
        known = ('format', 'joint', 'control_period', 'delay_samples', 'plant', 'f', 'g', 'kI',
                 'poles', 'design', 'idz', 'u_limits', 'v_limits')
        data = read_document(data, 'a controller file', CONTROLLER_FORMAT, known=known,
                             required=('format', 'joint', 'control_period', 'plant', 'f', 'g',
                                       'kI'))
        plant = data['plant']
        if not isinstance(plant, Mapping) or set(plant) != {'a', 'b'}:
            raise ModelFileError("key 'plant': expected a mapping with keys 'a' and 'b'")
        try:
            spec = cls(
                joint=str(data['joint']),
                control_period=require_float(data['control_period'], 'control_period'),
                plant=DiscretePlant(require_float_list(plant['a'], 'plant.a'),
                                    require_float_list(plant['b'], 'plant.b')),
                gains=PipGains(require_float_list(data['f'], 'f'),
                               require_float_list(data['g'], 'g'),
                               require_float(data['kI'], 'kI')),
                idz=_idz_from_mapping(data.get('idz')),
                u_limits=_optional_pair(data.get('u_limits'), 'u_limits'),
                v_limits=_optional_pair(data.get('v_limits'), 'v_limits'),
                design=dict(data.get('design') or {}),
            )
        except ConfigurationError as error:
            raise ModelFileError(str(error)) from None
        delay = data.get('delay_samples')
        if delay is not None and delay != spec.delay_samples:
            raise ModelFileError(f"key 'delay_samples': {delay} disagrees with the plant's "
                                 f'delay of {spec.delay_samples}')
        return spec


def format_pole(pole: complex) -> str:
    """Format a pole as a Python complex literal, e.g. ``0.94+0.05j``."""
    # Repeated eigenvalues scatter by about sqrt(machine epsilon); six decimals hide that.
    pole = complex(pole)
    real = round(pole.real, 6) + 0.0
    imag = round(pole.imag, 6) + 0.0
    return f'{real:.6g}{imag:+.6g}j'


def _optional_pair(value: Any, key: str) -> tuple[float, float] | None:
    return None if value is None else require_ordered_pair(value, key)


def _idz_from_mapping(data: Any) -> InverseDeadZone | None:
    if data is None:
        return None
    if not isinstance(data, Mapping):
        raise ModelFileError("key 'idz': expected a mapping or null")
    unknown = sorted(set(data) - {'mode', 'beta', 'dead_zone', 'slopes', 'rest'})
    if unknown:
        raise ModelFileError(f"key 'idz': unknown key {unknown[0]!r}")
    for key in ('dead_zone', 'slopes'):
        if key not in data:
            raise ModelFileError(f"key 'idz': missing key {key!r}")
    mode = data.get('mode', 'zero')
    if mode not in IDZ_MODES:
        raise ModelFileError(f"key 'idz.mode': expected one of {', '.join(IDZ_MODES)}, "
                             f'got {mode!r}')
    return InverseDeadZone(
        dead_zone=require_ordered_pair(data['dead_zone'], 'idz.dead_zone', strict=False),
        slopes=require_pair(data['slopes'], 'idz.slopes'),
        beta=require_float(data.get('beta', 0.05), 'idz.beta'),
        mode=mode,
        rest=require_float(data.get('rest', 0.0), 'idz.rest'))


def idz_for_model(model: JointModel, control_period: float, *, beta: float | None = None,
                  mode: IdzMode = 'zero',
                  v_range: tuple[float, float] | None = None) -> InverseDeadZone:
    """
    Inverse dead-zone of a model at the control period (docs/methods.md section 3.3).

    Parameters
    ----------
    model : JointModel
        The joint.
    control_period : float
        Control period, s.
    beta : float or None
        Chatter band, degrees per control sample; default 0.05 for maps with a
        dead-zone (the paper's value) and 0 for a linear map.
    mode : str
        IDZ mode.
    v_range : tuple[float, float] or None
        ``(v_min, v_max)`` where the chords meet an ``sdp`` map; default: where
        its speed reaches two thirds of saturation (J2 in the paper: -2.2, 1.75).

    Returns
    -------
    InverseDeadZone
        Slopes in degrees per control sample per input unit.

    """
    period = check_sample_period(control_period)
    static_map = model.static_map
    if isinstance(static_map, SdpMap):
        v_min, v_max = v_range if v_range is not None else chord_commands(static_map)
        chord = linearise(static_map, v_min, v_max)
        dead_zone, slopes = chord.dead_zone, chord.slope
    elif isinstance(static_map, SdpDzMap):
        dead_zone, slopes = static_map.dead_zone, static_map.slope
    elif isinstance(static_map, LinearMap):
        dead_zone, slopes = (0.0, 0.0), (static_map.gain, static_map.gain)
    else:  # pragma: no cover - every kind is handled above
        raise ConfigurationError(f'no IDZ for kind {model.kind}')
    if beta is None:
        beta = 0.0 if isinstance(static_map, LinearMap) else 0.05
    return InverseDeadZone(dead_zone=dead_zone,
                           slopes=(slopes[0] * period, slopes[1] * period),
                           beta=beta, mode=mode, rest=model.rest_command)


def default_u_limits(model: JointModel, idz: InverseDeadZone,
                     control_period: float) -> tuple[float, float] | None:
    """
    Return the default limits of ``u`` for a model.

    For an ``sdp`` map, 1.25 times the saturation speeds (J2 at 0.05 s: about
    -1.84 and +2.43, near the paper's +-2.5); otherwise the chord increments at
    the valve's input limits, or no limits when the model has none.

    Parameters
    ----------
    model : JointModel
        The joint.
    idz : InverseDeadZone
        Its inverse dead-zone.
    control_period : float
        Control period, s.

    Returns
    -------
    tuple[float, float] or None
        ``(u_min, u_max)`` in degrees per control sample.

    """
    static_map = model.static_map
    if isinstance(static_map, SdpMap):
        negative, positive = static_map.saturation_velocity
        return (U_LIMIT_MARGIN * negative * control_period,
                U_LIMIT_MARGIN * positive * control_period)
    if model.input_limits is None:
        return None
    low, high = model.input_limits
    return idz.increment(low), idz.increment(high)


def design_from_model(model: JointModel, *, control_period: float = 0.05,
                      poles: Sequence[complex] | None = None,
                      weights: LqWeights | None = None,
                      u_limits: tuple[float, float] | None = None,
                      beta: float | None = None, mode: IdzMode = 'zero',
                      v_range: tuple[float, float] | None = None) -> ControllerSpec:
    """
    Design a PIP-IDZ controller for a joint model.

    Parameters
    ----------
    model : JointModel
        The joint.
    control_period : float
        Control period, s.
    poles : sequence of complex or None
        Closed-loop poles (``n + m`` of them); default: LQ design.
    weights : LqWeights or None
        LQ weights; default :class:`LqWeights` (the paper's design for J2:
        dominant poles 0.94 +- 0.05i at any delay).
    u_limits : tuple[float, float] or None
        Limits of ``u``; default :func:`default_u_limits`.
    beta, mode, v_range
        IDZ chatter band, mode and chord ends, as in :func:`idz_for_model`.

    Returns
    -------
    ControllerSpec
        The controller.

    """
    period = check_sample_period(control_period)
    plant = DiscretePlant.integrator(model.delay_samples(period))
    if poles is not None:
        gains = pole_assignment(plant, poles)
        design: dict[str, Any] = {'method': 'poles',
                                  'requested': [format_pole(p) for p in poles]}
    else:
        weights = weights if weights is not None else LqWeights()
        gains = lq_design(plant, weights)
        design = {'method': 'lq', 'weights': {'w_y': weights.w_y, 'w_u': weights.w_u,
                                              'w_e': weights.w_e}}
    idz = idz_for_model(model, period, beta=beta, mode=mode, v_range=v_range)
    if u_limits is None:
        u_limits = default_u_limits(model, idz, period)
    return ControllerSpec(joint=model.joint, control_period=period, plant=plant, gains=gains,
                          idz=idz, u_limits=u_limits, v_limits=model.input_limits,
                          design=design)
