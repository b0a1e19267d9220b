"""Quality-of-service profiles of hydro_sdp's topics."""

from rclpy.qos import QoSProfile

#: joint_states: reliable, depth 10 (both reliable and best-effort subscribers can attach).
STATE_QOS = QoSProfile(depth=10)
#: valve commands and set-points: reliable, depth 10.
COMMAND_QOS = QoSProfile(depth=10)
#: identifier estimates: reliable, depth 10.
ESTIMATE_QOS = QoSProfile(depth=10)
#: /diagnostics: reliable, depth 10.
DIAGNOSTICS_QOS = QoSProfile(depth=10)
