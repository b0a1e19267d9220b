"""The controller file (YAML, ``hydro_sdp/controller/v1``, docs/interfaces.md section 6)."""

from __future__ import annotations

import os
from pathlib import Path

from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model
from hydro_sdp.core.control.safety import controller_within_model
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.io.atomic import atomic_write_text
from hydro_sdp.io.documents import load_document, yaml_text


def load_controller(path: str | os.PathLike[str]) -> ControllerSpec:
    """
    Load and validate a controller file written by ``hydro-sdp design``.

    Parameters
    ----------
    path : str or PathLike
        Controller file.

    Returns
    -------
    ControllerSpec
        The controller; its closed loop is checked to be stable.

    See Also
    --------
    save_controller : write a controller file.

    Examples
    --------
    >>> from hydro_sdp import design_from_model, load_controller, load_model, save_controller
    >>> path = save_controller(design_from_model(load_model('config/brokk_j2.yaml')), 'c.yaml')
    >>> load_controller(path).joint
    'j2'

    """
    return load_document(path, ControllerSpec.from_mapping)


def controller_for(model: JointModel, path: str | os.PathLike[str] | None,
                   control_period: SamplePeriod) -> ControllerSpec:
    """Return the controller of ``path`` checked against ``model``, or one designed from it."""
    if path:
        return controller_within_model(load_controller(path), model)
    return design_from_model(model, control_period=control_period)


def save_controller(spec: ControllerSpec, path: str | os.PathLike[str]) -> Path:
    """
    Write the controller ``spec`` to a file whole or not at all.

    Parameters
    ----------
    spec : ControllerSpec
        The controller.
    path : str or PathLike
        Target file.

    Returns
    -------
    Path
        The target path.

    See Also
    --------
    load_controller : read a controller file.
    design_from_model : the controller of a model.

    """
    return atomic_write_text(path, yaml_text(spec.to_mapping()))
