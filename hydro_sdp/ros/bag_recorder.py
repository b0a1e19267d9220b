"""
Record topics into a rosbag2 bag without rosbag2 (``ros2 run hydro_sdp bag_recorder``).

Subscribes to the chosen topics as serialised messages and writes them with
``rosbags``, stamped with the node's clock at receipt (simulated time when
``use_sim_time`` is set). The bag is built under a temporary name and moved
to ``output`` when the node shuts down, so a crash leaves no partial bag where
``identify`` or ``diagnose`` would read it.

"""

from __future__ import annotations

from contextlib import ExitStack
from pathlib import Path
from typing import Any

from hydro_sdp.bags import STORAGES
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.files import atomic_directory
from hydro_sdp.ros.params import declare
from hydro_sdp.ros.runner import run_node
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

TYPES = {'sensor_msgs/msg/JointState': JointState, 'std_msgs/msg/Float64': Float64}


def topic_type(topic: str) -> str:
    """Return the message type hydro_sdp records on ``topic``: JointState or Float64."""
    return 'sensor_msgs/msg/JointState' if topic.rstrip('/').endswith('joint_states') \
        else 'std_msgs/msg/Float64'


class BagRecorderNode(Node):
    """
    Write chosen topics to a bag (``joint_states`` as JointState, others as Float64).

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : Any
        Forwarded to :class:`rclpy.node.Node`.

    """

    def __init__(self, *, node_name: str = 'bag_recorder', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import get_typestore, Stores

        output = declare(self, 'output', '', 'bag folder to write (required)', read_only=True)
        topics = declare(self, 'topics', Parameter.Type.STRING_ARRAY,
                         'topics to record (default: joint_states and every valve_command '
                         'and setpoint of the joints in joint_names)', read_only=True)
        joints = declare(self, 'joint_names', ['j2'], 'joints whose command and set-point '
                         'topics are recorded by default', read_only=True)
        storage = declare(self, 'storage', 'sqlite3', f"storage: {', '.join(STORAGES)}",
                          read_only=True)
        if not output:
            raise ConfigurationError("parameter 'output' (the bag folder) is required")
        if storage not in STORAGES:
            raise ConfigurationError(f"parameter 'storage' must be one of "
                                     f"{', '.join(STORAGES)}, got {storage!r}")
        if not topics:
            topics = ['joint_states'] + [f'{j}/{t}' for j in joints
                                         for t in ('valve_command', 'setpoint')]
        self.output = Path(output)
        self.messages = 0
        self.closed = False
        self._stack = ExitStack()
        building = self._stack.enter_context(atomic_directory(self.output))
        plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
        self._writer = self._stack.enter_context(Writer(building, version=8,
                                                        storage_plugin=plugin))
        typestore = get_typestore(Stores.ROS2_JAZZY)
        self._recorded = []
        for topic in topics:
            msgtype = topic_type(topic)
            subscription = self.create_subscription(
                TYPES[msgtype], topic, lambda raw, t=topic: self._on_message(t, raw), 100,
                raw=True)
            name = subscription.topic_name
            connection = self._writer.add_connection(name, msgtype, typestore=typestore)
            self._recorded.append((subscription, connection))
        self._connections = {topic: connection for topic, (_, connection) in
                             zip(topics, self._recorded)}

    def _on_message(self, topic: str, raw: bytes) -> None:
        if self.closed:
            return
        self._writer.write(self._connections[topic], self.get_clock().now().nanoseconds, raw)
        self.messages += 1

    def close(self) -> None:
        """Finish the bag and move it into place."""
        if not self.closed:
            self.closed = True
            self._stack.close()

    def destroy_node(self) -> None:
        """Finish the bag, then destroy the node."""
        self.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Run :class:`BagRecorderNode` until shutdown (console script ``bag_recorder``)."""
    run_node(BagRecorderNode, args)
