"""The mobile tripod of paper 004 in PyBullet, built from primitives: the
terrain as a heightfield, three drive units, the legs and the plate, posed
from the drive's true state (the scene is what ``render`` draws)."""

from __future__ import annotations

import numpy as np
import pybullet as pb

from paragym.mechanisms import mobile_tripod as mt
from paragym.sim.client import PyBulletSim
from paragym.sim.tripod_drive import Terrain

__all__ = ["TripodScene"]


class TripodScene:
    """Terrain (heightfield over 0-22 m x +-4 m), units, legs and plate."""

    def __init__(self, terrain: Terrain, gui: bool = False) -> None:
        self.sim = PyBulletSim(gui=gui)
        c = self.sim.client
        nx, ny, cell = 221, 81, 0.1
        x, y = np.meshgrid(np.arange(nx) * cell - 1.0, np.arange(ny) * cell - 4.0)
        heights = terrain.height(np.stack([x, y], -1))
        shape = pb.createCollisionShape(pb.GEOM_HEIGHTFIELD, meshScale=[cell, cell, 1.0],
                                        heightfieldData=heights.ravel().tolist(), numHeightfieldRows=nx,
                                        numHeightfieldColumns=ny, physicsClientId=c)
        ground = pb.createMultiBody(0, shape, physicsClientId=c)
        mid = (heights.max() + heights.min()) / 2  # PyBullet centres a heightfield on its height range
        pb.resetBasePositionAndOrientation(ground, [(nx - 1) * cell / 2 - 1.0, 0.0, mid], [0, 0, 0, 1],
                                           physicsClientId=c)
        pb.changeVisualShape(ground, -1, rgbaColor=[0.55, 0.6, 0.45, 1], physicsClientId=c)
        self._bodies: list[int] = []
        self._target = np.zeros(3)

    def _rod(self, a: np.ndarray, b: np.ndarray, radius: float, rgba: tuple) -> None:
        c = self.sim.client
        d = b - a
        length = float(np.linalg.norm(d))
        z = np.array([0.0, 0.0, 1.0])
        axis = np.cross(z, d / length)
        s, cos = np.linalg.norm(axis), float(np.dot(z, d / length))
        half = np.arctan2(s, cos) / 2
        q = np.append(axis / max(s, 1e-12) * np.sin(half), np.cos(half))
        vis = pb.createVisualShape(pb.GEOM_CYLINDER, radius=radius, length=length, rgbaColor=rgba, physicsClientId=c)
        self._bodies.append(pb.createMultiBody(0, -1, vis, basePosition=list((a + b) / 2), baseOrientation=list(q),
                                               physicsClientId=c))

    def set_state(self, units: np.ndarray, centre: np.ndarray, rotation: np.ndarray, geometry: mt.TripodGeometry
                  ) -> None:
        """Draw the units (3, 3), and the plate at (centre, rotation) with its legs."""
        c = self.sim.client
        for body in self._bodies:
            pb.removeBody(body, physicsClientId=c)
        self._bodies = []
        a = geometry.alphas
        vertices = centre + (rotation @ (geometry.p / np.sqrt(3) * np.stack([np.cos(a), np.sin(a), np.zeros(3)])).T)
        for k in range(3):
            box = pb.createVisualShape(pb.GEOM_BOX, halfExtents=[0.15, 0.1, 0.08], rgbaColor=[0.2, 0.45, 0.8, 1],
                                       physicsClientId=c)
            self._bodies.append(pb.createMultiBody(0, -1, box, basePosition=list(units[k] + [0, 0, 0.08]),
                                                   physicsClientId=c))
            self._rod(units[k] + [0, 0, 0.08], vertices[k], 0.03, (0.3, 0.3, 0.3, 1))
            self._rod(vertices[k], vertices[(k + 1) % 3], 0.04, (0.85, 0.7, 0.2, 1))
        self._target = centre

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image around the robot (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=tuple(self._target), distance=6.0, yaw=30.0, pitch=-30.0)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
