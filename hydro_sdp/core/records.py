"""
Records: aligned samples of one joint (time, command, angle).

A :class:`Record` is what a bag becomes once a joint and its command topic are
chosen: ``t`` in seconds, ``v`` in the command's own units (volts, percent
duty...) and ``y`` in degrees, one entry per angle sample.

"""

from __future__ import annotations

from dataclasses import dataclass

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
import numpy as np


@dataclass(frozen=True, eq=False)
class Record:
    """
    Time series of one joint's command and angle.

    Parameters
    ----------
    t : FloatArray
        Sample times, s, strictly increasing.
    v : FloatArray
        Command applied at each sample (held until the next), input units.
    y : FloatArray
        Measured angle at each sample, degrees.
    joint : str
        Joint name.
    source : str
        Where the record came from (a bag path), for messages.

    """

    t: FloatArray
    v: FloatArray
    y: FloatArray
    joint: str = ''
    source: str = ''

    def __post_init__(self) -> None:
        arrays = {}
        for name in ('t', 'v', 'y'):
            values = np.asarray(getattr(self, name), dtype=np.float64)
            if values.ndim != 1:
                raise DataError(f'{self._label()}: {name} must be 1-D, got shape {values.shape}')
            arrays[name] = values
            object.__setattr__(self, name, values)
        lengths = {name: values.size for name, values in arrays.items()}
        if len(set(lengths.values())) != 1:
            raise DataError(f'{self._label()}: lengths differ (t, v, y: '
                            f"{lengths['t']}, {lengths['v']}, {lengths['y']})")
        for name, what in (('t', 'time'), ('v', 'command'), ('y', 'angle')):
            bad = np.flatnonzero(~np.isfinite(arrays[name]))
            if bad.size:
                raise DataError(f'{self._label()}: {bad.size} {what} samples are NaN or '
                                f'infinite (first at sample {bad[0]})')
        steps = np.diff(arrays['t'])
        backwards = np.flatnonzero(steps <= 0.0)
        if backwards.size:
            k = int(backwards[0])
            kind = 'repeat' if steps[k] == 0.0 else 'go backwards'
            raise DataError(f'{self._label()}: time stamps {kind} at sample {k + 1} '
                            f'(t = {arrays["t"][k + 1]:.6f} s), {backwards.size} times in all')

    def _label(self) -> str:
        parts = [part for part in (self.source, self.joint and f'joint {self.joint}') if part]
        return ' '.join(parts) or 'record'

    def __len__(self) -> int:
        """Return the number of samples."""
        return int(self.t.size)

    @property
    def sample_period(self) -> float:
        """Median spacing of the time stamps, s."""
        if self.t.size < 2:
            raise DataError(f'{self._label()}: needs at least two samples for a sample period')
        return float(np.median(np.diff(self.t)))

    @property
    def duration(self) -> float:
        """Time from the first to the last sample, s."""
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0

    def window(self, start: int, stop: int) -> Record:
        """Return samples ``start:stop`` as a new record."""
        return Record(self.t[start:stop], self.v[start:stop], self.y[start:stop],
                      self.joint, self.source)
