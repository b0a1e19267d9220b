"""What every static map is: the :class:`StaticMap` protocol and the kind names (methods 3.5)."""

from __future__ import annotations

from typing import ClassVar, Literal, Protocol, runtime_checkable

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.validation import Document

#: The model file's ``kind``: one static-map family each.
MapKind = Literal['sdp', 'sdp_dz', 'linear', 'pwl', 'poly', 'power_sat']


class StaticMap(Protocol):
    """
    A static map from the delayed valve command to the joint's angular velocity (deg/s).

    Class attributes ``kind`` and ``keys`` name the family and its model-file keys.
    """

    kind: ClassVar[MapKind]
    keys: ClassVar[tuple[str, ...]]

    @property
    def dead_zone(self) -> tuple[float, float] | None:
        """Edges ``(low, high)`` of the zero-speed band, input units, or None."""

    def rate(self, v: FloatArray) -> FloatArray:
        """Angular velocity (deg/s, same shape) for steady commands ``v`` (input units)."""

    def to_mapping(self) -> dict[str, float | list[float]]:
        """Return the model-file keys of this map."""

    @classmethod
    def from_mapping(cls, data: Document) -> StaticMap:
        """Build the map from model-file keys (already checked for presence)."""


@runtime_checkable
class ShiftableMap(Protocol):
    """A map whose dead-zone edges can be moved (wear, new parts)."""

    def shifted(self, shift: tuple[float, float]) -> StaticMap:
        """Return the map with ``shift`` added to its lower and upper edge, input units."""


def check_dead_zone(dead_zone: tuple[float, float]) -> None:
    """Refuse dead-zone edges ``(low, high)`` in the wrong order (:class:`ModelFileError`)."""
    if dead_zone[0] > dead_zone[1]:
        raise ModelFileError(
            f"key 'dead_zone': lower edge {dead_zone[0]} is above upper edge {dead_zone[1]}")


def check_saturation_velocity(saturation_velocity: tuple[float, float]) -> None:
    """Refuse saturation speeds that are not ``[negative, positive]`` deg/s (ModelFileError)."""
    negative, positive = saturation_velocity
    if not negative < 0.0 < positive:
        raise ModelFileError(
            "key 'saturation_velocity': expected [negative, positive] deg/s, "
            f'got [{negative}, {positive}]')


def check_positive_pair(key: str, pair: tuple[float, float]) -> None:
    """Refuse the pair of file key ``key`` unless both values are > 0 (ModelFileError)."""
    if min(pair) <= 0.0:
        raise ModelFileError(f'key {key!r}: both values must be > 0, got {list(pair)}')
