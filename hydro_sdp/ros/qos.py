"""Quality-of-service profiles of hydro_sdp's topics, and the nodes' QoS event callbacks."""

from weakref import WeakSet

from rclpy.context import Context
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.qos import QoSProfile

#: joint_states: reliable, depth 10 (both reliable and best-effort subscribers can attach).
STATE_QOS = QoSProfile(depth=10)
#: valve commands and set-points: reliable, depth 10.
COMMAND_QOS = QoSProfile(depth=10)
#: identifier estimates: reliable, depth 10.
ESTIMATE_QOS = QoSProfile(depth=10)
#: /diagnostics: reliable, depth 10.
DIAGNOSTICS_QOS = QoSProfile(depth=10)

#: For the nodes' publishers: no QoS event handlers. Each handler is one more entity the
#: executor checks after every wait, before it runs the callback that woke it; a reliable,
#: volatile publisher matches every subscription but a transient-local one, and a mismatch
#: is still reported by the subscription's side. The nodes' subscriptions keep theirs: a
#: best-effort publisher (a sensor driver's joint_states) never reaches a reliable one.
QUIET_PUBLISHER = PublisherEventCallbacks(use_default_callbacks=False)

#: For the subscriptions of nodes that share a context with their publishers only (the
#: in-process harness, :mod:`hydro_sdp.ros.testing`): no QoS event handlers either. Their
#: two handlers each (incompatible QoS, incompatible type) are most of the entities an
#: executor checks per wait there, and every publisher in such a context is one of ours.
QUIET_SUBSCRIPTION = SubscriptionEventCallbacks(use_default_callbacks=False)

#: Contexts whose nodes' subscriptions go without QoS event handlers.
_IN_PROCESS: 'WeakSet[Context]' = WeakSet()


def mark_in_process(context: Context) -> None:
    """Let the subscriptions of the nodes made in ``context`` go without QoS event handlers."""
    _IN_PROCESS.add(context)


def subscription_events(context: Context) -> SubscriptionEventCallbacks | None:
    """Return the event callbacks for a node's subscription in ``context``."""
    return QUIET_SUBSCRIPTION if context in _IN_PROCESS else None
