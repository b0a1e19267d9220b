"""ASAM MDF4 files (``.mf4``) as channels, each on its own channel group's time base."""

from __future__ import annotations

from contextlib import contextmanager
import logging
import os
from pathlib import Path
from typing import Iterator, TYPE_CHECKING

from hydro_sdp.core.errors import DataError
from hydro_sdp.io.logs.table import Channel
import numpy as np

if TYPE_CHECKING:
    import asammdf

#: File name endings read as MDF.
MDF_SUFFIXES = ('.mf4', '.mdf')


@contextmanager
def _quiet() -> Iterator[None]:
    """Keep asammdf's own log lines off the terminal: its errors become ours, one line."""
    logger = logging.getLogger('asammdf')
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        logger.setLevel(level)


class MdfTable:
    """
    The channels of an MDF4 file.

    ``time``: a channel whose values are the time of its group's channels, s (default: each group's
    master channel).
    """

    def __init__(self, path: str | os.PathLike[str], time: str | None = None, *,
                 time_role: str = '--time') -> None:
        from asammdf import MDF

        self.source = str(path)
        if not Path(path).is_file():
            raise DataError(f'{self.source}: no such file')
        try:
            with _quiet():
                self._mdf: asammdf.MDF = MDF(str(path))
        except Exception as error:  # noqa: B902 - asammdf raises anything on a bad file
            raise DataError(f'{self.source}: not an MDF file ({error})') from None
        self._time: tuple[int, np.ndarray] | None = None
        masters = self._mdf.masters_db
        if time is not None and not all(masters.get(group) == index for group, index in
                                        self._mdf.channels_db.get(time, ((-1, -1),))):
            # A data channel holding the time; the masters are the default anyway.
            group, index = self._locate(time, time_role)
            self._time = (group, self._numbers(time, group, index, time_role))

    def close(self) -> None:
        """Close the file."""
        self._mdf.close()

    def _locate(self, name: str, role: str) -> tuple[int, int]:
        places = list(self._mdf.channels_db.get(name, ()))
        if not places:
            names = sorted(n for n in self._mdf.channels_db if n not in ('time', 't'))
            shown = ', '.join(names[:20]) + (', ...' if len(names) > 20 else '')
            raise DataError(f'{self.source}: channel {name!r} ({role}): no such channel; '
                            f'channels: {shown}')
        if len({group for group, _ in places}) > 1:
            groups = ', '.join(str(group) for group, _ in places)
            raise DataError(f'{self.source}: channel {name!r} ({role}): in several channel '
                            f'groups ({groups}); rename it in the logger')
        return places[0]

    def _numbers(self, name: str, group: int, index: int, role: str) -> np.ndarray:
        with _quiet():
            signal = self._mdf.get(name, group=group, index=index)
        samples = np.asarray(signal.samples)
        if samples.dtype.kind not in 'biuf' or samples.ndim != 1:
            raise DataError(f'{self.source}: channel {name!r} ({role}): not a numeric '
                            f'signal ({samples.dtype}, shape {samples.shape})')
        return samples.astype(np.float64)

    def channel(self, name: str, role: str) -> Channel:
        """Return channel ``name`` with its own timestamps (or the ``time`` channel's)."""
        group, index = self._locate(name, role)
        values = self._numbers(name, group, index, role)
        label = f'channel {name!r}'
        if self._time is None:
            with _quiet():
                t = np.asarray(self._mdf.get(name, group=group, index=index).timestamps,
                               dtype=np.float64)
            return Channel(name, t, values, label)
        time_group, t = self._time
        if group != time_group:
            raise DataError(f'{self.source}: {label} ({role}): in channel group {group}, the '
                            f'time channel in group {time_group}; leave the time out to use '
                            "each group's own")
        return Channel(name, t, values, label)
