"""
Record topics into a rosbag2 bag without rosbag2 (``ros2 run hydro_sdp bag_recorder``).

Topics, parameters and lifecycle: docs/interfaces.md section 3.5.

"""

from __future__ import annotations

import sys
import time
from typing import Callable, Mapping, Unpack

from hydro_sdp.bags.live_writer import Sqlite3BagWriter
from hydro_sdp.ros.node_options import NodeOptions
from hydro_sdp.ros.parameters.node_parameters import NodeParameters
from hydro_sdp.ros.parameters.recorder import RECORDER_PARAMETERS
from hydro_sdp.ros.qos import subscription_events
from hydro_sdp.ros.recorded_types import choose_type, message_class
from hydro_sdp.ros.runner import run_node
from rclpy.clock import Clock, ClockType, ROSClock
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.topic_endpoint_info import TopicEndpointInfo

#: Longest a callback may run after its message arrived for the arrival stamp to be used, ns
#: (beyond it, or with a stamp from another clock, the callback's own time is).
LATE_LIMIT = 1_000_000_000


def _seconds(duration: Duration) -> dict[str, int]:
    sec, nsec = divmod(int(duration.nanoseconds), 1_000_000_000)
    return {'sec': sec, 'nsec': nsec}


def qos_text(endpoints: list[TopicEndpointInfo]) -> str:
    """Return the publishers' QoS as rosbag2 stores it with metadata version 8 (YAML text)."""
    import yaml

    profiles = [{
        'history': int(q.history), 'depth': int(q.depth), 'reliability': int(q.reliability),
        'durability': int(q.durability), 'deadline': _seconds(q.deadline),
        'lifespan': _seconds(q.lifespan), 'liveliness': int(q.liveliness),
        'liveliness_lease_duration': _seconds(q.liveliness_lease_duration),
        'avoid_ros_namespace_conventions': bool(q.avoid_ros_namespace_conventions),
    } for q in (e.qos_profile for e in endpoints)]
    return yaml.safe_dump(profiles, sort_keys=False).strip() if profiles else ''


