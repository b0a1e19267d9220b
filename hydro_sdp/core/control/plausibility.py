"""Whether a measured angle can be the joint's: inside its stops, not too fast (methods 4.11)."""

from __future__ import annotations

import math

from hydro_sdp.core.errors import ConfigurationError, DataError

#: Fastest credible change between two samples, as a multiple of the joint's top speed.
SPEED_FACTOR = 2.0
#: Default allowance beyond the stops and on each change, degrees.
FEEDBACK_MARGIN = 1.0


class FeedbackPlausibility:
    """
    Range and speed checks of one joint's measured angle.

    ``angle_limits``: end stops, degrees (None: no range check).
    ``top_speed``: largest speed of the joint either way, deg/s (None: no speed check).
    ``margin``: allowance beyond the stops and on each change, degrees (>= 0).
    """

    def __init__(self, angle_limits: tuple[float, float] | None, top_speed: float | None,
                 margin: float = FEEDBACK_MARGIN) -> None:
        self.angle_limits = angle_limits
        self.top_speed = top_speed
        self.margin = margin
        self._last: tuple[int, float] | None = None

    @property
    def margin(self) -> float:
        """Return the allowance, degrees (settable)."""
        return self._margin

    @margin.setter
    def margin(self, value: float) -> None:
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0):
            raise ConfigurationError(f'feedback_margin must be a finite number >= 0 deg, '
                                     f'got {value!r}')
        self._margin = float(value)

    def reset(self) -> None:
        """Forget the last sample (after a pause: the next one is judged on its range only)."""
        self._last = None

    def check(self, stamp_ns: int, angle: float) -> None:
        """
        Refuse an angle the joint cannot have; remember it if it lies within range.

        ``stamp_ns``: its stamp, ns (after the previous sample's).
        ``angle``: measured angle, degrees (finite).
        Raises DataError naming the angle and the stops, or the change, the time and the top speed.
        """
        margin = self._margin
        limits = self.angle_limits
        if limits is not None and not limits[0] - margin <= angle <= limits[1] + margin:
            raise DataError(f'angle {angle:.6g} deg lies beyond the end stops {list(limits)} '
                            f'by more than feedback_margin {margin:g} deg')
        last, self._last = self._last, (stamp_ns, angle)
        if last is None or self.top_speed is None:
            return
        seconds = max(stamp_ns - last[0], 0) * 1e-9
        allowed = SPEED_FACTOR * self.top_speed * seconds + margin
        change = angle - last[1]
        if abs(change) > allowed:
            raise DataError(f'angle moved {change:+.4g} deg in {seconds:.4g} s: more than '
                            f'{SPEED_FACTOR:g} x its top speed {self.top_speed:.4g} deg/s plus '
                            f'feedback_margin {margin:g} deg')
