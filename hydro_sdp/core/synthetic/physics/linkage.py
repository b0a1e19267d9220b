"""
Linkage geometry: cylinder length to joint angle, moment arm and gravity force.

The joint pivot O and the cylinder's pivots B (base, at ``base_distance`` a)
and R (rod end, at ``rod_distance`` b) form a triangle; its angle at O is
``gamma = angle + angle_offset`` and the cylinder length is
``L = sqrt(a^2 + b^2 - 2 a b cos(gamma))``. The moment arm of the cylinder
force about O is ``dL/dgamma = a b sin(gamma) / L``, so the joint speed of a
given cylinder speed changes along the stroke.

"""

from __future__ import annotations

import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.synthetic.physics.plant import Joint
import numpy as np

GRAVITY = 9.81
# mm to m.
_MM = 1e-3


class Geometry:
    """Triangle of one joint, in SI units."""

    def __init__(self, joint: Joint) -> None:
        link = joint.linkage
        self.a = link.base_distance * _MM
        self.b = link.rod_distance * _MM
        self.offset = math.radians(link.angle_offset)
        self.min_length = joint.cylinder.min_length * _MM
        self.stroke = joint.cylinder.stroke * _MM
        load = joint.load
        # Gravity moment at the centre-of-mass angle 0, N m.
        self.moment = GRAVITY * (load.mass * load.distance + load.payload * load.payload_distance
                                 ) * _MM
        self.phase = math.radians(load.phase)

    def gamma(self, extension: float) -> float:
        """Triangle angle at the joint pivot, rad, for cylinder extension ``extension`` (m)."""
        length = self.min_length + extension
        cosine = (self.a * self.a + self.b * self.b - length * length) / (2.0 * self.a * self.b)
        return math.acos(min(max(cosine, -1.0), 1.0))

    def angle(self, extension: float) -> float:
        """Joint angle, degrees, at cylinder extension ``extension`` (m from fully retracted)."""
        return math.degrees(self.gamma(extension) - self.offset)

    def angles(self, extensions: FloatArray) -> FloatArray:
        """Joint angles, degrees, at many cylinder extensions (m), as :meth:`angle` does."""
        length = self.min_length + np.asarray(extensions, dtype=np.float64)
        cosine = (self.a * self.a + self.b * self.b - length * length) / (2.0 * self.a * self.b)
        return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)) - self.offset)

    def extension(self, angle: float) -> float:
        """Cylinder extension, m, at joint ``angle`` (degrees), clamped to the stroke."""
        gamma = math.radians(angle) + self.offset
        length = math.sqrt(max(self.a * self.a + self.b * self.b
                               - 2.0 * self.a * self.b * math.cos(gamma), 0.0))
        return min(max(length - self.min_length, 0.0), self.stroke)

    def moment_arm(self, extension: float) -> float:
        """Cylinder speed over joint speed, m/rad (the moment arm of the cylinder force)."""
        length = self.min_length + extension
        return self.a * self.b * math.sin(self.gamma(extension)) / length

    def load_force(self, extension: float) -> float:
        """Cylinder force the gravity load asks for, N, positive when it resists extension."""
        gamma = self.gamma(extension)
        length = self.min_length + extension
        arm = self.a * self.b * math.sin(gamma) / length
        return self.moment * math.cos(gamma - self.offset + self.phase) / arm

    @property
    def angle_limits(self) -> tuple[float, float]:
        """Joint angles at the two stroke ends, degrees (the hard end stops)."""
        return self.angle(0.0), self.angle(self.stroke)
