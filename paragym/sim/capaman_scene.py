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
from paragym.mechanisms.geometry import matrix_to_quat, quat_to_matrix
from paragym.sim.client import LinkSpec, PyBulletSim
from paragym.sim.obstacles import Cylinder, Obstacle
from paragym.sim.recipes import Vector

__all__ = ["CaPaManScene", "capaman_links"]

_LEG_COLORS = ((0.25, 0.45, 0.8, 1.0), (0.25, 0.45, 0.8, 1.0), (0.35, 0.35, 0.4, 1.0),
               (0.35, 0.35, 0.4, 1.0), (0.55, 0.55, 0.6, 1.0))
_PLATE_COLOR = (0.85, 0.7, 0.2, 1.0)
_TOOL_COLOR = (0.15, 0.15, 0.15, 1.0)
_OBSTACLE_COLOR = (0.8, 0.25, 0.25, 1.0)
_SWEEP_MARGIN = 0.02  # m, on top of the swept boxes' own margin


def capaman_links(geometry: capaman.CaPaManGeometry) -> list[LinkSpec]:
    """The CaPaMan's kinematic tree, cut open at the ball joints.

    Per leg k (F0 = columns w_k, z, u_k): the two cranks turn about w_k at
    the frame's pivots ``r_f e_k -/+ (c/2) u_k`` (joint value -alpha_k); the
    coupler hangs on crank a's tip (joint +alpha_k, so it stays horizontal:
    the parallelogram); bar and rail are fixed to the coupler. The plate
    floats on three prismatic joints and a spherical one, placed by the
    closed-form direct kinematics; the tool is fixed under it. Link frames
    equal the frames of :func:`paragym.mechanisms.capaman.part_frames` (a test
    checks it), with cranks and coupler shifted to their joint axes.
    """
    g = geometry
    shapes = {s.name: s for s in capaman.part_shapes(g)}
    zhat = np.array([0.0, 0.0, 1.0])
    rel_bar = tuple(matrix_to_quat(np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]], float)))
    rel_rail = tuple(matrix_to_quat(np.array([[0, 0, 1], [0, -1, 0], [1, 0, 0]], float)))
    links: list[LinkSpec] = []
    for k in range(3):
        e, u, w = g.e[k], g.u[k], g.w[k]
        f0 = tuple(matrix_to_quat(np.column_stack([w, zhat, u])))
        leg = f"leg{k + 1}"
        for sign, crank in ((-1.0, "crank_a"), (1.0, "crank_b")):
            pivot = tuple(g.r_f * e + sign * (g.c / 2) * u)
            links.append(LinkSpec(f"{leg}_{crank}", None, "revolute", pivot, f0, (1.0, 0.0, 0.0),
                                  shapes[f"{leg}_{crank}"], (0.0, 0.0, g.a / 2), _LEG_COLORS[0]))
        links.append(LinkSpec(f"{leg}_coupler", f"{leg}_crank_a", "revolute", (0.0, 0.0, g.a),
                              axis=(1.0, 0.0, 0.0), shape=shapes[f"{leg}_coupler"],
                              shape_offset=(0.0, 0.0, g.c / 2), rgba=_LEG_COLORS[2]))
        links.append(LinkSpec(f"{leg}_bar", f"{leg}_coupler", "fixed", (0.0, g.h / 2, g.c / 2), rel_bar,
                              shape=shapes[f"{leg}_bar"], rgba=_LEG_COLORS[3]))
        links.append(LinkSpec(f"{leg}_rail", f"{leg}_coupler", "fixed", (0.0, g.h, g.c / 2), rel_rail,
                              shape=shapes[f"{leg}_rail"], rgba=_LEG_COLORS[4]))
    links += [
        LinkSpec("plate_x", None, "prismatic", axis=(1.0, 0.0, 0.0)),
        LinkSpec("plate_y", "plate_x", "prismatic", axis=(0.0, 1.0, 0.0)),
        LinkSpec("plate_z", "plate_y", "prismatic", axis=(0.0, 0.0, 1.0)),
        LinkSpec("plate", "plate_z", "spherical", shape=shapes["plate"], rgba=_PLATE_COLOR),
        LinkSpec("tool", "plate", "fixed", (0.0, 0.0, -g.tool_length / 2), shape=shapes["tool"],
                 rgba=_TOOL_COLOR),
    ]
    return links


