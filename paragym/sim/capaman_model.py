"""The CaPaMan in PyBullet, kinematic fidelity.

The fixed plate, the 17 rigid parts of :func:`paragym.mechanisms.capaman.part_shapes`
(per leg two cranks, coupler, connecting bar, slider rail; the movable plate
and the tool rod) and the obstacles. Part poses come from the analytic model;
PyBullet answers clearance and collision for the whole manipulator against
the obstacles (paper 000 insists on the whole manipulator, not the tool
alone). The dynamic fidelity (closed chain under motors) belongs to the
validation module and will be a second builder beside this one.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from paragym.mechanisms import capaman
from paragym.sim.client import PyBulletSim
from paragym.sim.obstacles import Cylinder, Obstacle

__all__ = ["CaPaManScene"]

_LEG_COLORS = ((0.25, 0.45, 0.8, 1.0), (0.25, 0.45, 0.8, 1.0), (0.35, 0.35, 0.4, 1.0),
               (0.35, 0.35, 0.4, 1.0), (0.55, 0.55, 0.6, 1.0))
_PLATE_COLOR = (0.85, 0.7, 0.2, 1.0)
_TOOL_COLOR = (0.15, 0.15, 0.15, 1.0)
_OBSTACLE_COLOR = (0.8, 0.25, 0.25, 1.0)


class CaPaManScene:
    """A PyBullet scene with one kinematic CaPaMan and its obstacles.

    Args:
        geometry: the mechanism's dimensions.
        gui: open the PyBullet GUI.
        clearance_cap: distances beyond this (m) are reported as the cap.
    """

    ROBOT = "capaman"

    def __init__(self, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                 gui: bool = False, clearance_cap: float = 0.05) -> None:
        self.geometry = geometry
        self.clearance_cap = clearance_cap
        self.sim = PyBulletSim(gui=gui)
        g = geometry
        base = Cylinder(center=(0.0, 0.0, -0.005), radius=g.r_f + g.c / 2 + 0.03, height=0.01)
        self.sim.add_static("fixed_plate", base, rgba=(0.6, 0.6, 0.6, 1.0))
        shapes = capaman.part_shapes(g)
        colors = list(_LEG_COLORS) * 3 + [_PLATE_COLOR, _TOOL_COLOR]
        self.sim.add_parts_body(self.ROBOT, shapes, colors)
        self._obstacles: list[str] = []
        self.alpha = g.alpha_home.copy()
        self.tip = np.zeros(3)
        self.set_configuration(self.alpha)

    def set_obstacles(self, obstacles: Sequence[Obstacle]) -> None:
        """Replace the obstacles of the scene."""
        for name in self._obstacles:
            self.sim.remove(name)
        self._obstacles = []
        for i, obstacle in enumerate(obstacles):
            name = f"obstacle{i}"
            self.sim.add_static(name, obstacle, rgba=_OBSTACLE_COLOR)
            self._obstacles.append(name)

    def set_configuration(self, alpha: Sequence[float]) -> np.ndarray:
        """Place every part for crank angles ``alpha`` (rad, trusted: the caller
        validated them); returns the tool tip (m)."""
        centres, quats, tip = capaman.part_frames_one(alpha, self.geometry)
        self.sim.set_part_poses(self.ROBOT, centres, quats)
        self.alpha = np.array(alpha, dtype=float)
        self.tip = np.array(tip)
        return self.tip

    def clearance(self) -> tuple[float, str | None]:
        """Signed distance (m) from the whole manipulator to the nearest
        obstacle (negative: penetration), capped; and the nearest part."""
        return self.sim.clearance(self.ROBOT, self._obstacles, self.clearance_cap)

    def render(self, width: int = 480, height: int = 360, yaw: float = 45.0, pitch: float = -25.0,
               distance: float = 0.9) -> np.ndarray:
        """RGB image of the scene (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.0, 0.1), distance=distance, yaw=yaw, pitch=pitch)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
