"""
Thin rclpy nodes around the hydro_sdp core.

Only this package imports rclpy. Each node turns messages and parameters into
calls of a core object and publishes the result; the maths lives in
:mod:`hydro_sdp.core`.

"""
