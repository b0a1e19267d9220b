"""Safety rules shared by the controller node and ``hydro-sdp closed-loop`` (methods 4.11)."""

from __future__ import annotations

from dataclasses import replace
import math

from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.control.idz_table import Idz
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Default distance of set-points from the end stops, degrees.
SETPOINT_MARGIN = 0.5
#: Default band of the stop-side hold, degrees (:class:`StopHold`).
STOP_BAND = 0.5
#: How far an IDZ slope may lie outside the model's physical slopes (a factor either way).
SLOPE_TOLERANCE = 2.0
#: Commands per side at which the model's map is read for its slopes.
_SLOPE_POINTS = 200


def setpoint_range(angle_limits: tuple[float, float] | None,
                   margin: float = SETPOINT_MARGIN) -> tuple[float, float] | None:
    """
    Return the range of allowed set-points: the end stops moved ``margin`` inwards.

    ``angle_limits``: end stops, degrees (``None``: no stops, no range).
    ``margin``: distance kept from each stop, degrees (>= 0).
    Returns: ``(low, high)``, degrees.
    Raises ConfigurationError if ``margin`` is negative or not finite, or leaves no room between
    the stops.
    """
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 0.0):
        raise ConfigurationError(f'setpoint_margin must be a finite number >= 0 deg, '
                                 f'got {margin!r}')
    if angle_limits is None:
        return None
    low, high = float(angle_limits[0]) + margin, float(angle_limits[1]) - margin
    if low > high:
        raise ConfigurationError(f'setpoint_margin {margin:g} deg leaves no set-point between '
                                 f'the end stops {list(angle_limits)}')
    return low, high


def clamp_setpoint(setpoint: float, angle_limits: tuple[float, float] | None,
                   margin: float = SETPOINT_MARGIN) -> float:
    """Return ``setpoint`` kept ``margin`` degrees inside the end stops."""
    allowed = setpoint_range(angle_limits, margin)
    if allowed is None:
        return float(setpoint)
    return min(max(float(setpoint), allowed[0]), allowed[1])


def check_controller_fits(spec: ControllerSpec, model: JointModel) -> None:
    """
    Refuse a controller made for another joint or for commands beyond the model's valve range.

    Raises ConfigurationError naming the joint or the ranges that differ, and what to do.
    """
    if spec.joint != model.joint:
        raise ConfigurationError(f'the controller is for joint {spec.joint!r}, the model is '
                                 f'joint {model.joint!r}: design a controller from this model '
                                 '(hydro-sdp design MODEL --out CONTROLLER)')
    ours, theirs = spec.v_limits, model.input_limits
    if ours is None or theirs is None:
        return
    slack = 1e-9 * max(abs(theirs[0]), abs(theirs[1]), 1.0)
    if ours[0] < theirs[0] - slack or ours[1] > theirs[1] + slack:
        raise ConfigurationError(
            f'the controller commands the valve over {list(ours)}, beyond the range '
            f'{list(theirs)} of the model of joint {model.joint!r}: design the controller '
            'from this model (hydro-sdp design MODEL --out CONTROLLER), or give the model '
            "the valve's whole range (identify --input-limits LOW HIGH)")


def controller_within_model(spec: ControllerSpec, model: JointModel) -> ControllerSpec:
    """Return the controller to run on ``model``: checked, and limited to its valve range."""
    check_controller_fits(spec, model)
    if spec.v_limits is None and model.input_limits is not None:
        return replace(spec, v_limits=model.input_limits)
    return spec


def top_speeds(model: JointModel) -> tuple[float, float] | None:
    """Return the joint's identified top speeds down and up, deg/s, over its valve range."""
    if model.input_limits is None:
        return None
    rates = model.rate(np.linspace(*model.input_limits, 2 * _SLOPE_POINTS + 1))
    return min(float(np.min(rates)), 0.0), max(float(np.max(rates)), 0.0)


