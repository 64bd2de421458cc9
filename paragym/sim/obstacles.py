"""Static obstacles: vertical cylinders, axis-aligned boxes and vertical capsules (SI units, m).

Both are described by their centre and half sizes so that an environment can
put them in its observation as fixed-length vectors (:meth:`encode`), the
PyBullet layer can build them (:mod:`paragym.sim.client`), and the occupancy
grid of paper 000 (eq 1) can test points against them (:meth:`contains`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Box", "Capsule", "Cylinder", "Obstacle", "ENCODING_SIZE"]

ENCODING_SIZE = 8  # present, kind (0 cylinder, 1 box, 0.5 capsule), centre (3), half sizes (3)


def _vec3(value, name: str) -> tuple[float, float, float]:
    if type(value) is tuple and len(value) == 3 and all(type(v) is float and math.isfinite(v) for v in value):
        return value  # already three finite floats (the ladder's generator makes thousands a second)
    arr = np.asarray(value, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be 3 finite numbers; got {value!r}")
    x, y, z = arr.tolist()
    return x, y, z


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder: ``center`` (m), ``radius`` (m), ``height`` (m)."""

    center: tuple[float, float, float]
    radius: float
    height: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vec3(self.center, "Cylinder.center"))
        if not (self.radius > 0 and self.height > 0):
            raise ValueError(f"Cylinder radius and height must be > 0; got {self.radius}, {self.height}")

    @property
    def half_extents(self) -> tuple[float, float, float]:
        """Half sizes of the bounding box (m)."""
        return (self.radius, self.radius, self.height / 2)

    def contains(self, points: np.ndarray, inflate: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """Which points (..., 3) lie inside, the radius grown by ``inflate[0]``
        and the half height by ``inflate[1]`` (m)."""
        d = points - np.asarray(self.center)
        r = self.radius + inflate[0]
        return (d[..., 0] ** 2 + d[..., 1] ** 2 <= r * r) & (np.abs(d[..., 2]) <= self.height / 2 + inflate[1])

    def encode(self) -> np.ndarray:
        """[present=1, is_box=0, cx, cy, cz, r, r, height/2]."""
        return np.array([1.0, 0.0, *self.center, *self.half_extents])


@dataclass(frozen=True)
class Box:
    """An axis-aligned box: ``center`` and ``half_extents`` (m)."""

    center: tuple[float, float, float]
    half_extents: tuple[float, float, float]

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vec3(self.center, "Box.center"))
        object.__setattr__(self, "half_extents", _vec3(self.half_extents, "Box.half_extents"))
        if min(self.half_extents) <= 0:
            raise ValueError(f"Box.half_extents must be > 0; got {self.half_extents}")

    def contains(self, points: np.ndarray, inflate: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """Which points (..., 3) lie inside, grown by ``inflate[0]`` sideways and
        ``inflate[1]`` vertically (m)."""
        d = np.abs(points - np.asarray(self.center))
        hx, hy, hz = self.half_extents
        return (d[..., 0] <= hx + inflate[0]) & (d[..., 1] <= hy + inflate[0]) & (d[..., 2] <= hz + inflate[1])

    def encode(self) -> np.ndarray:
        """[present=1, is_box=1, cx, cy, cz, hx, hy, hz]."""
        return np.array([1.0, 1.0, *self.center, *self.half_extents])


@dataclass(frozen=True)
class Capsule:
    """A vertical capsule (a post with rounded ends): the points within ``radius`` (m) of the vertical segment
    of length ``height`` (m) centred at ``center`` (m). Its distance to another capsule is closed form, which
    is why the CaPaMan's difficulty ladder stands its obstacles as these
    (:mod:`paragym.sim.capaman_posts`)."""

    center: tuple[float, float, float]
    radius: float
    height: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vec3(self.center, "Capsule.center"))
        if not (self.radius > 0 and self.height >= 0):
            raise ValueError(f"Capsule radius must be > 0 and height >= 0; got {self.radius}, {self.height}")

    @property
    def half_extents(self) -> tuple[float, float, float]:
        """Half sizes of the bounding box (m)."""
        return (self.radius, self.radius, self.height / 2 + self.radius)

    @property
    def top(self) -> float:
        """The highest point (m)."""
        return self.center[2] + self.height / 2 + self.radius

    def contains(self, points: np.ndarray, inflate: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """Which points (..., 3) lie inside, the radius grown by ``inflate[0]`` and the segment's half length by
        ``inflate[1]`` (m)."""
        d = points - np.asarray(self.center)
        half = self.height / 2 + inflate[1]
        dz = np.maximum(np.abs(d[..., 2]) - half, 0.0)
        r = self.radius + inflate[0]
        return d[..., 0] ** 2 + d[..., 1] ** 2 + dz ** 2 <= r * r

    def encode(self) -> np.ndarray:
        """[present=1, kind=0.5, cx, cy, cz, r, r, height/2 + r]."""
        return np.array([1.0, 0.5, *self.center, *self.half_extents])


Obstacle = Cylinder | Box | Capsule
