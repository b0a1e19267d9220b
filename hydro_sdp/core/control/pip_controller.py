"""The runtime PIP-IDZ controller, used offline and inside the ROS node (methods 4.7)."""

from __future__ import annotations

from dataclasses import dataclass, replace
import math

from hydro_sdp.core.control.idz_table import Idz, TableInverseDeadZone
from hydro_sdp.core.control.pip_design import PipGains
from hydro_sdp.core.errors import ConfigurationError, DataError


def _check_limits(limits: tuple[float, float] | None, name: str) -> tuple[float, float] | None:
    if limits is None:
        return None
    low, high = (float(x) for x in limits)
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ConfigurationError(f'{name} must be two finite numbers, low < high; '
                                 f'got {list(limits)}')
    return low, high


@dataclass(frozen=True)
class ControllerSettings:
    """
    Everything a PIP-IDZ controller needs at run time.

    Attributes
    ----------
    idz : InverseDeadZone, TableInverseDeadZone or None
        Inverse dead-zone, chord or table; ``None`` sends ``u`` to the valve unchanged.
    u_limits : tuple[float, float] or None
        Limits of the linear controller's output (angle per control sample).
    v_limits : tuple[float, float] or None
        Range of the valve command (input units).

    """

    gains: PipGains
    idz: Idz | None = None
    u_limits: tuple[float, float] | None = None
    v_limits: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, 'u_limits', _check_limits(self.u_limits, 'u_limits'))
        object.__setattr__(self, 'v_limits', _check_limits(self.v_limits, 'v_limits'))
        if self.v_limits is not None and self.idz is not None:
            low, high = self.v_limits
            if not low <= self.idz.rest <= high:
                raise ConfigurationError(f'the IDZ rest command {self.idz.rest} lies outside '
                                         f'the valve range {list(self.v_limits)}')


