"""The planar 2PRR + table of paper 003 in PyBullet, built from primitives
(kinematic fidelity: the analytic model places the sliders, links and table;
the scene is what ``render`` draws)."""

from __future__ import annotations

import numpy as np

from paragym.mechanisms import orthoglide as og
from paragym.sim.client import PyBulletSim
from paragym.sim.obstacles import Box

__all__ = ["OrthoglideScene"]


class OrthoglideScene:
    """Guides, sliders, the two links, the table and the path, posed by :meth:`set_state`."""

    def __init__(self, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY, gui: bool = False) -> None:
        self.geometry = g = geometry
        self.sim = PyBulletSim(gui=gui)
        self.sim.add_static("guide_x", Box((g.slider2_origin + 0.75, -0.03, -0.01), (0.85, 0.01, 0.01)),
                            (0.4, 0.4, 0.4, 1))
        self.sim.add_static("guide_y", Box((-0.03, g.slider3_origin + 0.75, -0.01), (0.01, 0.85, 0.01)),
                            (0.4, 0.4, 0.4, 1))
        self._bodies: list[str] = []

    def _box(self, centre: np.ndarray, half: tuple[float, float, float], yaw: float, rgba: tuple) -> None:
        name = f"part{len(self._bodies)}"
        self.sim.add_visual(name, Box((0.0, 0.0, 0.0), half), rgba, centre,
                            (0.0, 0.0, float(np.sin(yaw / 2)), float(np.cos(yaw / 2))))
        self._bodies.append(name)

    def set_state(self, rho: np.ndarray, path: np.ndarray) -> None:
        """Draw the mechanism at rho (3,) and the path (K, 2, table frame)."""
        g = self.geometry
        for name in self._bodies:
            self.sim.remove(name)
        self._bodies = []
        d = g.direction
        origin = np.asarray(g.table_origin) + rho[0] * d
        self._box(np.append(origin + [0.1, 0.55], -0.03), (0.55, 0.55, 0.01), float(np.arctan2(d[1], d[0])),
                  (0.75, 0.75, 0.6, 1))
        a = np.array([g.slider2_origin + rho[1], 0.0])
        b = np.array([0.0, g.slider3_origin + rho[2]])
        tool = og.forward(rho[None], g)[0] + origin
        self._box(np.append(a, 0.0), (0.05, 0.03, 0.02), 0.0, (0.2, 0.45, 0.8, 1))
        self._box(np.append(b, 0.0), (0.03, 0.05, 0.02), 0.0, (0.2, 0.45, 0.8, 1))
        for p in (a, b):
            mid, v = (p + tool) / 2, tool - p
            self._box(np.append(mid, 0.03), (float(np.linalg.norm(v)) / 2, 0.012, 0.008),
                      float(np.arctan2(v[1], v[0])), (0.3, 0.3, 0.3, 1))
        for q in path[::40]:
            self._box(np.append(origin + q, -0.015), (0.006, 0.006, 0.004), 0.0, (0.8, 0.2, 0.2, 1))

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image from above (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.05, 0.0), distance=3.0, yaw=0.0, pitch=-89.0)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
