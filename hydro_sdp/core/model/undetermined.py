"""A model parameter the data bound but do not pin (key ``undetermined``, methods 13.9)."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Mapping

from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.validation import require_float

#: The dead-zone's edges: bounded by the commands used, and taken by the IDZ.
EDGES = ('dead_zone[0]', 'dead_zone[1]')


@dataclass(frozen=True)
class Undetermined:
    """
    One parameter the data leave within a bound.

    Attributes
    ----------
    parameter : str
        The parameter, by its model-file name (``dead_zone[1]``, ``curvature[0]``).
    motion : float
        Speed at the bound's end where the joint moved, share of its fastest (0: unknown).

    """

    parameter: str
    bound: tuple[float, float]
    reason: str
    record: str = ''
    motion: float = 0.0

    def __post_init__(self) -> None:
        key = f'undetermined.{self.parameter}'
        if not self.parameter or any(c.isspace() for c in self.parameter):
            raise ModelFileError(f"key 'undetermined': expected a parameter name, "
                                 f'got {self.parameter!r}')
        low, high = self.bound
        if math.isnan(low) or math.isnan(high) or not low <= high:
            raise ModelFileError(f"key '{key}.bound': expected [low, high], "
                                 f'got {list(self.bound)}')
        if not (math.isfinite(self.motion) and 0.0 <= self.motion <= 1.0):
            raise ModelFileError(f"key '{key}.motion': expected a share in [0, 1], "
                                 f'got {self.motion}')

    @property
    def is_edge(self) -> bool:
        """Whether this is a dead-zone edge (:data:`EDGES`)."""
        return self.parameter in EDGES

    @property
    def side(self) -> int:
        """Return the side of a dead-zone edge: 0 below rest, 1 above."""
        return EDGES.index(self.parameter)

    @property
    def moving_end(self) -> float:
        """Return the end of the bound where the joint was seen to move."""
        return self.bound[0] if self.side == 0 else self.bound[1]

    def describe(self) -> str:
        """One line for reports: the bound, why, and what to record."""
        line = (f'{self.parameter} is undetermined: the data put it in '
                f'[{self.bound[0]:.4g}, {self.bound[1]:.4g}]; {self.reason}')
        return f'{line}; to pin it, {self.record}' if self.record else line

    def to_mapping(self) -> dict[str, object]:
        """Return the entry under the model file's ``undetermined`` key."""
        return {'bound': [x if math.isfinite(x) else None for x in self.bound],
                'reason': self.reason, 'record': self.record, 'motion': self.motion}

    @classmethod
    def from_mapping(cls, parameter: str, data: object) -> Undetermined:
        """Read one entry of the model file's ``undetermined`` key."""
        key = f'undetermined.{parameter}'
        if not isinstance(data, Mapping):
            raise ModelFileError(f"key '{key}': expected a mapping with bound, reason, record")
        reason, record = data.get('reason', ''), data.get('record', '')
        if not isinstance(reason, str) or not isinstance(record, str):
            raise ModelFileError(f"key '{key}': reason and record must be text")
        motion = data.get('motion', 0.0)
        if not isinstance(motion, (int, float)) or isinstance(motion, bool):
            raise ModelFileError(f"key '{key}.motion': expected a number, got {motion!r}")
        bound = data.get('bound')
        if not isinstance(bound, (list, tuple)) or len(bound) != 2:
            raise ModelFileError(f"key '{key}.bound': expected [low, high], got {bound!r}")
        # An open side (a standard error without end) is null in the file.
        low, high = (open_end if value is None else require_float(value, f'{key}.bound')
                     for value, open_end in zip(bound, (-math.inf, math.inf)))
        return cls(parameter, (low, high), reason, record, float(motion))
