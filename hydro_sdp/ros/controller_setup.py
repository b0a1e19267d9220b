"""
Configuration of the controller node: files, designs, per-joint parameters, interfaces.

:class:`ControllerSetup` is the part of
:class:`~hydro_sdp.ros.controller_node.PipControllerNode` that lifecycle
configure and cleanup run: it reads the file parameters, builds one
:class:`~hydro_sdp.ros.joint_loop.JointLoop` per joint, declares the joints'
run-time parameters, and creates (and destroys) the topics and timers.

"""

from __future__ import annotations

from functools import partial
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from hydro_sdp.core.control.health import joint_health
from hydro_sdp.core.control.safety import setpoint_range
from hydro_sdp.core.control.scheduling import seconds_to_ns, watchdog_period_ns
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.io.controller_files import controller_for
from hydro_sdp.io.model_files import load_model
from hydro_sdp.ros import qos
from hydro_sdp.ros.conversions import CONTROLLER_STATE_LABELS
from hydro_sdp.ros.diagnostics import diagnostic_array
from hydro_sdp.ros.joint_loop import JointLoop, PARAMETERS
from hydro_sdp.ros.params import alias, declare, unalias
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension
from trajectory_msgs.msg import JointTrajectory as TrajectoryMessage


class ControllerSetup:
    """Configure and clean up the controller node (a mixin of a lifecycle node)."""

    loops: list[JointLoop]
    files: dict[str, Any]
    feedback_timeout: float
    setpoint_margin: float
    diagnostic_period: float
    active: bool
    _entities: list[Any]
    _watchdog: Any = None
    _state_message: Float64MultiArray

    def _node(self) -> Node:
        assert isinstance(self, Node)
        return self

    def _file_lists(self) -> list[tuple[str, str, str | None]]:
        """Return ``(joint or None, model file, controller file)`` of every joint."""
        files = self.files
        joints = files['joints']
        if not joints:
            return [('', files['model_file'], files['controller_file'] or None)]
        models = list(files['model_files'] or [])
        controllers = list(files['controller_files'] or [])
        if len(models) != len(joints):
            raise ConfigurationError(f'model_files needs one file per joint of joints '
                                     f'({len(joints)}), got {len(models)}')
        if controllers and len(controllers) != len(joints):
            raise ConfigurationError(f'controller_files needs one file per joint of joints '
                                     f'({len(joints)}) or none, got {len(controllers)}')
        if len(set(joints)) != len(joints):
            raise ConfigurationError(f'joint names must be distinct, got {list(joints)}')
        return [(joint, model, (controllers[i] if controllers else '') or None)
                for i, (joint, model) in enumerate(zip(joints, models))]

    def build_loops(self, now_ns: int) -> list[JointLoop]:
        """Load the files and design; declare each joint's parameters; return the loops."""
        node = self._node()
        period = float(node.get_parameter('control_period').value)
        timeout_ns = seconds_to_ns(self.feedback_timeout)
        loops = []
        for joint, model_file, controller_file in self._file_lists():
            model = load_model(model_file)
            spec = controller_for(model, controller_file, period)
            if not joint:
                if not node.has_parameter('joint'):
                    declare(node, 'joint', spec.joint, 'joint name in JointState',
                            read_only=True)
                joint = str(node.get_parameter('joint').value)
            setpoint_range(model.angle_limits, self.setpoint_margin)   # leaves room?
            loops.append(JointLoop(joint, model, spec, timeout_ns, now_ns))
        for loop in loops:
            self._declare_joint(loop, single=len(loops) == 1)
        return loops

    def _declare_joint(self, loop: JointLoop, single: bool) -> None:
        node = self._node()
        for name, default in loop.parameter_defaults().items():
            description, low, high = PARAMETERS[name]
            value = default
            if single:
                # The plain name of a one-joint node, kept in step with the joint's own.
                value = declare(node, name, default, description, low=low, high=high)
                if value is None:
                    value = default
            declare(node, loop.prefix + name, value, f'{loop.joint}: {description}',
                    low=low, high=high)
            if single:
                alias(node, name, loop.prefix + name)
        # Values from the command line or a parameters file go through the same check.
        wanted = [node.get_parameter(loop.prefix + name)
                  for name in loop.parameter_defaults()]
        loop.apply(loop.candidate(wanted))

    def create_interfaces(self) -> None:
        """Create the topics and timers of every joint."""
        node = self._node()
        entities = self._entities
        layout = Float64MultiArray()
        layout.layout.dim = [MultiArrayDimension(label=','.join(CONTROLLER_STATE_LABELS),
                                                 size=len(CONTROLLER_STATE_LABELS),
                                                 stride=len(CONTROLLER_STATE_LABELS))]
        self._state_message = layout
        for loop in self.loops:
            loop.command_pub = node.create_publisher(Float64, f'{loop.joint}/valve_command',
                                                     qos.COMMAND_QOS)
            loop.state_pub = node.create_publisher(Float64MultiArray,
                                                   f'{loop.joint}/controller_state',
                                                   qos.COMMAND_QOS)
            loop.setpoint_sub = node.create_subscription(
                Float64, f'{loop.joint}/setpoint',
                partial(getattr(node, '_on_setpoint'), loop=loop), qos.COMMAND_QOS)
            entities += [loop.command_pub, loop.state_pub, loop.setpoint_sub]
        entities.append(node.create_subscription(JointState, 'joint_states',
                                                 getattr(node, '_on_state'), qos.STATE_QOS))
        entities.append(node.create_subscription(TrajectoryMessage, 'joint_trajectory',
                                                 getattr(node, '_on_trajectory'),
                                                 qos.COMMAND_QOS))
        self._diagnostics_pub = node.create_publisher(DiagnosticArray, '/diagnostics',
                                                      qos.DIAGNOSTICS_QOS)
        entities.append(self._diagnostics_pub)
        self._watchdog = node.create_timer(
            watchdog_period_ns(seconds_to_ns(self.feedback_timeout)) * 1e-9,
            getattr(node, '_on_watchdog'))
        entities.append(node.create_timer(self.diagnostic_period, self.publish_diagnostics))
        entities.append(self._watchdog)

    def publish_diagnostics(self) -> None:
        """Publish one status per joint on ``/diagnostics``."""
        node = self._node()
        now = node.get_clock().now().nanoseconds
        statuses = [joint_health(loop.snapshot(now, self.active)) for loop in self.loops]
        self._diagnostics_pub.publish(diagnostic_array(
            now, node.get_name(), [loop.joint for loop in self.loops], statuses))

    def destroy_interfaces(self) -> None:
        """Destroy the topics and timers, undeclare the joints' parameters."""
        node = self._node()
        for entity in self._entities:
            if hasattr(entity, 'timer_period_ns'):
                node.destroy_timer(entity)
            elif hasattr(entity, 'topic_name') and hasattr(entity, 'publish'):
                node.destroy_publisher(entity)
            else:
                node.destroy_subscription(entity)
        self._entities.clear()
        self._watchdog = None
        single = len(self.loops) == 1
        for loop in self.loops:
            names = [loop.prefix + name for name in loop.parameter_defaults()]
            if single:
                names += list(loop.parameter_defaults())
            unalias(node, names)
            for name in names:
                if node.has_parameter(name):
                    node.undeclare_parameter(name)
        self.loops = []

    @staticmethod
    def parameter_result(successful: bool, reason: str = '') -> SetParametersResult:
        """Return the answer to a set request."""
        return SetParametersResult(successful=successful, reason=reason)
