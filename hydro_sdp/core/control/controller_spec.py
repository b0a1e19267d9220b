"""Controller specifications: PIP-IDZ design from a joint model (methods 4.3-4.5)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Mapping, Sequence

from hydro_sdp.core.control.design_plant import (
    check_plant_lag, Mode, model_lag, model_mode, plant_for_model)
from hydro_sdp.core.control.idz import IdzMode
from hydro_sdp.core.control.idz_bounds import design_notes
from hydro_sdp.core.control.idz_design import default_u_limits, idz_for_model, IdzForm
from hydro_sdp.core.control.idz_mapping import idz_from_mapping, idz_to_mapping
from hydro_sdp.core.control.idz_table import Idz
from hydro_sdp.core.control.idz_table_design import DEFAULT_NOISE
from hydro_sdp.core.control.pip_controller import ControllerSettings, PipIdzController
from hydro_sdp.core.control.pip_design import (
    closed_loop_poles, DiscretePlant, lq_design, LqWeights, PipGains, pole_assignment)
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import require_period, SamplePeriod
from hydro_sdp.core.validation import (
    Document, read_document, require_float, require_float_list, require_ordered_pair)
import numpy as np

CONTROLLER_FORMAT = 'hydro_sdp/controller/v1'
#: Keys of the ``plant`` mapping.
PLANT_KEYS = {'a', 'b', 'valve_lag', 'oscillation'}


@dataclass(frozen=True)
class ControllerSpec:
    """
    A designed PIP-IDZ controller for one joint.

    Parameters
    ----------
    joint : str
        Joint name.
    control_period : SamplePeriod
        Control period, s (a number is checked and wrapped).
    plant : DiscretePlant
        Design plant at the control period.
    gains : PipGains
        PIP gains.
    idz : InverseDeadZone, TableInverseDeadZone or None
        Inverse dead-zone, chord or table (``None``: the valve gets ``u`` itself).
    u_limits : tuple[float, float] or None
        Limits of ``u``, degrees per control sample.
    v_limits : tuple[float, float] or None
        Valve command range, input units.
    design : Document
        How the gains were found (``method``: ``lq`` with ``weights``, or ``poles``).
    valve_lag : float or None
        Valve lag the plant was made from, s (:func:`.design_plant.lagged_integrator`);
        ``None``: the plant is given as it is.
    oscillation : tuple[float, float] or None
        The link's mode the plant was made from, Hz and damping ratio; ``None``: none.

    See Also
    --------
    design_from_model : the controller of a model.
    load_controller, save_controller : the controller file.

    Examples
    --------
    >>> from hydro_sdp import design_from_model, load_model
    >>> spec = design_from_model(load_model('config/brokk_j2.yaml'))
    >>> spec.control_period, spec.delay_samples
    (0.05, 3)

    """

    joint: str
    control_period: SamplePeriod
    plant: DiscretePlant
    gains: PipGains
    idz: Idz | None
    u_limits: tuple[float, float] | None
    v_limits: tuple[float, float] | None
    design: Document = field(default_factory=dict)
    valve_lag: float | None = None
    oscillation: Mode | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, 'control_period', SamplePeriod(self.control_period))
        if self.valve_lag is not None or self.oscillation is not None:
            check_plant_lag(self.plant, self.valve_lag, self.control_period, self.oscillation)
        if len(self.gains.f) != self.plant.n or len(self.gains.g) != self.plant.m - 1:
            raise ConfigurationError(
                f'gains ({len(self.gains.f)} f, {len(self.gains.g)} g) do not fit a plant with '
                f'n = {self.plant.n}, m = {self.plant.m}')
        poles = closed_loop_poles(self.plant, self.gains)
        if np.max(np.abs(poles)) >= 1.0:
            raise ConfigurationError(f'the closed loop is unstable: poles {np.round(poles, 4)}')
        self.settings()  # validates limits against the IDZ

    @property
    def notes(self) -> tuple[str, ...]:
        """Return what the design says of the values it took where the data left a choice."""
        notes = self.design.get('undetermined', ())
        return tuple(str(note) for note in notes) if isinstance(notes, (list, tuple)) else ()

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

    def to_mapping(self) -> dict[str, object]:
        """Return the controller file's content."""
        plant: dict[str, object] = {'a': list(self.plant.a), 'b': list(self.plant.b)}
        if self.valve_lag is not None:
            plant['valve_lag'] = self.valve_lag
        if self.oscillation is not None:
            plant['oscillation'] = {'frequency': self.oscillation[0],
                                    'damping': self.oscillation[1]}
        return {
            'format': CONTROLLER_FORMAT,
            'joint': self.joint,
            'control_period': float(self.control_period),
            'delay_samples': self.delay_samples,
            'plant': plant,
            'f': list(self.gains.f),
            'g': list(self.gains.g),
            'kI': self.gains.k_i,
            'poles': [format_pole(p) for p in self.poles],
            'design': dict(self.design),
            'idz': idz_to_mapping(self.idz),
            'u_limits': None if self.u_limits is None else list(self.u_limits),
            'v_limits': None if self.v_limits is None else list(self.v_limits),
        }

    @classmethod
    def from_mapping(cls, data: object) -> ControllerSpec:
        """
        Validate a controller file's content and build the spec.

        Parameters
        ----------
        data : object
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
        if not isinstance(plant, Mapping) or not {'a', 'b'} <= set(plant) <= PLANT_KEYS:
            raise ModelFileError("key 'plant': expected a mapping with keys 'a' and 'b' "
                                 "(and 'valve_lag', 'oscillation')")
        lag = plant.get('valve_lag')
        mode = _plant_mode(plant.get('oscillation'))
        idz = idz_from_mapping(data.get('idz'))
        design = data.get('design') or {}
        if not isinstance(design, Mapping):
            raise ModelFileError("key 'design': expected a mapping of how the gains were found")
        try:
            spec = cls(
                joint=str(data['joint']),
                control_period=require_period(data['control_period'], 'control_period'),
                plant=DiscretePlant(require_float_list(plant['a'], 'plant.a'),
                                    require_float_list(plant['b'], 'plant.b')),
                gains=PipGains(require_float_list(data['f'], 'f'),
                               require_float_list(data['g'], 'g'),
                               require_float(data['kI'], 'kI')),
                idz=idz,
                u_limits=_optional_pair(data.get('u_limits'), 'u_limits'),
                v_limits=_optional_pair(data.get('v_limits'), 'v_limits'),
                design=dict(design),
                valve_lag=None if lag is None else require_float(lag, 'plant.valve_lag'),
                oscillation=mode,
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


def _plant_mode(value: object) -> Mode | None:
    """Read ``plant.oscillation``: ``{frequency: Hz, damping: ratio}``, or None."""
    if value is None:
        return None
    if not isinstance(value, Mapping) or set(value) != {'frequency', 'damping'}:
        raise ModelFileError("key 'plant.oscillation': expected a mapping with keys "
                             "'frequency' and 'damping'")
    return (require_float(value['frequency'], 'plant.oscillation.frequency'),
            require_float(value['damping'], 'plant.oscillation.damping'))


def _optional_pair(value: object, key: str) -> tuple[float, float] | None:
    return None if value is None else require_ordered_pair(value, key)


def design_from_model(model: JointModel, *, control_period: float = 0.05,
                      poles: Sequence[complex] | None = None,
                      weights: LqWeights | None = None,
                      u_limits: tuple[float, float] | None = None,
                      beta: float | None = None, mode: IdzMode = 'zero',
                      v_range: tuple[float, float] | None = None,
                      form: IdzForm | None = None,
                      noise_std: float = DEFAULT_NOISE, fade: float = 0.0) -> ControllerSpec:
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
        Limits of ``u``; default :func:`.idz_design.default_u_limits`.
    beta, mode, v_range, form
        IDZ chatter band, mode, command range and form (``chord`` or ``table``;
        default: the chord for ``sdp``, ``sdp_dz`` and ``linear`` maps, the table
        for the others), as in :func:`.idz_design.idz_for_model`.
    noise_std : float
        Angle noise the controller will read, degrees: a table's default chatter
        band covers it (default 0.03, the online identifier's default).
    fade : float
        Fade-in band of the IDZ beyond its chatter band, degrees per control sample
        (0: none; docs/methods.md section 5.2).

    Returns
    -------
    ControllerSpec
        The controller, designed on the integrator with the model's delay, valve lag and
        link mode.

    See Also
    --------
    ControllerSpec : the controller and its file.
    calibrate : identification, diagnosis, design and the closed-loop check in one call.

    Examples
    --------
    >>> from hydro_sdp import design_from_model, load_model
    >>> spec = design_from_model(load_model('config/brokk_j2.yaml'))
    >>> spec.gains.k_i > 0
    True

    """
    period = SamplePeriod(control_period)
    plant = plant_for_model(model, period)
    lag = model_lag(model)
    ringing = model_mode(model)
    if poles is not None:
        gains = pole_assignment(plant, poles)
        design: dict[str, object] = {'method': 'poles',
                                     'requested': [format_pole(p) for p in poles]}
    else:
        weights = weights if weights is not None else LqWeights()
        gains = lq_design(plant, weights)
        design = {'method': 'lq', 'weights': {'w_y': weights.w_y, 'w_u': weights.w_u,
                                              'w_e': weights.w_e}}
    idz = idz_for_model(model, period, form=form, beta=beta, mode=mode, v_range=v_range,
                        design=(plant, gains, lag), noise_std=noise_std)
    notes = design_notes(model, idz.dead_zone) if idz is not None else ()
    if notes:
        design['undetermined'] = list(notes)
    if fade:
        idz = replace(idz, fade=fade)
    if u_limits is None:
        u_limits = default_u_limits(model, idz, period)
    return ControllerSpec(joint=model.joint, control_period=period, plant=plant, gains=gains,
                          idz=idz, u_limits=u_limits, v_limits=model.input_limits,
                          design=design, valve_lag=lag, oscillation=ringing)
