"""
Replay a bag's JointState and Float64 topics (``ros2 run hydro_sdp bag_player``).

Topics, parameters and lifecycle: docs/interfaces.md section 3.6.

"""

from __future__ import annotations

from pathlib import Path
import time
from typing import Unpack

from hydro_sdp.bags import EmptyBagError, FLOAT64, JOINT_STATE, raw_messages
from hydro_sdp.ros.conversions import fill_stamp
from hydro_sdp.ros.node_options import NodeOptions
from hydro_sdp.ros.parameters.node_parameters import NodeParameters
from hydro_sdp.ros.parameters.player import PLAYER_PARAMETERS
from hydro_sdp.ros.runner import run_node
from rclpy.node import Node
from rclpy.publisher import Publisher
from rosgraph_msgs.msg import Clock  # type: ignore[import-untyped, unused-ignore]
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

TYPES = {JOINT_STATE: JointState, FLOAT64: Float64}


class BagPlayerNode(Node):
    """Publish a bag's JointState and Float64 topics."""

    def __init__(self, *, node_name: str = 'bag_player', **kwargs: Unpack[NodeOptions]) -> None:
        super().__init__(node_name, **kwargs)
        self.parameters = NodeParameters(self, PLAYER_PARAMETERS)
        self.parameters.declare()      # refuses a missing bag
        self.parameters.start()
        parameters = self.parameters
        bag = parameters.text('bag')
        self.rate = parameters.double('rate')
        self.publish_clock = parameters.flag('publish_clock')
        self.loop = parameters.flag('loop')
        autostart = parameters.flag('autostart')
        messages = [m for m in raw_messages(Path(bag)) if m[1] in TYPES]
        if not messages:
            raise EmptyBagError(f'{bag}: no JointState or Float64 messages to play')
        messages.sort(key=lambda m: m[2])
        self._messages = messages
        self._topic_pubs: dict[str, Publisher] = {}
        for topic, msgtype, _, _ in messages:
            if topic not in self._topic_pubs:
                # Bag topics are absolute; drop the slash so a namespace still applies.
                self._topic_pubs[topic] = self.create_publisher(TYPES[msgtype],
                                                                topic.lstrip('/'), 100)
        self._clock_pub = self.create_publisher(Clock, '/clock', 10) if self.publish_clock \
            else None
        self.start_ns = messages[0][2]
        self.published = 0
        #: Times the whole bag was played.
        self.loops = 0
        self._started: float | None = None
        self._timer = self.create_timer(0.001, self._on_timer) if autostart else None

    @property
    def finished(self) -> bool:
        """Whether every message has been published."""
        return self.published >= len(self._messages)

    def _publish_next(self) -> str:
        topic, message_type, stamp, raw = self._messages[self.published]
        if self._clock_pub is not None:
            clock = Clock()
            fill_stamp(clock.clock, stamp)
            self._clock_pub.publish(clock)
        self._topic_pubs[topic].publish(raw)
        self.published += 1
        return message_type

    def play_next(self) -> str:
        """Publish the next message alone and return its type (for step-by-step tests)."""
        return self._publish_next()

    def play_until(self, bag_time_ns: int) -> int:
        """Publish every message stamped at or before ``bag_time_ns``."""
        count = 0
        while not self.finished and self._messages[self.published][2] <= bag_time_ns:
            self._publish_next()
            count += 1
        return count

    def _on_timer(self) -> None:
        now = time.monotonic()
        if self._started is None:
            self._started = now
        self.play_until(self.start_ns + int((now - self._started) * self.rate * 1e9))
        if not self.finished:
            return
        self.loops += 1
        if self.loop:
            self.published, self._started = 0, None
            return
        assert self._timer is not None
        self._timer.cancel()
        self.get_logger().info(f'played {len(self._messages)} messages; done')
        # Ends rclpy.spin in main(): the process exits with code 0.
        self.context.try_shutdown()


def main(args: list[str] | None = None) -> None:
    """Run :class:`BagPlayerNode` until shutdown (console script ``bag_player``)."""
    run_node(BagPlayerNode, args)