class BagRecorderNode(Node):
    """Write chosen topics to a new bag, each with its advertised type."""

    def __init__(self, *, node_name: str = 'bag_recorder', **kwargs: Unpack[NodeOptions]) -> None:
        super().__init__(node_name, **kwargs)
        self.parameters = NodeParameters(self, RECORDER_PARAMETERS)
        self.parameters.declare()      # refuses a missing output, a storage not sqlite3
        self.parameters.start()
        parameters = self.parameters
        output = parameters.text('output')
        flush_period = parameters.double('flush_period')
        discovery_period = parameters.double('discovery_period')
        joints = parameters.texts('joint_names') or []
        topics = parameters.texts('topics') or ['joint_states'] + [
            f'{joint}/{topic}' for joint in joints for topic in ('valve_command', 'setpoint')]
        self.closed = False
        # Refuses an existing output before anything is subscribed.
        self._writer = Sqlite3BagWriter(output, flush_period=flush_period)
        self.output = self._writer.folder
        from rosbags.typesys import get_typestore, Stores
        self._typestore = get_typestore(Stores.ROS2_JAZZY)
        self._ids: dict[str, int] = {}
        self.recorded: dict[str, str] = {}     # topic -> type
        self._last_stamp: dict[str, int] = {}
        self._waiting = {self.resolve_topic_name(t) for t in topics}
        self._said: set[str] = set()
        self._announced = False
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._flush_timer = self.create_timer(flush_period, self._flush, clock=steady)
        self._discovery_timer = self.create_timer(discovery_period, self._discover,
                                                  clock=steady)
        self._discover()
        waiting = f"; waiting for {', '.join(sorted(self._waiting))} to be advertised" \
            if self._waiting else ''
        self.get_logger().info(
            f'recording to {self.output} (committed every {flush_period:g} s): '
            f"{', '.join(f'{t} ({m})' for t, m in self.recorded.items()) or 'nothing yet'}"
            f'{waiting}')
        self._announced = True

    @property
    def messages(self) -> int:
        """Messages written so far (committed or not)."""
        return self._writer.message_count

    @property
    def waiting(self) -> set[str]:
        """Topics asked for that nobody has advertised yet."""
        return set(self._waiting)

    def _discover(self) -> None:
        if self.closed or not self._waiting:
            return
        advertised = dict(self.get_topic_names_and_types())
        for topic in sorted(self._waiting & advertised.keys()):
            msgtype, problem = choose_type(topic, advertised[topic])
            if problem and problem not in self._said:
                self._said.add(problem)      # once: the graph is read again every period
                log = self.get_logger()
                (log.warning if msgtype else log.error)(problem)
            if msgtype is None:
                continue
            self._waiting.discard(topic)
            try:
                self._subscribe(topic, msgtype)
            except (ImportError, AttributeError) as error:
                self.get_logger().error(f'cannot record {topic}: type {msgtype} is not '
                                        f'available here ({error})')
        if not self._waiting:
            self._discovery_timer.cancel()

    def _subscribe(self, topic: str, msgtype: str) -> None:
        cls = message_class(msgtype)
        publishers = self.get_publishers_info_by_topic(topic)
        qos = QoSProfile(depth=100)
        if any(p.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT for p in publishers):
            qos.reliability = ReliabilityPolicy.BEST_EFFORT    # a reliable reader would miss them
        msgdef, digest = '', ''
        if msgtype in self._typestore.fielddefs:
            msgdef, _ = self._typestore.generate_msgdef(msgtype, ros_version=2)
            digest = self._typestore.hash_rihs01(msgtype)
        self._ids[topic] = self._writer.add_topic(topic, msgtype, msgdef=msgdef,
                                                  type_hash=digest,
                                                  offered_qos_profiles=qos_text(publishers))
        self.recorded[topic] = msgtype
        # rclpy hands a callback of two parameters the message info too (Subscription's
        # callback setter); its annotation names only the one-parameter form.
        self.create_subscription(cls, topic, self._recorder_for(topic),  # type: ignore[arg-type]
                                 qos, raw=True,
                                 event_callbacks=subscription_events(self.context))
        if self._announced:
            self.get_logger().info(f'now recording {topic} ({msgtype})')

    def _recorder_for(self, topic: str) -> Callable[[bytes, Mapping[str, int]], None]:
        return lambda raw, info: self._on_message(topic, raw, info)

    def _on_message(self, topic: str, raw: bytes, info: Mapping[str, int]) -> None:
        if self.closed:
            return
        clock = self.get_clock()
        now = clock.now().nanoseconds
        # Stamped when the middleware received the message, not when this callback ran:
        # on a busy machine the callback runs tens of ms late, and a command stamped that
        # late moves every step it starts against the samples of the joint it drove. On
        # simulated time the clock does not run while the callback waits: nothing to undo.
        late = time.time_ns() - int(info.get('received_timestamp', 0) or 0)
        simulated = isinstance(clock, ROSClock) and clock.ros_time_is_active
        stamp = now - late if 0 <= late < LATE_LIMIT and not simulated else now
        # Arrival stamps of one topic can come out of order by a few ms across the
        # middleware's transports; a topic's stamps stay in the order its messages came.
        stamp = max(stamp, self._last_stamp.get(topic, stamp - 1) + 1)
        self._last_stamp[topic] = stamp
        self._writer.write(self._ids[topic], stamp, raw)

    def _flush(self) -> None:
        if not self.closed:
            self._writer.flush()

    def close(self) -> None:
        """Commit the last messages and write ``metadata.yaml``."""
        if self.closed:
            return
        self.closed = True
        summary = self._writer.close()
        counts = ', '.join(f'{t.name} {t.count}' for t in summary.topics) or 'no topics'
        never = f"; never advertised: {', '.join(sorted(self._waiting))}" \
            if self._waiting else ''
        text = f'wrote {summary.count} messages to {self.output} ({counts}){never}'
        if self.context.ok():
            self.get_logger().info(text)
        else:
            # After Ctrl-C the context is down and the logger could not reach /rosout.
            sys.stderr.write(f'[INFO] [{self.get_name()}]: {text}\n')

    def destroy_node(self) -> None:
        """Finish the bag, then destroy the node."""
        self.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Run :class:`BagRecorderNode` until shutdown (console script ``bag_recorder``)."""
    run_node(BagRecorderNode, args)
