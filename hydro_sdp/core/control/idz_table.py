"""The identified map's own inverse as the IDZ: a monotone table (methods 5.4-5.5)."""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Sequence

from hydro_sdp.core.control.idz import (
    check_fade, idz_mode, IdzMode, InverseDeadZone, TwoBranchInverse)
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.static_maps import CHORD_SPEED_FRACTION
import numpy as np


@dataclass(frozen=True)
class TableInverseDeadZone(TwoBranchInverse):
    """
    Inverse of a monotone speed map given as a table.

    Parameters
    ----------
    u : tuple[float, ...]
        Increments, degrees per control sample: negative, then 0 at one or two
        points (the dead-zone edges), then positive; increasing on each branch.
    v : tuple[float, ...]
        Valve commands of the increments, input units, strictly increasing.
    beta : float
        Chatter band, degrees per control sample (>= 0).
    mode : str
        ``zero``, ``smooth`` or ``hysteresis``.
    rest : float
        Command that holds the valve closed: between the edges.
    fade : float
        Fade-in band beyond ``beta``, degrees per control sample (0: none; ``zero`` mode).

    """

    u: tuple[float, ...]
    v: tuple[float, ...]
    beta: float = 0.05
    mode: IdzMode = 'zero'
    rest: float = 0.0
    fade: float = 0.0
    _negative_u: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _negative_v: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _positive_u: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _positive_v: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        u = tuple(float(x) for x in self.u)
        v = tuple(float(x) for x in self.v)
        if len(u) != len(v) or len(u) < 3:
            raise ConfigurationError('the IDZ table needs u and v of equal length, at least 3')
        if not all(math.isfinite(x) for x in u + v + (float(self.beta), float(self.rest))):
            raise ConfigurationError('IDZ table values must be finite')
        if any(b <= a for a, b in zip(v, v[1:])):
            raise ConfigurationError('the IDZ table commands v must increase strictly')
        zeros = [i for i, x in enumerate(u) if x == 0.0]
        if not zeros or len(zeros) > 2 or zeros[-1] - zeros[0] != len(zeros) - 1:
            raise ConfigurationError('the IDZ table needs u = 0 at one point or at two '
                                     'neighbouring points (the dead-zone edges)')
        first, last = zeros[0], zeros[-1]
        if first == 0 or last == len(u) - 1:
            raise ConfigurationError('the IDZ table needs increments of both signs')
        if any(b <= a for a, b in zip(u[:first + 1], u[1:first + 1])) or \
                any(b <= a for a, b in zip(u[last:], u[last + 1:])):
            raise ConfigurationError('the IDZ table increments u must increase strictly on '
                                     'each side of the dead-zone')
        if self.beta < 0.0:
            raise ConfigurationError(f'IDZ chatter band beta must be >= 0, got {self.beta}')
        idz_mode(self.mode)
        object.__setattr__(self, 'fade', check_fade(self.fade, self.mode))
        if not v[first] <= self.rest <= v[last]:
            raise ConfigurationError(f'IDZ rest command {self.rest} lies outside the dead-zone '
                                     f'[{v[first]}, {v[last]}]')
        object.__setattr__(self, 'u', u)
        object.__setattr__(self, 'v', v)
        object.__setattr__(self, '_negative_u', u[:first + 1])
        object.__setattr__(self, '_negative_v', v[:first + 1])
        object.__setattr__(self, '_positive_u', u[last:])
        object.__setattr__(self, '_positive_v', v[last:])

    @classmethod
    def from_branches(cls, negative: tuple[Sequence[float], Sequence[float]],
                      positive: tuple[Sequence[float], Sequence[float]], *,
                      beta: float = 0.05, mode: IdzMode = 'zero',
                      rest: float = 0.0, fade: float = 0.0) -> TableInverseDeadZone:
        """Build the table from two branches, each ``(u, v)`` from its outer end to its edge."""
        nu, nv = (tuple(float(x) for x in side) for side in negative)
        pu, pv = (tuple(float(x) for x in side) for side in positive)
        if not (nu and pu and nu[-1] == 0.0 and pu[0] == 0.0):
            raise ConfigurationError('each IDZ table branch must reach u = 0 at its edge')
        if nv[-1] == pv[0]:
            pu, pv = pu[1:], pv[1:]
        return cls(nu + pu, nv + pv, beta=beta, mode=mode, rest=rest, fade=fade)

    @property
    def dead_zone(self) -> tuple[float, float]:
        """Edges ``(a3, a6)``: the commands where the increments leave 0, input units."""
        return self._negative_v[-1], self._positive_v[0]

    @property
    def u_range(self) -> tuple[float, float]:
        """Largest increments the table gives, degrees per control sample."""
        return self.u[0], self.u[-1]

    @property
    def slopes(self) -> tuple[float, float]:
        """Chord slope of each branch, degrees per control sample per input unit."""
        low, high = self.dead_zone
        target = CHORD_SPEED_FRACTION * self.u[0]
        reach = float(np.interp(target, self._negative_u, self._negative_v))
        negative = target / (reach - low)
        target = CHORD_SPEED_FRACTION * self.u[-1]
        reach = float(np.interp(target, self._positive_u, self._positive_v))
        return negative, target / (reach - high)

    def _positive(self, u: float) -> float:
        us, vs = self._positive_u, self._positive_v
        if u >= 0.0:
            return float(np.interp(u, us, vs))
        # The first segment continued, floored at the other edge (as the chord IDZ).
        return max(vs[0] + u * (vs[1] - vs[0]) / (us[1] - us[0]), self.dead_zone[0])

    def _negative(self, u: float) -> float:
        us, vs = self._negative_u, self._negative_v
        if u <= 0.0:
            return float(np.interp(u, us, vs))
        return min(vs[-1] + u * (vs[-1] - vs[-2]) / (us[-1] - us[-2]), self.dead_zone[1])

    def branch_command(self, u: float, side: int) -> float:
        """Return the command of the positive (``side > 0``) or negative branch for ``u``."""
        return self._positive(u) if side > 0 else self._negative(u)

    def increment(self, v: float) -> float:
        """
        Increment the map gives for command ``v`` (the inverse of :meth:`command`).

        ``v``: valve command, input units.
        Returns: degrees per control sample; 0 on the dead-zone, the end values beyond the table.
        """
        return float(np.interp(v, self.v, self.u))

    def with_edges(self, edges: tuple[float, float]) -> TableInverseDeadZone:
        """
        Return the table with its edges moved to ``edges``: each branch shifts with its edge.

        ``edges``: new ``(a3, a6)``, input units.
        """
        low, high = (float(x) for x in edges)
        if not (math.isfinite(low) and math.isfinite(high)):
            raise ConfigurationError('IDZ edges must be finite')
        if low > high:
            raise ConfigurationError(f'IDZ dead-zone edges reversed: [{low}, {high}]')
        shift_n, shift_p = low - self.dead_zone[0], high - self.dead_zone[1]
        return TableInverseDeadZone.from_branches(
            (self._negative_u, [x + shift_n for x in self._negative_v]),
            (self._positive_u, [x + shift_p for x in self._positive_v]),
            beta=self.beta, mode=self.mode, rest=self.rest, fade=self.fade)

    def with_slopes(self, slopes: tuple[float, float]) -> TableInverseDeadZone:
        """
        Return the table with each branch's increments scaled to the chord slopes ``slopes``.

        ``slopes``: new :attr:`slopes`, degrees per control sample per input unit (> 0).
        """
        new_n, new_p = (float(x) for x in slopes)
        if not (new_n > 0.0 and new_p > 0.0 and math.isfinite(new_n) and math.isfinite(new_p)):
            raise ConfigurationError(f'IDZ slopes must be finite and > 0, got [{new_n}, {new_p}]')
        old_n, old_p = self.slopes
        return TableInverseDeadZone.from_branches(
            ([x * new_n / old_n for x in self._negative_u], self._negative_v),
            ([x * new_p / old_p for x in self._positive_u], self._positive_v),
            beta=self.beta, mode=self.mode, rest=self.rest, fade=self.fade)


#: An inverse dead-zone of either form.
Idz = InverseDeadZone | TableInverseDeadZone


def chord_as_table(idz: InverseDeadZone, v_range: tuple[float, float]) -> TableInverseDeadZone:
    """Return the chord IDZ as a table of two points per branch over ``v_range`` (input units)."""
    low, high = idz.dead_zone
    if not v_range[0] < low <= high < v_range[1]:
        raise ConfigurationError(f'the command range {list(v_range)} must contain the IDZ '
                                 f'edges [{low}, {high}]')
    return TableInverseDeadZone.from_branches(
        ((idz.increment(v_range[0]), 0.0), (v_range[0], low)),
        ((0.0, idz.increment(v_range[1])), (high, v_range[1])),
        beta=idz.beta, mode=idz.mode, rest=idz.rest, fade=idz.fade)
