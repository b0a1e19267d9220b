"""Scenarios run through the ROS nodes in-process, for the demo and for users' checks."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Mapping, Sequence

from hydro_sdp.ros import qos
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.identifier_node import IdentifierNode
from hydro_sdp.ros.parameters.spec import ParameterValue
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, RosHarness
import numpy as np
from rclpy.parameter import Parameter
from std_msgs.msg import Float64


@dataclass(frozen=True, eq=False)
class WearRun:
    """
    A set-point sequence through the three nodes while the valve wears.

    Attributes
    ----------
    angle, setpoint : numpy.ndarray
        True joint angle and set-point, degrees.
    command : numpy.ndarray
        Valve command the controller sent, V.
    edges : numpy.ndarray
        ``(samples, 2)`` IDZ edges the controller used, V.
    drift_time : float
        When the dead-zone moved, s.
    recalibration_times : tuple of float
        When the accepted updates were requested, s.

    """

    t: np.ndarray
    angle: np.ndarray
    setpoint: np.ndarray
    command: np.ndarray
    edges: np.ndarray
    drift_time: float
    recalibrations: int
    recalibration_times: tuple[float, ...] = ()

    @property
    def time_to_recalibration(self) -> float:
        """Return the time from the drift to the first update after it, s (inf: none)."""
        after = [t for t in self.recalibration_times if t >= self.drift_time]
        return min(after) - self.drift_time if after else math.inf


def wear_and_recalibration(*, holds: int = 20, steps: int = 400, drift_at: int = 5,
                           shift: Sequence[float] = (0.3, -0.3), seed: int = 1,
                           levels: Sequence[float] = (20.0, 35.0, 15.0, 30.0),
                           noise_std: float = 0.01,
                           identifier: Mapping[str, ParameterValue] | None = None) -> WearRun:
    """
    Track set-points while the plant's dead-zone moves; the identifier recalibrates.

    ``holds``: number of set-points, each held ``steps`` plant samples (0.01 s).
    ``steps``: samples per set-point.
    ``drift_at``: set-point at whose start the dead-zone edges move by ``shift``.
    ``shift``: movement of the lower and upper edge, V.
    ``levels``: set-points, degrees, used in turn.
    ``noise_std``: angle measurement noise of the plant, and the identifier's ``noise_std``, deg.
    ``identifier``: more identifier parameters (``significance``, ``cooldown``...).
    """
    rows = []
    with RosHarness() as ros:
        # Only the controller answers parameter requests: the identifier recalibrates it
        # through them. The plant is worn through its own set_parameters.
        plant = ros.add(PlantNode, parameters={'noise_std': noise_std, 'seed': seed},
                        services=False)
        controller = ros.add(PipControllerNode)
        identifier_node = ros.add(IdentifierNode, parameters={
            'auto_recalibrate': True, 'noise_std': noise_std, **(identifier or {})},
            services=False)
        helper = ros.helper('scenario_setpoints')
        publisher = helper.create_publisher(Float64, 'j2/setpoint', 10,
                                            event_callbacks=qos.QUIET_PUBLISHER)
        loop = Lockstep(ros, plant, controllers=[controller], observers=[identifier_node])
        ros.spin_until(lambda: publisher.get_subscription_count() >= 1)
        for hold in range(holds):
            if hold == drift_at:
                plant.set_parameters([Parameter('dead_zone_shift', value=list(shift))])
            level = levels[hold % len(levels)]
            count = controller.setpoints_received
            publisher.publish(Float64(data=math.radians(level)))
            ros.spin_until(lambda: controller.setpoints_received > count)
            for _ in range(steps):
                loop.step()
                rows.append((loop.steps * plant.sample_period, plant.last_angles[0], level,
                             controller.last_command,
                             *controller.controller.settings.idz.dead_zone))
        recalibrations = identifier_node.recalibrations
        times = tuple(identifier_node.recalibration_times)
    table = np.array(rows)
    return WearRun(t=table[:, 0], angle=table[:, 1], setpoint=table[:, 2],
                   command=table[:, 3], edges=table[:, 4:6],
                   drift_time=drift_at * steps * 0.01, recalibrations=recalibrations,
                   recalibration_times=times)
