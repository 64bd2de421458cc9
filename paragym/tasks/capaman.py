"""Scenarios of the CaPaMan collision-free task (paper 000, section 4).

One module for the env, the vector env, the planners and the CLI.

A scenario is the obstacles plus the task configurations T.C.1..3 (tool-tip
positions) and their task points T.P.1..3 in the joint space (crank angles
from the inverse kinematics). The tour is T.C.1 -> T.C.2 -> T.C.3 -> T.C.1.

* ``paper_scenario()``: the paper's case as a fixed scenario: a vertical
  cylinder standing on the fixed plate under the movable plate, the three
  T.C.s close around it, so that straight joint-space motion between them
  collides (tested). The paper gives no sizes; these are assumptions.
* ``random_scenario(rng)``: seeded random obstacles (cylinders and boxes on
  the fixed plate, below the movable plate) and T.P.s, generated feasible:
  every T.P. collision-free with a margin (PyBullet), and all three in one
  connected free component of the joint matrix Theta (paper 000's collision
  map on a joint grid, colliding cells grown by one), so a collision-free
  tour exists at that resolution (the tests follow one with a planner).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from scipy import ndimage

from paragym.mechanisms import capaman
from paragym.sim import capaman_grid
from paragym.sim.capaman_scene import CaPaManScene
from paragym.sim.obstacles import Box, Cylinder, Obstacle
from paragym.tasks import base
from paragym.units import DEG

__all__ = ["CaPaManScenario", "draw_scenarios", "paper_scenario", "random_scenario", "resolve_scenario",
           "validate_scenario", "MAX_OBSTACLES", "SCENARIOS", "TOUR"]

SCENARIOS = ("paper", "random")

MAX_OBSTACLES = 3
TOUR = (1, 2, 0)  # indices of the T.C.s visited after starting at T.C.1 (index 0)


@dataclass(frozen=True)
class CaPaManScenario:
    """Obstacles and task of one CaPaMan episode (frozen; SI units).

    Attributes:
        name: "paper", "random" or a user label.
        obstacles: up to ``MAX_OBSTACLES`` cylinders/boxes.
        task_points: T.P.1..3, crank angles (3, 3) rad, as nested tuples.
        task_configs: T.C.1..3, tool-tip positions (3, 3) m.
        seed: the seed that generated it (random scenarios), else None.
    """

    name: str
    obstacles: tuple[Obstacle, ...]
    task_points: tuple[tuple[float, float, float], ...]
    task_configs: tuple[tuple[float, float, float], ...] = field(default=())
    seed: int | None = None

    @classmethod
    def from_tool_tips(cls, tips: Sequence[Sequence[float]], obstacles: Sequence[Obstacle],
                       name: str = "custom", geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY
                       ) -> CaPaManScenario:
        """Build a scenario from three tool-tip positions (m); the task points
        come from the inverse kinematics (``ValueError`` if unreachable)."""
        tips_arr = np.asarray(tips, float)
        if tips_arr.shape != (3, 3):
            raise ValueError(f"tips must be three 3-D points, shape (3, 3); got {tips_arr.shape}")
        alpha = capaman.inverse_tool_tip(tips_arr, geometry)
        return cls(name, tuple(obstacles), _tuples(alpha), _tuples(tips_arr))

    @property
    def alpha(self) -> np.ndarray:
        """Task points as an array (3, 3), rad."""
        return np.array(self.task_points)


def _tuples(a: np.ndarray) -> tuple[tuple[float, float, float], ...]:
    return tuple(tuple(float(v) for v in row) for row in np.asarray(a))


@lru_cache(maxsize=8)
def paper_scenario(geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY) -> CaPaManScenario:
    """The paper's case (section 4, Fig 3a), with assumed sizes.

    A cylinder of radius 15 mm and height 100 mm stands at the centre of the
    fixed plate; T.C.1..3 put the tool tip 35 mm from its axis at 90, 210 and
    330 deg, 50 mm above the fixed plate (inside the paper's 6 cm circle).
    """
    obstacle = Cylinder(center=(0.0, 0.0, 0.05), radius=0.015, height=0.10)
    ang = np.radians([90.0, 210.0, 330.0])
    tips = np.column_stack([0.035 * np.cos(ang), 0.035 * np.sin(ang), np.full(3, 0.05)])
    return CaPaManScenario.from_tool_tips(tips, [obstacle], name="paper", geometry=geometry)


def validate_scenario(scenario: CaPaManScenario, scene: CaPaManScene) -> None:
    """Raise ``ValueError`` if the scenario is malformed, a task point is out
    of range, or the manipulator collides at a task configuration
    (PyBullet's exact check). Leaves the scene's obstacles set."""
    base.resolve_scenario(scenario, (), CaPaManScenario)
    if not 1 <= len(scenario.obstacles) <= MAX_OBSTACLES:
        raise ValueError(f"a scenario has 1 to {MAX_OBSTACLES} obstacles; got {len(scenario.obstacles)}")
    alpha = capaman.check_joint_angles(scenario.alpha, scene.geometry, name="scenario.task_points")
    if alpha.shape != (3, 3):
        raise ValueError(f"scenario.task_points must be three configurations; got {alpha.shape}")
    scene.set_obstacles(scenario.obstacles)
    for i, a in enumerate(alpha):
        scene.set_configuration(a)
        d, part = scene.clearance()
        if d <= 0.0:
            raise ValueError(f"scenario T.C.{i + 1} collides: the {part} is {-d * 1000:.1f} mm inside an obstacle")


def _random_obstacles(rng: np.random.Generator) -> list[Obstacle]:
    """1-3 cylinders or boxes standing on the fixed plate near its centre,
    10 mm to 25 mm wide and 60 mm to 100 mm tall (below the movable plate)."""
    out: list[Obstacle] = []
    for _ in range(int(rng.integers(1, MAX_OBSTACLES + 1))):
        r = rng.uniform(0.0, 0.05)
        t = rng.uniform(0.0, 2 * np.pi)
        height = rng.uniform(0.06, 0.10)
        centre = (r * np.cos(t), r * np.sin(t), height / 2)
        if rng.random() < 0.5:
            out.append(Cylinder(centre, radius=rng.uniform(0.008, 0.02), height=height))
        else:
            out.append(Box(centre, half_extents=(rng.uniform(0.006, 0.016), rng.uniform(0.006, 0.016),
                                                  height / 2)))
    return out


def random_scenario(rng: np.random.Generator, scene: CaPaManScene,
                    clusters: capaman_grid.ClusterPoints | None = None, min_clearance: float = 0.004,
                    grid_points: int = 16, max_tries: int = 50) -> CaPaManScenario:
    """A seeded random feasible scenario (see the module docstring).

    T.P.s are drawn in the free cells of a ``grid_points``^3 joint matrix
    Theta (6 deg cells by default; cluster points every 10 mm unless
    ``clusters`` are given) with the colliding cells grown by one cell, in one
    connected component (26-neighbours),
    at least 20 deg apart, and each must have ``min_clearance`` (m) in
    PyBullet. Leaves the scene's obstacles set.
    """
    g = scene.geometry
    clusters = clusters or capaman_grid.cluster_points(g, spacing=0.01)
    for _ in range(max_tries):
        obstacles = _random_obstacles(rng)
        grid = capaman_grid.OccupancyGrid.from_obstacles(obstacles)
        theta, axis = capaman_grid.joint_matrix(grid, clusters, grid_points, g)
        blocked = ndimage.binary_dilation(theta, structure=np.ones((3, 3, 3), bool))  # edges stay clear
        labels, count = ndimage.label(~blocked, structure=np.ones((3, 3, 3)))
        if count == 0:
            continue
        sizes = np.bincount(labels.ravel())[1:]
        biggest = 1 + int(np.argmax(sizes))
        cells = np.argwhere(labels == biggest)
        if len(cells) < 10:
            continue
        scene.set_obstacles(obstacles)
        chosen: list[np.ndarray] = []
        for _ in range(60):
            a = axis[cells[rng.integers(len(cells))]]
            if any(np.linalg.norm(a - b) < 20 * DEG for b in chosen):
                continue
            scene.set_configuration(a)
            if scene.clearance()[0] < min_clearance:
                continue
            chosen.append(a)
            if len(chosen) == 3:
                alpha = np.array(chosen)
                tips = capaman.tool_tip(capaman.forward(alpha, g, validate=False), g)
                return CaPaManScenario("random", tuple(obstacles), _tuples(alpha), _tuples(tips))
    raise RuntimeError(f"no feasible random scenario in {max_tries} tries")


def resolve_scenario(choice: Any) -> str | CaPaManScenario:
    """The scenario argument's kind checked (:func:`paragym.tasks.base.resolve_scenario`):
    "paper", "random" or a :class:`CaPaManScenario`. Whether a custom one
    can run needs PyBullet: :func:`draw_scenario` checks it at reset."""
    return base.resolve_scenario(choice, SCENARIOS, CaPaManScenario)


def draw_scenarios(choice: Any, rngs: list[np.random.Generator], scene: CaPaManScene,
                   clusters: capaman_grid.ClusterPoints | None = None) -> list[CaPaManScenario]:
    """One episode's scenario per generator (single env, vector env and CLI alike): the paper's, random
    ones drawn from the generators one after another, or the custom one once :func:`validate_scenario`
    accepts it. Leaves ``scene``'s obstacles set to the last one's."""
    choice = resolve_scenario(choice)
    return [_draw_one(choice, rng, scene, clusters) for rng in rngs]


def _draw_one(choice: Any, rng: np.random.Generator, scene: CaPaManScene,
              clusters: capaman_grid.ClusterPoints | None = None) -> CaPaManScenario:
    """:func:`draw_scenarios` for one generator (the name of before paragym 0.9: ``draw_scenario``)."""
    choice = resolve_scenario(choice)
    if choice == "random":
        return random_scenario(rng, scene, clusters)
    scenario = paper_scenario(scene.geometry) if choice == "paper" else choice
    validate_scenario(scenario, scene)
    return scenario


#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = base.renamed(__name__, {"resolve_capaman": "resolve_scenario", "draw_scenario": "_draw_one"})
