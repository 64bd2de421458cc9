"""The model paper 000's planner for the CaPaMan plans in (:mod:`paragym.planners.rrt_ga`): its settings, eq 3,
the joint space and the RRT forest.

:class:`JointSpaceModel` is Theta (Fig 2: the collision map of an
epsilon-grid over Omega = [45, 135] deg^3, from the Cartesian matrix Psi and
the cluster points, eqs 1-2), rho (the joint-space distance to the nearest
colliding configuration) and the collision validity of configurations and
segments; :class:`Forest` holds the N pairs of RRT trees grown in lockstep.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import ndimage

from paragym.mechanisms import capaman
from paragym.sim import capaman_grid
from paragym.tasks.capaman import CaPaManScenario, posts_of, scene_clearance
from paragym.units import DEG

__all__ = ["LEG_INTERVALS", "CapsuleSpaceModel", "Forest", "JointSpaceModel", "RrtGaSettings", "fitness"]

LEG_INTERVALS = (7, 7, 6)  # 20 intervals: m = 21 configurations, T.P.s at 0, 7, 14, 20


@dataclass(frozen=True)
class RrtGaSettings:
    """Parameters of the planner (rad, m, s). The paper gives m = 21; the rest
    it leaves open and these defaults are ours.

    Theta's default resolution is 31 points per crank angle (3 deg cells,
    29,791 configurations). The first build in a process keeps the reachable
    parts' cluster points over the joint grid for every later scenario
    (``python benchmarks/planner_capaman.py`` reports the build times).
    """

    theta_points: int = 31  # epsilon-grid of Omega: 3 deg cells
    cell: float = 0.005  # Psi cell size (m)
    cluster_spacing: float = 0.005  # cluster-point spacing (m)
    check_step: float = 1.0 * DEG  # segment sampling
    population: int = 16  # N
    generations: int = 60
    rrt_step: float = 15.0 * DEG  # RRT steering distance (the connecting move is not limited)
    rrt_iterations: int = 1500  # per leg, for all trees together
    rrt_quorum: float = 0.5  # a leg is done when this share of the N tree pairs has met
    delta: float = 8.0 * DEG  # rho below this: k_i = 1 (eq 5)
    beta: float = 0.05  # fitness cost of one close configuration (rad of path)
    crossover_rate: float = 0.8
    mutation_sigma: float = 3.0 * DEG
    mutation_rate: float = 0.15  # per interior configuration
    smoothing_rate: float = 0.15  # per interior configuration: move to the neighbours' midpoint
    tournament: int = 3
    elite: int = 2
    final_step: float = 0.25 * DEG  # PyBullet dense check
    time_budget: float = 30.0  # s, the whole plan

    @property
    def via_points(self) -> int:
        """m, configurations in a path (paper 000, section 5: 21)."""
        return sum(LEG_INTERVALS) + 1


def fitness(paths: np.ndarray, segment_free: np.ndarray, rho: np.ndarray, delta: float,
            beta: float) -> np.ndarray:
    """Eq 3 for a population: ``J = Lambda + sum_i d(Xi_i, Xi_i+1) + beta sum_i k_i``.

    Args:
        paths: (P, m, 3) configurations, rad.
        segment_free: (P, m - 1) whether each segment (and so its end
            configurations) is collision-free; any False gives Lambda = inf (eq 4).
        rho: (P, m) joint-space distance of each configuration to the nearest
            collision (rad); ``k_i = 1`` where ``rho_i < delta`` (eq 5, as the
            paper's text reads).
    """
    length = np.linalg.norm(np.diff(paths, axis=1), axis=2).sum(axis=1)
    close = (rho < delta).sum(axis=1)
    lam = np.where(segment_free.all(axis=1), 0.0, np.inf)
    return lam + length + beta * close


@lru_cache(maxsize=4)
def _clusters(geometry: capaman.CaPaManGeometry, spacing: float) -> capaman_grid.ClusterPoints:
    return capaman_grid.cluster_points(geometry, spacing)


class JointSpaceModel:
    """Steps 1-2 of the method for one scenario: Theta, rho, and collision
    validity of configurations and joint-space segments.

    A configuration is free when the eight Theta nodes around it are free
    (conservative by up to one cell). Near a task point, which may sit closer
    to an obstacle than one cell, eq 2 is evaluated at the configuration
    itself instead. A segment is free when its samples, ``check_step`` apart,
    are; segments already seen are remembered (a GA child shares most of its
    segments with its parents). The OMPL comparison uses this same model.
    """

    def __init__(self, scenario: CaPaManScenario, settings: RrtGaSettings,
                 geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY) -> None:
        t0 = time.perf_counter()
        s, g = settings, geometry
        self.settings, self.geometry = s, g
        self.grid = capaman_grid.OccupancyGrid.from_obstacles(scenario.obstacles, resolution=s.cell)
        clusters = _clusters(g, s.cluster_spacing)
        self._set_theta(*capaman_grid.joint_matrix(self.grid, clusters, s.theta_points, g), scenario)
        self.clusters = clusters.subset(capaman_grid.reachable_parts(self.grid, g))
        self.build_seconds = time.perf_counter() - t0

    def _set_theta(self, theta: np.ndarray, axis: np.ndarray, scenario: CaPaManScenario) -> None:
        """Theta (n, n, n, True where a node collides) on the grid ``axis`` (n,), and what follows from it:
        rho's distance transform, the free cells, the task points, an empty memo of segments."""
        self.theta = theta
        self.lo, self.eps, self.n = axis[0], axis[1] - axis[0], len(axis)
        self.rho_grid = (ndimage.distance_transform_edt(~self.theta, sampling=self.eps) if self.theta.any()
                         else np.full(self.theta.shape, np.inf))
        free = ~self.theta
        self.cell_free = (free[:-1, :-1, :-1] & free[1:, :-1, :-1] & free[:-1, 1:, :-1] & free[:-1, :-1, 1:]
                          & free[1:, 1:, :-1] & free[1:, :-1, 1:] & free[:-1, 1:, 1:] & free[1:, 1:, 1:])
        self.task_points = scenario.alpha
        self.step = self.settings.check_step
        self.memo: dict[bytes, bool] = {}

    def rho(self, q: np.ndarray) -> np.ndarray:
        """Joint-space distance (rad) to the nearest colliding Theta node, (...,) for q (..., 3)."""
        coords = ((q.reshape(-1, 3) - self.lo) / self.eps).T
        return ndimage.map_coordinates(self.rho_grid, coords, order=1, mode="nearest").reshape(q.shape[:-1])

    def fitness(self, paths: np.ndarray) -> np.ndarray:
        """Eq 3 for paths (P, m, 3) with this model's segment checks and rho."""
        p = len(paths)
        free = self.free(paths[:, :-1].reshape(-1, 3), paths[:, 1:].reshape(-1, 3)).reshape(p, -1)
        return fitness(paths, free, self.rho(paths), self.settings.delta, self.settings.beta)

    def configs(self, q: np.ndarray) -> np.ndarray:
        """Whether each configuration (K, 3) is free."""
        idx = np.clip(((q - self.lo) / self.eps).astype(int), 0, self.n - 2)
        ok = self.cell_free[idx[:, 0], idx[:, 1], idx[:, 2]]
        near = np.linalg.norm(q[:, None] - self.task_points[None], axis=2).min(axis=1) < 2 * self.eps
        exact = ~ok & near
        if exact.any():
            ok[exact] = self._exact_free(q[exact])
        return ok

    def _exact_free(self, q: np.ndarray) -> np.ndarray:
        """Whether configurations (K, 3) near a task point are free in the model itself: eq 2 on Psi."""
        return ~capaman_grid.grid_collision(q, self.grid, self.clusters, self.geometry)

    def config_free(self, q0: float, q1: float, q2: float) -> bool:
        """:meth:`configs` for one configuration in Python floats (for
        per-state callers such as OMPL's validity checker)."""
        top = self.n - 2
        i = min(max(int((q0 - self.lo) / self.eps), 0), top)
        j = min(max(int((q1 - self.lo) / self.eps), 0), top)
        k = min(max(int((q2 - self.lo) / self.eps), 0), top)
        if self.cell_free[i, j, k]:
            return True
        return bool(self.configs(np.array([[q0, q1, q2]]))[0])

    def evaluate(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether each segment a_i -> b_i ((S, 3) each) is free at every sample."""
        if len(a) == 0:
            return np.zeros(0, bool)
        counts = np.maximum(2, np.ceil(np.abs(b - a).max(axis=1) / self.step).astype(int) + 1)
        seg = np.repeat(np.arange(len(a)), counts)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        frac = (np.arange(len(seg)) - starts[seg]) / (counts[seg] - 1)
        ok = self.configs(a[seg] + frac[:, None] * (b - a)[seg])
        return np.logical_and.reduceat(ok, starts)

    def reach(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """For each segment a_i -> b_i, the fraction of it that is free from a_i
        up to the last sample before the first collision (1 when all is free)."""
        counts = np.maximum(2, np.ceil(np.abs(b - a).max(axis=1) / self.step).astype(int) + 1)
        seg = np.repeat(np.arange(len(a)), counts)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        frac = (np.arange(len(seg)) - starts[seg]) / (counts[seg] - 1)
        ok = self.configs(a[seg] + frac[:, None] * (b - a)[seg])
        blocked = np.where(ok, np.inf, frac)  # fraction of each colliding sample
        first = np.minimum.reduceat(blocked, starts)
        last_free = np.maximum.reduceat(np.where(frac < first[seg], frac, -1.0), starts)
        return np.where(np.isinf(first), 1.0, np.maximum(last_free, 0.0))

    def free(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """:meth:`evaluate`, remembering the segments already seen."""
        keys = [row.tobytes() for row in np.concatenate([a, b], axis=1)]
        todo = [i for i, k in enumerate(keys) if k not in self.memo]
        if todo:
            for i, ok in zip(todo, self.evaluate(a[todo], b[todo]), strict=True):
                self.memo[keys[i]] = bool(ok)
        return np.array([self.memo[k] for k in keys])


class CapsuleSpaceModel(JointSpaceModel):
    """:class:`JointSpaceModel` for scenes of capsule obstacles (the difficulty ladder's posts), with Theta taken
    from the capsule model's exact clearance instead of the Cartesian matrix Psi: a node collides where the
    whole manipulator passes closer than ``margin`` (m) to a post (:func:`paragym.tasks.capaman.scene_clearance`,
    the model the rungs' generator proves a tour in). Psi's cells are ``settings.cell`` wide and a cluster
    point is blocked by any cell it touches, so passages between posts narrower than a few cells close in Psi
    while they stay open here. Everything else (rho, the cell rule, the segment checks, the exact check near a
    task point, now in the capsule model) is the parent's, as is PyBullet's final dense check in the planner."""

    def __init__(self, scenario: CaPaManScenario, settings: RrtGaSettings,
                 geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, margin: float = 0.001) -> None:
        t0 = time.perf_counter()
        s, g = settings, geometry
        self.settings, self.geometry, self.margin = s, g, margin
        self.posts = posts_of(scenario.obstacles)
        axis = np.linspace(g.alpha_min, g.alpha_max, s.theta_points)
        nodes = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
        self._set_theta((self._clearance(nodes) < margin).reshape((len(axis),) * 3), axis, scenario)
        self.build_seconds = time.perf_counter() - t0

    def _clearance(self, q: np.ndarray) -> np.ndarray:
        return scene_clearance(np.ascontiguousarray(q, np.float64), self.posts, self.geometry,
                               cap=self.margin + 0.004)

    def _exact_free(self, q: np.ndarray) -> np.ndarray:
        """Near a task point: the capsule model's clearance is positive."""
        return self._clearance(q) > 0


class Forest:
    """N pairs of trees in the joint space (tree 0 grows from the start, tree
    1 from the goal), stored as arrays: nodes (N, 2, cap, 3), each node's
    parent, each tree's size, and where each pair's trees met (-1: not yet)."""

    def __init__(self, n: int, cap: int, start: np.ndarray, goal: np.ndarray) -> None:
        self.nodes = np.zeros((n, 2, cap, 3))
        self.parent = np.full((n, 2, cap), -1)
        self.nodes[:, 0, 0], self.nodes[:, 1, 0] = start, goal
        self.count = np.ones((n, 2), int)
        self.meet = np.full((n, 2), -1)

    def join_straight(self, goal: np.ndarray) -> None:
        """Every pair met at once: the goal is tree 0's child of the start."""
        self.nodes[:, 0, 1] = goal
        self.parent[:, 0, 1] = 0
        self.count[:, 0] = 2
        self.meet[:] = (1, 0)

    def nearest(self, pairs: np.ndarray, tree: int, q: np.ndarray) -> np.ndarray:
        """The node of ``tree`` nearest each point ``q`` (M, 3), for pairs (M,)."""
        size = int(self.count[pairs, tree].max())
        diff = self.nodes[pairs, tree, :size] - q[:, None]
        d = np.einsum("aki,aki->ak", diff, diff)  # squared distances to every node
        d[np.arange(size)[None] >= self.count[pairs, tree, None]] = np.inf
        return d.argmin(axis=1)

    def add(self, pairs: np.ndarray, tree: int, q: np.ndarray, par: np.ndarray) -> np.ndarray:
        """Add nodes ``q`` (M, 3) with parents ``par`` to ``tree`` of ``pairs``; returns their slots."""
        slot = self.count[pairs, tree]
        self.nodes[pairs, tree, slot] = q
        self.parent[pairs, tree, slot] = par
        self.count[pairs, tree] += 1
        return slot

    def _chain(self, i: int, tree: int) -> list[int]:
        out = [int(self.meet[i, tree])]
        while out[-1] > 0:
            out.append(int(self.parent[i, tree, out[-1]]))
        return out

    def path(self, i: int, goal: np.ndarray) -> np.ndarray:
        """Pair ``i``'s path from the start to the goal (K, 3), through the meeting point."""
        points = np.vstack([self.nodes[i, 0, self._chain(i, 0)[::-1]], self.nodes[i, 1, self._chain(i, 1)[1:]]])
        if self.meet[i, 1] == 0 and not np.array_equal(points[-1], goal):  # tree 0 reached the goal itself
            points = np.vstack([points, goal])
        return points