class PipIdzController:
    """Incremental PIP controller with inverse dead-zone, limits and anti-windup."""

    def __init__(self, settings: ControllerSettings) -> None:
        self.settings = settings
        self._n = len(settings.gains.f)
        self._m = len(settings.gains.g) + 1
        self._y: list[float] = []       # y_k, y_{k-1}, ..., newest first (n + 1 values)
        self._u: list[float] = []       # u_{k-1}, u_{k-2}, ..., newest first (m values)
        self._branch = 0
        self._d: list[float] = []       # d_{k-1}, d_{k-2}, ..., newest first (feed-forward only)
        self._d_steps = -1              # value of ``steps`` when ``_d`` was last written
        self.last_u = 0.0
        self.last_v = settings.idz.rest if settings.idz is not None else 0.0
        self.steps = 0

    def reset(self, y: float | None = None, u: float = 0.0) -> None:
        """
        Forget the history; the next step starts bumplessly from ``y`` and ``u``.

        ``y``: angle to assume as the past output; ``None`` takes the next measurement.
        ``u``: increment to assume as the past input (0: valve at rest).
        """
        self._y = [] if y is None else [float(y)] * (self._n + 1)
        self._u = [float(u)] * self._m
        self._branch = 0
        self._d = []
        self.last_u = float(u)

    def step(self, setpoint: float, y: float,
             feedforward: float | None = None) -> tuple[float, float]:
        """
        Compute one control sample.

        ``setpoint``: desired angle ``d_k``, degrees.
        ``y``: measured angle ``y_k``, degrees.
        ``feedforward``: set-point increment ``w_k``, degrees per control sample, ``tau`` samples
        ahead (methods 4.9); ``None``: the plain PIP law.
        Returns: ``(u, v)``: the increment applied (angle per control sample) and the valve command
        (input units), always finite and inside their limits.
        Raises DataError if ``setpoint``, ``y`` or ``feedforward`` is not finite; the state is left
        unchanged.
        """
        if feedforward is not None:
            return self._step_feedforward(float(setpoint), float(y), float(feedforward))
        if not (math.isfinite(setpoint) and math.isfinite(y)):
            raise DataError(f'set-point and angle must be finite, got {setpoint} and {y}')
        ys = [float(y)] + (self._y[:self._n] if self._y else [float(y)] * self._n)
        us = self._u if self._u else [0.0] * self._m
        u, v, branch = self._limited(self._law(setpoint, y, ys, us))
        self._commit(ys, [u] + us[:self._m - 1], u, v, branch)
        return u, v

    def _step_feedforward(self, setpoint: float, y: float,
                          feedforward: float) -> tuple[float, float]:
        """:meth:`step` with a feed-forward: the law on the deviation from the set-point."""
        if not (math.isfinite(setpoint) and math.isfinite(y) and math.isfinite(feedforward)):
            raise DataError(f'set-point, angle and feed-forward must be finite, got {setpoint}, '
                            f'{y} and {feedforward}')
        ys = [y] + (self._y[:self._n] if self._y else [y] * self._n)
        # Past set-points kept by feed-forward steps only; after a plain step or a reset
        # the set-point is taken as having stood still (bumpless, as for y).
        fresh = self._d and self._d_steps == self.steps
        ds = [setpoint] + (self._d[:self._n] if fresh else [setpoint] * self._n)
        us = self._u if self._u else [0.0] * self._m
        own = self._law(setpoint, y, ys, us, ds)
        wanted = own + feedforward
        u, v, branch = self._limited(wanted)
        # The history keeps the controller's own part, not the feed-forward (the law would
        # integrate it). When the limits cut the command, that part is kept no further
        # beyond the limit than the applied command itself (as without feed-forward), nor
        # than the full back-calculation ``u - feedforward``: it neither winds up nor is
        # pushed against the motion by a feed-forward the valve cannot deliver.
        if wanted > u:
            own = min(own, max(u - feedforward, u))
        elif wanted < u:
            own = max(own, min(u - feedforward, u))
        self._commit(ys, [own] + us[:self._m - 1], u, v, branch)
        self._d = ds[:self._n]
        self._d_steps = self.steps
        return u, v

    def _law(self, setpoint: float, y: float, ys: list[float], us: list[float],
             ds: list[float] | None = None) -> float:
        """Return the PIP increment ``u`` before limits."""
        gains = self.settings.gains
        u = us[0] + gains.k_i * (setpoint - y)
        for j, g_j in enumerate(gains.g, start=1):
            u -= g_j * (us[j - 1] - us[j])
        for i, f_i in enumerate(gains.f):
            change = ys[i] - ys[i + 1]
            u -= f_i * (change if ds is None else change - (ds[i] - ds[i + 1]))
        return u

    def _limited(self, u: float) -> tuple[float, float, int]:
        """Apply the ``u`` limits, the IDZ and the valve limits: ``(u, v, branch)``."""
        if not math.isfinite(u):
            raise DataError('the controller output is not finite (gains or inputs too large)')
        settings = self.settings
        if settings.u_limits is not None:
            u = min(max(u, settings.u_limits[0]), settings.u_limits[1])
        if isinstance(settings.idz, TableInverseDeadZone):
            # Beyond its ends the table holds the end commands: keep what the valve gives.
            u = min(max(u, settings.idz.u_range[0]), settings.idz.u_range[1])
        if settings.idz is not None:
            v, branch = settings.idz.command(u, self._branch)
        else:
            v, branch = u, 0
        if settings.v_limits is not None:
            limited = min(max(v, settings.v_limits[0]), settings.v_limits[1])
            if limited != v:
                # Store the increment the valve can really give, not the one asked for.
                u = settings.idz.increment(limited) if settings.idz is not None else limited
                v = limited
        return u, v, branch

    def _commit(self, ys: list[float], us: list[float], u: float, v: float,
                branch: int) -> None:
        """Keep the new histories and outputs once the step can no longer fail."""
        self._branch = branch
        self._y = ys[:self._n + 1]
        self._u = us
        self.last_u, self.last_v = u, v
        self.steps += 1

    def pending(self, delay: int) -> float:
        """Return the increments issued that the angle cannot show yet, degrees."""
        return float(sum(self._u[:max(delay - 1, 0)]))

    def update_idz(self, idz: Idz) -> None:
        """Change the IDZ at run time without a jump in the valve command."""
        settings = replace(self.settings, idz=idz)  # validates against the valve range
        old = self.settings.idz
        if old is not None and self._u and self._branch != 0:
            self._u = [idz.increment(old.command(u, self._branch)[0]) for u in self._u]
            self.last_u = self._u[0]
        self.settings = settings

    def update_gains(self, gains: PipGains) -> None:
        """Change the PIP gains (same orders); the incremental form makes this bumpless."""
        if len(gains.f) != self._n or len(gains.g) != self._m - 1:
            raise ConfigurationError(f'new gains must keep {self._n} f and {self._m - 1} g '
                                     'coefficients')
        self.settings = replace(self.settings, gains=gains)
