"""
Safety rules shared by the controller node and ``hydro-sdp closed-loop``.

* Set-points are kept ``margin`` degrees inside the end stops, so the loop never
  drives the joint into a stop (where the integral would press against it).
* A controller designed for another joint, or one that commands the valve beyond
  the range of the model in use, is refused with the reason and the fix. A range
  known on one side only is the range: a controller made from a model without
  one runs within the model's, and one made with a range runs a model without one.

"""

from __future__ import annotations

from dataclasses import replace
import math

from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel

#: Default distance of set-points from the end stops, degrees.
SETPOINT_MARGIN = 0.5


def setpoint_range(angle_limits: tuple[float, float] | None,
                   margin: float = SETPOINT_MARGIN) -> tuple[float, float] | None:
    """
    Return the range of allowed set-points: the end stops moved ``margin`` inwards.

    Parameters
    ----------
    angle_limits : tuple[float, float] or None
        End stops, degrees (``None``: no stops, no range).
    margin : float
        Distance kept from each stop, degrees (>= 0).

    Returns
    -------
    tuple[float, float] or None
        ``(low, high)``, degrees.

    Raises
    ------
    ConfigurationError
        If ``margin`` is negative or not finite, or leaves no room between the stops.

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
    """
    Return ``setpoint`` kept ``margin`` degrees inside the end stops.

    Parameters
    ----------
    setpoint : float
        Desired angle, degrees.
    angle_limits : tuple[float, float] or None
        End stops, degrees.
    margin : float
        Distance kept from each stop, degrees.

    Returns
    -------
    float
        The set-point to use, degrees (``setpoint`` itself when inside the range).

    """
    allowed = setpoint_range(angle_limits, margin)
    if allowed is None:
        return float(setpoint)
    return min(max(float(setpoint), allowed[0]), allowed[1])


def check_controller_fits(spec: ControllerSpec, model: JointModel) -> None:
    """
    Refuse a controller made for another joint or for commands beyond the model's valve range.

    Parameters
    ----------
    spec : ControllerSpec
        The controller (e.g. from a controller file).
    model : JointModel
        The joint it is to control.

    Raises
    ------
    ConfigurationError
        Naming the joint or the ranges that differ, and what to do.

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
    """
    Return the controller to run on ``model``: checked, and limited to its valve range.

    Parameters
    ----------
    spec : ControllerSpec
        The controller.
    model : JointModel
        The joint it is to control.

    Returns
    -------
    ControllerSpec
        ``spec``, with the model's valve range when it has none of its own.

    Raises
    ------
    ConfigurationError
        As :func:`check_controller_fits`.

    """
    check_controller_fits(spec, model)
    if spec.v_limits is None and model.input_limits is not None:
        return replace(spec, v_limits=model.input_limits)
    return spec
