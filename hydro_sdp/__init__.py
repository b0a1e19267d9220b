"""
State-dependent parameter identification and PIP-IDZ control of hydraulic joints.

Arrays in, a model out::

    import hydro_sdp as hs
    found = hs.identify([hs.Record(t, v, y, joint='j2')])
    controller = hs.design_from_model(found.model)

The names below are the user-level API; each is imported on first use, so that
``import hydro_sdp`` stays cheap. The numerical core lives in :mod:`hydro_sdp.core`
and never imports ROS; bags, the command line and plots are thin adapters around it.

"""

from __future__ import annotations

import importlib
from typing import Any, TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover - for type checkers and editors only
    from hydro_sdp.core.calibration import calibrate
    from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model
    from hydro_sdp.core.diagnosis.search import diagnose
    from hydro_sdp.core.identification.evaluation import evaluate
    from hydro_sdp.core.identification.identify import identify
    from hydro_sdp.core.identification.state_dependence.analysis import analyse
    from hydro_sdp.core.model.joint_model import JointModel
    from hydro_sdp.core.model.records import Record
    from hydro_sdp.core.model.simulation import simulate
    from hydro_sdp.io.controller_files import load_controller, save_controller
    from hydro_sdp.io.model_files import load_model, save_model

__version__ = '0.1.0'

#: Public name -> module that defines it.
_EXPORTS = {
    'Record': 'hydro_sdp.core.model.records',
    'JointModel': 'hydro_sdp.core.model.joint_model',
    'ControllerSpec': 'hydro_sdp.core.control.controller_spec',
    'identify': 'hydro_sdp.core.identification.identify',
    'evaluate': 'hydro_sdp.core.identification.evaluation',
    'simulate': 'hydro_sdp.core.model.simulation',
    'analyse': 'hydro_sdp.core.identification.state_dependence.analysis',
    'diagnose': 'hydro_sdp.core.diagnosis.search',
    'design_from_model': 'hydro_sdp.core.control.controller_spec',
    'calibrate': 'hydro_sdp.core.calibration',
    'load_model': 'hydro_sdp.io.model_files',
    'save_model': 'hydro_sdp.io.model_files',
    'load_controller': 'hydro_sdp.io.controller_files',
    'save_controller': 'hydro_sdp.io.controller_files',
}

__all__ = [
    'analyse', 'calibrate', 'ControllerSpec', 'design_from_model', 'diagnose', 'evaluate',
    'identify', 'JointModel', 'load_controller', 'load_model', 'Record', 'save_controller',
    'save_model', 'simulate', '__version__',
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
