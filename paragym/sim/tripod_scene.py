"""The mobile tripod of paper 004 in PyBullet, built from primitives: the
terrain as a heightfield, three drive units, the legs and the plate, posed
from the drive's true state (the scene is what ``render`` draws)."""

from __future__ import annotations

import numpy as np

from paragym.mechanisms import tripod as mt
from paragym.sim.client import PyBulletSim
from paragym.sim.obstacles import Box, Cylinder
from paragym.sim.recipes import Vector
from paragym.sim.tripod_drive import Terrain

__all__ = ["TripodScene"]


class TripodScene:
    """Terrain (heightfield over 0-22 m x +-4 m), units, legs and plate."""

    def __init__(self, terrain: Terrain, gui: bool = False) -> None:
        self.sim = PyBulletSim(gui=gui)
        nx, ny, cell = 221, 81, 0.1
        x, y = np.meshgrid(np.arange(nx) * cell - 1.0, np.arange(ny) * cell - 4.0)
        heights = terrain.height(np.stack([x, y], -1))
        mid = (heights.max() + heights.min()) / 2  # PyBullet centres a heightfield on its height range
        self.sim.add_heightfield("ground", heights, cell, ((nx - 1) * cell / 2 - 1.0, 0.0, mid), (0.55, 0.6, 0.45, 1))
        self._bodies: list[str] = []
        self._target = np.zeros(3)

    def _visual(self, shape: Box | Cylinder, rgba: tuple, position: np.ndarray,
                quaternion: Vector = (0.0, 0.0, 0.0, 1.0)) -> None:
        name = f"part{len(self._bodies)}"
        self.sim.add_visual(name, shape, rgba, position, quaternion)
        self._bodies.append(name)

    def _rod(self, a: np.ndarray, b: np.ndarray, radius: float, rgba: tuple) -> None:
        d = b - a
        length = float(np.linalg.norm(d))
        z = np.array([0.0, 0.0, 1.0])
        axis = np.cross(z, d / length)
        s, cos = np.linalg.norm(axis), float(np.dot(z, d / length))
        half = np.arctan2(s, cos) / 2
        q = np.append(axis / max(s, 1e-12) * np.sin(half), np.cos(half))
        self._visual(Cylinder((0.0, 0.0, 0.0), radius, length), rgba, (a + b) / 2, q)

    def set_state(self, units: np.ndarray, centre: np.ndarray, rotation: np.ndarray, geometry: mt.TripodGeometry
                  ) -> None:
        """Draw the units (3, 3), and the plate at (centre, rotation) with its legs."""
        for name in self._bodies:
            self.sim.remove(name)
        self._bodies = []
        a = geometry.alphas
        vertices = centre + (rotation @ (geometry.p / np.sqrt(3) * np.stack([np.cos(a), np.sin(a), np.zeros(3)])).T)
        for k in range(3):
            self._visual(Box((0.0, 0.0, 0.0), (0.15, 0.1, 0.08)), (0.2, 0.45, 0.8, 1), units[k] + [0, 0, 0.08])
            self._rod(units[k] + [0, 0, 0.08], vertices[k], 0.03, (0.3, 0.3, 0.3, 1))
            self._rod(vertices[k], vertices[(k + 1) % 3], 0.04, (0.85, 0.7, 0.2, 1))
        self._target = centre

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image around the robot (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=tuple(self._target), distance=6.0, yaw=30.0, pitch=-30.0)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
