"""The controller node's ``joint_trajectory`` input: trajectories taken, refused, and followed."""

from __future__ import annotations

from hydro_sdp.core.control.trajectory import (
    check_trajectory, check_trajectory_speeds, start_time, TrajectorySampler)
from hydro_sdp.core.errors import DataError
from hydro_sdp.ros.conversions import trajectory_from_message, TrajectoryMessage
from hydro_sdp.ros.joint_loop import JointLoop


class TrajectoryFollower:
    """
    The trajectories of the joints of one controller.

    ``loops``: the controller's joints.
    """

    def __init__(self, loops: list[JointLoop]) -> None:
        self._loops = {loop.joint: loop for loop in loops}
        self.sampler = TrajectorySampler(dict.fromkeys(self._loops, 0.0))

    def take(self, message: TrajectoryMessage, now: float, margin: float,
             active: bool) -> None:
        """
        Follow a trajectory from its start on, for the joints it names.

        ``message``: the trajectory, in rad.
        ``now``: the node clock's reading, s.
        ``margin``: set-point margin inside the end stops, deg.
        Raises DataError naming every reason it is refused (nothing changes then): a message that
        is not a valid trajectory, a joint not controlled, a position beyond the end stops less
        ``margin``, the controller not active, a named joint without feedback yet, a set-point
        faster than a joint's identified top speed.
        """
        trajectory, stamp = trajectory_from_message(message)
        check_trajectory(trajectory, {joint: loop.model.angle_limits
                                      for joint, loop in self._loops.items()}, margin)
        loops = [self._loops[name] for name in trajectory.joint_names]
        waiting = [loop.joint for loop in loops if loop.setpoint is None and not loop.following]
        if not active or waiting:
            raise DataError('trajectory refused: ' + (
                f"no feedback yet from {', '.join(waiting)}" if active
                else 'the controller is not active'))
        start = start_time(stamp, now)
        sampler = self.sampler
        for loop in loops:
            if not loop.following:
                # Its set-point held until now is the trajectory's anchor (harmless if the
                # trajectory is then refused: a joint not following does not read it).
                assert loop.setpoint is not None
                sampler.hold(loop.joint, loop.setpoint, min(start, now) - 1e-3)
        check_trajectory_speeds(sampler.planned_rates(trajectory, start),
                                {loop.joint: loop.top_speeds for loop in loops})
        for loop in loops:
            if not loop.following:
                loop.following = True
                loop.clamped = False
        sampler.replace(trajectory, start)
        sampler.prune(now - 1.0)

    def setpoint(self, loop: JointLoop, t: float,
                 feedforward: bool) -> tuple[float, float | None]:
        """Return a joint's set-point (deg) at ``t`` (s), and its rate fed forward."""
        sampler = self.sampler
        setpoint = sampler.setpoint(loop.joint, t)
        if not feedforward:
            return setpoint, None
        return setpoint, sampler.feedforward(loop.joint, t, loop.spec.control_period,
                                             loop.spec.delay_samples)
