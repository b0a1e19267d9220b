"""MATLAB ``.mat`` files as channels: vectors of one length, timed by the time variable."""

from __future__ import annotations

from collections.abc import Mapping
import os
from pathlib import Path
from typing import TYPE_CHECKING

from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.io.logs.table import Channel
import numpy as np

if TYPE_CHECKING:
    import h5py

#: File name endings read as MATLAB files.
MAT_SUFFIXES = ('.mat',)


def _version(path: Path, source: str) -> int:
    from scipy.io.matlab import matfile_version

    try:
        with open(path, 'rb') as handle:
            major, _ = matfile_version(handle)
    except (ValueError, TypeError, OSError) as error:
        raise DataError(f'{source}: not a MATLAB file ({error})') from None
    return int(major)


def _v5_variables(path: Path, source: str) -> dict[str, object]:
    from scipy.io import loadmat

    try:
        return dict(loadmat(str(path), simplify_cells=True))
    except (ValueError, TypeError, OSError, NotImplementedError) as error:
        raise DataError(f'{source}: not a readable MATLAB file ({error})') from None


def _dataset_values(node: object) -> object:
    from h5py import Dataset

    # A dataset reads whole with [()]; a group (a structure) is no vector.
    return node[()] if isinstance(node, Dataset) else None


class MatTable:
    """
    The numeric vectors of a MATLAB file.

    ``time``: time variable, s; required.
    """

    def __init__(self, path: str | os.PathLike[str], time: str | None, *,
                 time_role: str = '--time') -> None:
        self.source = str(path)
        source = Path(path)
        if not source.is_file():
            raise DataError(f'{self.source}: no such file')
        if time is None:
            raise ConfigurationError(f'{self.source}: a MATLAB file needs its time variable '
                                     f'({time_role})')
        self._hdf5: h5py.File | None = None
        self._variables: dict[str, object] = {}
        if _version(source, self.source) == 2:
            from h5py import File
            try:
                self._hdf5 = File(source, 'r')
            except OSError as error:
                raise DataError(f'{self.source}: not a readable MATLAB 7.3 file ({error})') \
                    from None
        else:
            self._variables = _v5_variables(source, self.source)
        self.t = self._vector(time, time_role)

    def close(self) -> None:
        """Close the file."""
        if self._hdf5 is not None:
            self._hdf5.close()

    def _names(self) -> list[str]:
        if self._hdf5 is not None:
            return sorted(name for name in self._hdf5 if not name.startswith('#'))
        return sorted(name for name in self._variables if not name.startswith('__'))

    def _lookup(self, name: str, role: str) -> object:
        node: object = self._hdf5 if self._hdf5 is not None else self._variables
        for part in name.split('.'):
            try:
                # Structures are dicts (version 5) or h5py groups (7.3): both are mappings.
                if not isinstance(node, Mapping):
                    raise KeyError(part)
                node = node[part]
            except (KeyError, TypeError, IndexError, ValueError):
                shown = ', '.join(self._names()[:20])
                raise DataError(f'{self.source}: variable {name!r} ({role}): no such variable; '
                                f'variables: {shown}') from None
        return node

    def _vector(self, name: str, role: str) -> np.ndarray:
        node = self._lookup(name, role)
        try:
            values = np.asarray(_dataset_values(node) if self._hdf5 is not None else node)
        except (TypeError, ValueError):
            values = np.asarray(None)
        if values.dtype.kind not in 'biuf':
            raise DataError(f'{self.source}: variable {name!r} ({role}): not numeric '
                            f'({values.dtype})')
        if values.ndim > 1 and sorted(values.shape)[-2] != 1:
            shape = 'x'.join(str(n) for n in values.shape)
            raise DataError(f'{self.source}: variable {name!r} ({role}): a {shape} matrix, '
                            'not a vector')
        return values.astype(np.float64).ravel()

    def channel(self, name: str, role: str) -> Channel:
        """Return variable ``name``, timed by the time variable."""
        values = self._vector(name, role)
        if values.size != self.t.size:
            raise DataError(f'{self.source}: variable {name!r} ({role}): {values.size} '
                            f'samples, the time variable has {self.t.size}')
        return Channel(name, self.t, values, f'variable {name!r}')
