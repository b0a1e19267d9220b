"""Inverse dead-zone (IDZ) compensation, eq. (7) of West et al. (2018) (methods 5.1-5.3)."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import get_args, Literal

from hydro_sdp.core.errors import ConfigurationError

#: How the IDZ avoids chatter near ``u = 0`` (docs/methods.md section 5.2).
IdzMode = Literal['zero', 'smooth', 'hysteresis']
IDZ_MODES: tuple[IdzMode, ...] = get_args(IdzMode)


def idz_mode(value: object) -> IdzMode:
    """Return ``value`` as an IDZ mode name, or raise."""
    for mode in IDZ_MODES:
        if value == mode:
            return mode
    raise ConfigurationError(f"IDZ mode must be one of {', '.join(IDZ_MODES)}, got {value!r}")


def check_fade(fade: float, mode: str) -> float:
    """Return the fade-in band ``fade`` as a float, or raise if it is invalid for ``mode``."""
    fade = float(fade)
    if not (math.isfinite(fade) and fade >= 0.0):
        raise ConfigurationError(f'IDZ fade-in band must be finite and >= 0, got {fade}')
    if fade > 0.0 and mode != 'zero':
        raise ConfigurationError(f'the IDZ fade-in band ({fade:g}) works with mode zero, '
                                 f'not {mode}: set the fade to 0 or the mode to zero')
    return fade


def smooth_weight(u: float, beta: float) -> float:
    """Return the positive branch's weight in the ``smooth`` mode (Zhou, Wen & Zhang 2006)."""
    # The weights e^{u/eps} / (e^{u/eps} + e^{-u/eps}).
    return 0.5 * (1.0 + math.tanh(u / beta))


class TwoBranchInverse:
    """The anti-chatter modes (docs/methods.md section 5.2) over an inverse's two branches."""

    beta: float
    mode: IdzMode
    rest: float
    fade: float

    def branch_command(self, u: float, side: int) -> float:
        """Return the command of the positive (``side > 0``) or negative branch for ``u``."""
        raise NotImplementedError

    def blended_command(self, u: float) -> float:
        """Return the ``smooth`` mode's blend of the two branches for ``u`` (``beta > 0``)."""
        weight = smooth_weight(u, self.beta)
        return weight * self.branch_command(u, 1) + (1.0 - weight) * self.branch_command(u, -1)

    def command(self, u: float, branch: int = 0) -> tuple[float, int]:
        """
        Valve command for the desired increment ``u``.

        ``u``: desired increment, degrees per control sample.
        ``branch``: branch used last time (-1, 0 or +1); only the hysteresis mode uses it.
        Returns: the command and the branch now in use.
        """
        beta = self.beta
        if self.mode == 'smooth' and beta > 0.0:
            return self.blended_command(u), 0
        if u > beta:
            branch = 1
        elif u < -beta:
            branch = -1
        elif self.mode != 'hysteresis':
            # The paper's eq. (7) (and smooth without a band): rest inside |u| <= beta.
            branch = 0
        if branch == 0:
            return self.rest, 0
        v = self.branch_command(u, branch)
        if self.fade > 0.0:
            # The compensation fades in from rest beyond the band (methods.md 5.2).
            v = self.rest + math.tanh((abs(u) - beta) / self.fade) * (v - self.rest)
        return v, branch


@dataclass(frozen=True)
class InverseDeadZone(TwoBranchInverse):
    """
    Inverse of a dead-zone chord model.

    Parameters
    ----------
    dead_zone : tuple[float, float]
        Edges ``(a3, a6)``, input units.
    slopes : tuple[float, float]
        ``(s_n, s_p)``: angle per control sample per input unit beyond each edge.
    beta : float
        Chatter band, angle per control sample (>= 0).
    mode : str
        ``zero``, ``smooth`` or ``hysteresis``.
    rest : float
        Command that holds the valve closed (inside the dead-zone).
    fade : float
        Fade-in band beyond ``beta``, angle per control sample (0: none; ``zero`` mode).

    """

    dead_zone: tuple[float, float]
    slopes: tuple[float, float]
    beta: float = 0.05
    mode: IdzMode = 'zero'
    rest: float = 0.0
    fade: float = 0.0

    def __post_init__(self) -> None:
        low, high = (float(x) for x in self.dead_zone)
        s_n, s_p = (float(x) for x in self.slopes)
        values = (low, high, s_n, s_p, float(self.beta), float(self.rest))
        if not all(math.isfinite(x) for x in values):
            raise ConfigurationError('IDZ parameters must be finite')
        if low > high:
            raise ConfigurationError(f'IDZ dead-zone edges reversed: [{low}, {high}]')
        if s_n <= 0.0 or s_p <= 0.0:
            raise ConfigurationError(f'IDZ slopes must be > 0, got [{s_n}, {s_p}]')
        if self.beta < 0.0:
            raise ConfigurationError(f'IDZ chatter band beta must be >= 0, got {self.beta}')
        idz_mode(self.mode)
        object.__setattr__(self, 'fade', check_fade(self.fade, self.mode))
        if not low <= self.rest <= high:
            raise ConfigurationError(f'IDZ rest command {self.rest} lies outside the dead-zone '
                                     f'[{low}, {high}]')
        object.__setattr__(self, 'dead_zone', (low, high))
        object.__setattr__(self, 'slopes', (s_n, s_p))

    def _negative(self, u: float) -> float:
        return u / self.slopes[0] + self.dead_zone[0]

    def _positive(self, u: float) -> float:
        return u / self.slopes[1] + self.dead_zone[1]

    def branch_command(self, u: float, side: int) -> float:
        """Return the inverse of one chord for ``u``, floored (capped) at the other edge."""
        if side > 0:
            return max(self._positive(u), self.dead_zone[0])
        return min(self._negative(u), self.dead_zone[1])

    def blended_command(self, u: float) -> float:
        """Return the blend of the two chords' inverses, neither floored (unlike the table's)."""
        weight = smooth_weight(u, self.beta)
        return weight * self._positive(u) + (1.0 - weight) * self._negative(u)

    def increment(self, v: float) -> float:
        """
        Increment the chord model predicts for command ``v`` (the inverse of the IDZ).

        ``v``: valve command, input units.
        Returns: ``q_lin(v)``, angle per control sample.
        """
        low, high = self.dead_zone
        if v < low:
            return self.slopes[0] * (v - low)
        if v > high:
            return self.slopes[1] * (v - high)
        return 0.0
