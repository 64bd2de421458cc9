"""How each body of a scene was built, as data: one record per body, whatever holds the scene.

A scene builds its bodies through a holder's ``add_*`` calls (:class:`~paragym.sim.client.PyBulletSim`,
:class:`~paragym.sim.description.SceneDescription`); the holder keeps each as one of these records, by the
body's name (its ``recipes``). A record can build its body again in any holder (:meth:`build_in`: a PyBullet
world's rebuild, a description's picture), and the exporter (:mod:`paragym.sim.export`) reads what a scene is
from the records' types and fields. Lengths in m, masses in kg, colours RGBA in [0, 1].
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["GROUND", "Heightfield", "Plane", "Recipe", "StaticBody", "StaticGroup", "TreeBody", "Vector", "VisualBody"]

#: a point, direction, quaternion or colour as the scenes' methods take it: a sequence of floats or a 1-D array
Vector = Sequence[float] | np.ndarray


@dataclass(frozen=True, eq=False)
class TreeBody:
    """A multibody of ``links`` (:class:`~paragym.sim.client.LinkSpec`) forming a tree; its base fixed at the
    origin, or a free rigid body of ``base_mass`` > 0 with ``base_shape``."""

    name: str
    links: Sequence[Any]
    base_mass: float
    base_shape: Any
    base_rgba: Vector

    def build_in(self, holder: Any) -> None:
        holder.add_tree_body(self.name, self.links, self.base_mass, self.base_shape, self.base_rgba)


@dataclass(frozen=True, eq=False)
class StaticBody:
    """A fixed part (an obstacle, a base plate): ``shape`` an :mod:`~paragym.sim.obstacles` shape."""

    name: str
    shape: Any
    rgba: Vector

    def build_in(self, holder: Any) -> None:
        holder.add_static(self.name, self.shape, self.rgba)


@dataclass(frozen=True, eq=False)
class StaticGroup:
    """Fixed parts (obstacles) as one body."""

    name: str
    shapes: Sequence[Any]
    rgba: Vector

    def build_in(self, holder: Any) -> None:
        holder.add_static_group(self.name, self.shapes, self.rgba)


@dataclass(frozen=True, eq=False)
class VisualBody:
    """A part that is only drawn: no collision, no mass; at ``position``, turned by the xyzw ``quaternion``."""

    name: str
    shape: Any
    rgba: Vector
    position: Vector
    quaternion: Vector

    def build_in(self, holder: Any) -> None:
        holder.add_visual(self.name, self.shape, self.rgba, self.position, self.quaternion)


@dataclass(frozen=True, eq=False)
class Heightfield:
    """Ground: ``heights`` (rows along y, columns along x) on a grid of ``cell``, its centre at ``position``."""

    name: str
    heights: np.ndarray
    cell: float
    position: Vector
    rgba: Vector

    def build_in(self, holder: Any) -> None:
        holder.add_heightfield(self.name, self.heights, self.cell, self.position, self.rgba)


@dataclass(frozen=True, eq=False)
class Plane:
    """Flat ground: the plane z = 0."""

    name: str
    rgba: Vector

    def build_in(self, holder: Any) -> None:
        holder.add_plane(self.name, self.rgba)


#: any body's record
Recipe = TreeBody | StaticBody | StaticGroup | VisualBody | Heightfield | Plane
#: the records of ground (the scenario's terrain)
GROUND = (Plane, Heightfield)
