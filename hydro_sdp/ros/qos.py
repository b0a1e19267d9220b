"""Quality-of-service profiles of hydro_sdp's topics, and the publishers' event callbacks."""

from rclpy.event_handler import PublisherEventCallbacks
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
