"""Thin rclpy nodes around the hydro_sdp core."""
