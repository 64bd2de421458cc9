"""The hybrid hexapod + tripod of paper 002 in PyBullet, built from primitives.

Base, platform A and end-effector platform E are discs; the nine legs are
rods between their joints. In kinematic fidelity the poses come from
:mod:`paragym.mechanisms.hybrid` (the scene is what ``render`` draws).
"""

from __future__ import annotations

import numpy as np

from paragym.mechanisms import hybrid
from paragym.mechanisms.geometry import PartShape, matrix_to_quat
from paragym.sim.client import PyBulletSim
from paragym.sim.obstacles import Cylinder

__all__ = ["HybridScene"]

_LEG_RADIUS = 0.008


def _z_to(d: np.ndarray) -> np.ndarray:
    """Quaternion (x, y, z, w) turning +z onto the unit vector d."""
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, d)
    s, c = np.linalg.norm(axis), float(np.dot(z, d))
    if s < 1e-12:
        return np.array([0.0, 0.0, 0.0, 1.0]) if c > 0 else np.array([1.0, 0.0, 0.0, 0.0])
    half = np.arctan2(s, c) / 2
    return np.append(axis / s * np.sin(half), np.cos(half))


class HybridScene:
    """A PyBullet scene with the hybrid robot, posed by :meth:`set_state`."""

    def __init__(self, geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY, gui: bool = False) -> None:
        g = self.geometry = geometry
        self.sim = PyBulletSim(gui=gui)
        self.sim.add_static("base", Cylinder((0.0, 0.0, -0.005), g.base_radius + 0.02, 0.01), (0.5, 0.5, 0.5, 1))
        self.sim.add_visual("A", PartShape("A", "cylinder", radius=g.platform_radius + 0.015, length=0.01),
                            (0.2, 0.45, 0.8, 1))
        self.sim.add_visual("E", PartShape("E", "cylinder", radius=g.r_te + 0.015, length=0.01), (0.85, 0.7, 0.2, 1))
        self.legs: list[str] = []

    def set_state(self, t_a: np.ndarray, t_e: np.ndarray) -> None:
        """Place platforms and legs for transforms T_A, T_E (4, 4), base frame;
        each leg is a rod from joint to joint."""
        g = self.geometry
        for name, t in (("A", t_a), ("E", t_e)):
            self.sim.place(name, t[:3, 3], matrix_to_quat(t[:3, :3]))
        a = t_a[:3, :3] @ g.platform_joints.T + t_a[:3, 3:4]
        ends = [(g.base_joints[i], a[:, i]) for i in range(6)]
        ta = t_a[:3, :3] @ g.tripod_base.T + t_a[:3, 3:4]
        te = t_e[:3, :3] @ g.tripod_top.T + t_e[:3, 3:4]
        ends += [(ta[:, j], te[:, j]) for j in range(3)]
        for name in self.legs:  # a leg's length changes: its rod is rebuilt (rendering only)
            self.sim.remove(name)
        self.legs = []
        for i, (p, q) in enumerate(ends):
            d = q - p
            length = float(np.linalg.norm(d))
            rgba = (0.3, 0.3, 0.3, 1) if i < 6 else (0.6, 0.2, 0.2, 1)
            self.sim.add_visual(f"leg{i}", Cylinder((0.0, 0.0, 0.0), _LEG_RADIUS, length), rgba, (p + q) / 2,
                                _z_to(d / length))
            self.legs.append(f"leg{i}")

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.0, 0.25), distance=1.1, yaw=35.0, pitch=-20.0)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
