"""What the controller node's configure builds: one loop per joint, with its parameters."""

from __future__ import annotations

from dataclasses import dataclass

from hydro_sdp.core.control.safety import setpoint_range
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.io.controller_files import controller_for
from hydro_sdp.io.model_files import load_model
from hydro_sdp.ros.joint_loop import JointLoop
from hydro_sdp.ros.parameters.node_parameters import NodeParameters


@dataclass(frozen=True)
class JointFiles:
    """
    The files of one joint.

    Attributes
    ----------
    joint : str
        Joint name, or '' for the one joint of a node without ``joints`` (named by the ``joint``
        parameter, whose default is the controller's joint).
    controller_file : str or None
        Its controller file, or None to design from the model.

    """

    joint: str
    model_file: str
    controller_file: str | None


def joint_files(parameters: NodeParameters) -> list[JointFiles]:
    """
    Return the files of every joint, from ``joints``, ``model_files``, ``controller_files``.

    ``parameters``: the controller's parameters.
    Returns: one per joint; one (unnamed) from ``model_file`` and ``controller_file`` when
    ``joints`` is not set.
    Raises ConfigurationError if the lists do not match ``joints`` or a joint is named twice.
    """
    joints = parameters.texts('joints')
    if not joints:
        return [JointFiles('', parameters.text('model_file'),
                           parameters.text('controller_file') or None)]
    models = parameters.texts('model_files') or []
    controllers = parameters.texts('controller_files') or []
    if len(models) != len(joints):
        raise ConfigurationError(f'model_files needs one file per joint of joints '
                                 f'({len(joints)}), got {len(models)}')
    if controllers and len(controllers) != len(joints):
        raise ConfigurationError(f'controller_files needs one file per joint of joints '
                                 f'({len(joints)}) or none, got {len(controllers)}')
    if len(set(joints)) != len(joints):
        raise ConfigurationError(f'joint names must be distinct, got {joints}')
    return [JointFiles(joint, model, (controllers[i] if controllers else '') or None)
            for i, (joint, model) in enumerate(zip(joints, models))]


class ControllerConfiguration:
    """
    Build the controller's joints from its file parameters, and declare their parameters.

    ``parameters``: the controller's parameters.
    """

    def __init__(self, parameters: NodeParameters) -> None:
        self.parameters = parameters

    def build(self, timeout_ns: int, margin: float, now_ns: int, *, feedback_margin: float,
              stop_band: float) -> list[JointLoop]:
        """
        Load the files and design; declare each joint's parameters; return the loops.

        ``margin``: set-point margin, deg (it must leave room between the end stops).
        ``now_ns``: the node clock's reading, ns.
        ``feedback_margin``, ``stop_band``: allowance of the feedback checks and band of the
        stop-side hold, degrees.
        Returns: one per joint.
        Raises HydroSdpError if a file cannot be used or a value given at start-up is refused
        (nothing stays declared).
        """
        parameters = self.parameters
        period = parameters.period('control_period')
        loops = []
        for files in joint_files(parameters):
            model = load_model(files.model_file)
            spec = controller_for(model, files.controller_file, period)
            joint = files.joint
            if not joint:
                if not parameters.declared('joint'):
                    parameters.declare(['joint'], defaults={'joint': spec.joint})
                joint = parameters.text('joint')
            loop = JointLoop(joint, model, spec, timeout_ns, now_ns,
                             feedback_margin=feedback_margin, stop_band=stop_band)
            # Refused if the margin leaves no room between the stops.
            loop.allowed = setpoint_range(model.angle_limits, margin)
            loops.append(loop)
        declared: list[JointLoop] = []
        try:
            for loop in loops:
                declared.append(loop)
                names = parameters.declare_joint(loop.joint, loop.parameter_defaults(),
                                                 single=len(loops) == 1)
                loop.apply(loop.candidate(parameters.current(names)))
        except Exception:
            self.release(declared, single=len(loops) == 1)
            raise
        return loops

    def release(self, loops: list[JointLoop], single: bool | None = None) -> None:
        """Undeclare the joints' parameters (cleanup)."""
        single = len(loops) == 1 if single is None else single
        for loop in loops:
            self.parameters.undeclare_joint(loop.joint, loop.parameter_defaults(), single)
