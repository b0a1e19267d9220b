"""The joint model file (YAML, ``hydro_sdp/model/v1``, docs/interfaces.md section 1)."""

from __future__ import annotations

import os
from pathlib import Path

from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.io.atomic import atomic_write_text
from hydro_sdp.io.documents import load_document, shipped_config, yaml_text


def load_model(path: str | os.PathLike[str]) -> JointModel:
    """
    Load and validate a model file (docs/interfaces.md section 1).

    Parameters
    ----------
    path : str or PathLike
        Model file.

    Returns
    -------
    JointModel
        The validated model.

    Raises
    ------
    ModelFileError
        With the file name, the key and the reason.

    See Also
    --------
    save_model : write a model file.

    Examples
    --------
    >>> from hydro_sdp import load_model
    >>> load_model('config/brokk_j2.yaml').joint
    'j2'

    """
    return load_document(path, JointModel.from_mapping)


def dump_model(model: JointModel) -> str:
    """Return the YAML text of a model file."""
    return yaml_text(model.to_mapping())


def save_model(model: JointModel, path: str | os.PathLike[str]) -> Path:
    """
    Write a model file whole or not at all.

    Parameters
    ----------
    model : JointModel
        The model.
    path : str or PathLike
        Target file.

    Returns
    -------
    Path
        The target path.

    See Also
    --------
    load_model : read a model file.

    Examples
    --------
    >>> from hydro_sdp import load_model, save_model
    >>> save_model(load_model('config/brokk_j2.yaml'), 'j2_copy.yaml').name
    'j2_copy.yaml'

    """
    return atomic_write_text(path, dump_model(model))


def default_model_path() -> Path:
    """Path of the shipped BROKK J2 model file."""
    return shipped_config('brokk_j2.yaml')