def slope_bounds(model: JointModel, control_period: SamplePeriod,
                 v_limits: tuple[float, float] | None) -> list[tuple[float, float] | None]:
    """
    Return the physical IDZ slopes of each side of the model's map, (low, high) each.

    ``control_period``: control period, s.
    ``v_limits``: valve range, input units (default: the model's).
    Returns: negative side, positive side; None for a side without a range or without motion.
    """
    limits = v_limits if v_limits is not None else model.input_limits
    if limits is None:
        return [None, None]
    rest = model.rest_command
    edges = model.dead_zone or (rest, rest)
    bounds: list[tuple[float, float] | None] = []
    for edge, end in ((edges[0], limits[0]), (edges[1], limits[1])):
        if abs(end - edge) <= 1e-9 * max(abs(end), 1.0):
            bounds.append(None)
            continue
        v = edge + (end - edge) * np.linspace(1.0 / _SLOPE_POINTS, 1.0, _SLOPE_POINTS)
        chords = control_period * model.rate(v) / (v - edge)
        bounds.append((float(chords[-1]), float(np.max(chords))) if chords[-1] > 0.0
                      else None)
    return bounds


def check_idz_fits(idz: Idz, model: JointModel, control_period: SamplePeriod,
                   v_limits: tuple[float, float] | None) -> None:
    """
    Refuse an IDZ whose edges leave the valve range or whose slopes the joint cannot have.

    ``control_period``: control period, s.
    ``v_limits``: valve range, input units (default: the model's).
    Raises ConfigurationError naming the edge or slope, its bound and where the bound comes from.
    """
    limits = v_limits if v_limits is not None else model.input_limits
    low, high = idz.dead_zone
    if limits is not None and not limits[0] < low <= high < limits[1]:
        raise ConfigurationError(f'IDZ edges {[low, high]} must lie inside the valve range '
                                 f'{list(limits)}')
    for side, slope, bound in zip(('negative', 'positive'), idz.slopes,
                                  slope_bounds(model, control_period, limits)):
        if bound is None:
            continue
        least, most = bound[0] / SLOPE_TOLERANCE, bound[1] * SLOPE_TOLERANCE
        if not least <= slope <= most:
            raise ConfigurationError(
                f'IDZ {side} slope {slope:.6g} lies outside [{least:.4g}, {most:.4g}] deg per '
                f"control sample per input unit: the model's map gives {bound[0]:.4g} (its chord "
                f'to the valve end) to {bound[1]:.4g} (its steepest chord), and a factor '
                f'{SLOPE_TOLERANCE:g} either way is allowed')


class StopHold:
    """
    Hold the valve in its dead-zone once the joint is near a set-point at a stop.

    ``band``: band, degrees (>= 0; 0 never holds).
    """

    def __init__(self, band: float = STOP_BAND) -> None:
        self.band = band
        self.holding = False

    @property
    def band(self) -> float:
        """Return the band, degrees (settable)."""
        return self._band

    @band.setter
    def band(self, value: float) -> None:
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0):
            raise ConfigurationError(f'stop_band must be a finite number >= 0 deg, '
                                     f'got {value!r}')
        self._band = float(value)

    def decide(self, setpoint: float, angle: float,
               allowed: tuple[float, float] | None) -> bool:
        """
        Return whether the valve holds at this control step.

        ``setpoint``: set-point in force, degrees.
        ``angle``: the angle, degrees: measured, or where the commands already sent take the joint.
        ``allowed``: allowed set-point range (:func:`setpoint_range`); None: no stops, no hold.
        """
        band = self._band
        side = 0.0
        if allowed is not None and band > 0.0:
            if setpoint >= allowed[1] - band:
                side = 1.0
            elif setpoint <= allowed[0] + band:
                side = -1.0
        if side == 0.0:
            self.holding = False
            return False
        ahead = side * (angle - setpoint)      # > 0: past the set-point, towards the stop
        if self.holding:
            self.holding = ahead >= -2.0 * band
        else:
            self.holding = ahead >= -band
        return self.holding
