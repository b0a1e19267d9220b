"""Report, as a skip, a run without rclpy, whose ROS tests are left out."""

import pytest


def test_rclpy_is_importable():
    pytest.importorskip('rclpy')