class CaPaManScene:
    """A PyBullet scene with one kinematic CaPaMan and its obstacles.

    Args:
        geometry: the mechanism's dimensions.
        gui: open the PyBullet GUI.
        clearance_cap: distances beyond this (m) are reported as the cap.
        draws: build visual shapes (False: a scene that is never drawn, such as a checker of scenarios,
            builds its obstacles at every reset in about half the time; :class:`~paragym.sim.client.PyBulletSim`).
    """

    ROBOT = "capaman"

    def __init__(self, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                 gui: bool = False, clearance_cap: float = 0.05, draws: bool = True) -> None:
        self.geometry = geometry
        self.clearance_cap = clearance_cap
        self.sim = PyBulletSim(gui=gui, draws=draws)
        g = geometry
        base = Cylinder(center=(0.0, 0.0, -0.005), radius=g.r_f + g.c / 2 + 0.03, height=0.01)
        self.sim.add_static("fixed_plate", base, rgba=(0.6, 0.6, 0.6, 1.0))
        self.sim.add_tree_body(self.ROBOT, capaman_links(g))
        idx = lambda link: self.sim.link_index(self.ROBOT, link)  # noqa: E731
        self._legs = [(idx(f"leg{k}_crank_a"), idx(f"leg{k}_crank_b"), idx(f"leg{k}_coupler")) for k in (1, 2, 3)]
        self._joints = [j for leg in self._legs for j in leg] + [
            idx("plate_x"), idx("plate_y"), idx("plate_z"), idx("plate")]
        self._obstacles: list[str] = []
        self._query_links: list[int] = []
        self.obstacles: tuple[Obstacle, ...] = ()
        self.alpha = g.alpha_home.copy()
        self.tip = np.zeros(3)
        self._kinematics = capaman.kernel_consts(g)
        self.set_configuration(self.alpha)

    def set_obstacles(self, obstacles: Sequence[Obstacle]) -> None:
        """Replace the obstacles of the scene (kept as they are when unchanged)."""
        obstacles = tuple(obstacles)
        if obstacles == self.obstacles:
            return
        self.obstacles = obstacles
        for name in self._obstacles:
            self.sim.remove(name)  # rebuilds the world (PyBullet frees nothing else): pose the mechanism again
        if self._obstacles:
            self.set_configuration(self.alpha)
        self._obstacles = []
        if obstacles:
            self.sim.add_static_group("obstacles", obstacles, rgba=_OBSTACLE_COLOR)
            self._obstacles.append("obstacles")
        # Parts that cannot come within the cap anywhere in the joint range are
        # left out of the clearance query: the answer is the same, sooner.
        lo = np.min([np.subtract(o.center, o.half_extents) for o in obstacles], axis=0) if obstacles else 0
        hi = np.max([np.add(o.center, o.half_extents) for o in obstacles], axis=0) if obstacles else 0
        s_lo, s_hi = capaman.swept_part_boxes(self.geometry, 9)
        gap = np.linalg.norm(np.maximum(0.0, np.maximum(lo - s_hi, s_lo - hi)), axis=1)
        names = [p.name for p in capaman.part_shapes(self.geometry)]
        self._query_links = [self.sim.link_index(self.ROBOT, names[i])
                             for i in np.flatnonzero(gap <= self.clearance_cap + _SWEEP_MARGIN)]

    def set_configuration(self, alpha: Vector) -> np.ndarray:
        """Place every part for crank angles ``alpha`` (rad, trusted: the caller
        validated them); returns the tool tip (m)."""
        a1, a2, a3 = (float(a) for a in alpha)
        hx, hy, hz, x, y, z, w, _, tx, ty, tz, ok = capaman.k_forward(a1, a2, a3, self._kinematics)
        if not ok:
            raise ValueError("alpha gives no real plate yaw: the configuration is not assemblable")
        values = [[-a1], [-a1], [a1], [-a2], [-a2], [a2], [-a3], [-a3], [a3], [hx], [hy], [hz], [x, y, z, w]]
        self.sim.set_joints(self.ROBOT, self._joints, values)
        self.alpha = np.array((a1, a2, a3))
        self.tip = np.array((tx, ty, tz))
        return self.tip

    def part_frame(self, part: str) -> tuple[np.ndarray, np.ndarray]:
        """World centre (m) and xyzw quaternion of a part as PyBullet holds it."""
        pos, quat = self.sim.link_frame(self.ROBOT, part)
        offset = {"crank_a": self.geometry.a / 2, "crank_b": self.geometry.a / 2,
                  "coupler": self.geometry.c / 2}.get(part.split("_", 1)[-1], 0.0)
        rot = quat_to_matrix(quat)
        return pos + offset * rot[:, 2], quat

    def clearance(self) -> tuple[float, str | None]:
        """Signed distance (m) from the whole manipulator to the nearest
        obstacle (negative: penetration), capped; and the nearest part."""
        return self.sim.clearance(self.ROBOT, self._obstacles, self.clearance_cap, self._query_links)

    def render(self, width: int = 480, height: int = 360, yaw: float = 45.0, pitch: float = -25.0,
               distance: float = 0.9) -> np.ndarray:
        """RGB image of the scene (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.0, 0.1), distance=distance, yaw=yaw, pitch=pitch)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
