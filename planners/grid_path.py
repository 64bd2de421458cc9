"""Shortest collision-free path on paper 000's joint matrix Theta (a baseline planner).

Theta (Fig 2) marks which cells of an epsilon-grid of the joint space collide
(eqs 1-2). This planner joins the task points T.P.1 -> T.P.2 -> T.P.3 -> T.P.1
by Dijkstra's shortest path over the free cells (26-neighbours, edge weight
the joint distance; colliding cells grown by one cell so edges stay clear):
the optimum of the path-length term of the paper's fitness (eq 3) at the
grid's resolution, without the clearance term and
without the paper's RRT + GA search. It is the simplest planner that is
correct on this task and serves as a baseline and as the feasibility witness
for scenarios.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from paragym.mechanisms import capaman
from paragym.planners.base import PathFollowingPolicy, PlanningError
from paragym.sim import capaman_grid
from paragym.tasks.capaman import TOUR, CaPaManScenario
from paragym.trajectories import JointPath
from paragym.units import DEG

__all__ = ["GridField", "GridFieldPolicy", "GridPathPlanner", "GridPathPolicy", "PlanningError"]


def _offsets() -> np.ndarray:
    """The 13 neighbour offsets of a 26-neighbourhood, one of each +/- pair."""
    d = np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij")).reshape(3, -1).T
    return d[[tuple(o) > (0, 0, 0) for o in d]]


class GridPathPlanner:
    """Dijkstra on the free cells of Theta.

    Args:
        points_per_axis: grid points per crank angle over 45-135 deg (31: 3 deg cells).
        spacing: cluster-point spacing (m).
        geometry: the CaPaMan's dimensions.
    """

    def __init__(self, points_per_axis: int = 31, spacing: float = 0.005,
                 geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY) -> None:
        if points_per_axis < 3:
            raise ValueError(f"points_per_axis must be >= 3; got {points_per_axis}")
        self.n = points_per_axis
        self.geometry = geometry
        self.clusters = capaman_grid.cluster_points(geometry, spacing)

    def field(self, scenario: CaPaManScenario) -> GridField:
        """Dijkstra from each T.P. over the free cells of Theta: the shortest
        free path from any cell to any T.P. (:class:`GridField`)."""
        grid = capaman_grid.OccupancyGrid.from_obstacles(scenario.obstacles)
        theta, axis = capaman_grid.joint_matrix(grid, self.clusters, self.n, self.geometry)
        # Nodes are checked, edges are not: a free node next to a colliding one is
        # treated as colliding, so an edge never cuts through a collision region
        # one cell or more across.
        free = ~ndimage.binary_dilation(theta, structure=np.ones((3, 3, 3), bool)).ravel()
        n = self.n
        cells = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
        rows, cols, weights = [], [], []
        for off in _offsets():  # 13 directions, each over every cell at once
            nb = cells + off
            ok = np.all((nb >= 0) & (nb < n), axis=1)
            a = np.flatnonzero(ok)
            b = np.ravel_multi_index(nb[ok].T, (n, n, n))
            keep = free[a] & free[b]
            rows.append(a[keep])
            cols.append(b[keep])
            weights.append(np.full(keep.sum(), np.linalg.norm(off * (axis[1] - axis[0]))))
        graph = coo_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(n ** 3, n ** 3)).tocsr()
        tp = np.asarray(scenario.alpha, float)
        free_idx = np.flatnonzero(free)
        # Each T.P. enters the grid at its nearest free cell.
        entry = free_idx[np.argmin(np.linalg.norm(axis[cells[free_idx]][None] - tp[:, None], axis=2), axis=1)]
        dist, pred = dijkstra(graph, directed=False, indices=entry, return_predecessors=True)
        reachable = tuple(free_idx[np.isfinite(dist[j, free_idx])] for j in range(len(tp)))
        return GridField(axis[cells], free_idx, entry, dist, pred, tp, reachable)

    def plan(self, scenario: CaPaManScenario) -> JointPath:
        """The tour T.P.1 -> T.P.2 -> T.P.3 -> T.P.1 as a joint path."""
        f = self.field(scenario)
        waypoints = [f.tp[0]]
        vias = [0]
        order = (0,) + TOUR
        for i, j in zip(order[:-1], order[1:], strict=True):
            if not np.isfinite(f.dist[i, f.entry[j]]):
                raise PlanningError(f"T.P.{i + 1} and T.P.{j + 1} are not connected in Theta at "
                                    f"{np.degrees(f.points[1, 2] - f.points[0, 2]):.1f} deg resolution")
            node, chain = f.entry[j], []
            while node != f.entry[i]:  # walk the predecessor chain (path length, not grid size)
                chain.append(node)
                node = f.pred[i, node]
            chain.append(f.entry[i])
            waypoints += list(f.points[chain[::-1]]) + [f.tp[j]]
            vias.append(len(waypoints) - 1)
        return JointPath(np.array(waypoints), tuple(vias))


@dataclass(frozen=True)
class GridField:
    """Shortest free paths to each T.P. over the cells of Theta.

    Attributes:
        points: (n^3, 3) the cells' crank angles (rad).
        free_idx: the cells that are free with a one-cell margin.
        entry: (3,) each T.P.'s cell (its nearest free cell).
        dist: (3, n^3) the free path's length from each T.P.'s cell (rad; inf: not connected).
        pred: (3, n^3) the next cell toward T.P. j on that path (scipy's predecessors).
        tp: (3, 3) the task points (rad).
        reachable: per T.P., the free cells connected to it.
    """

    points: np.ndarray
    free_idx: np.ndarray
    entry: np.ndarray
    dist: np.ndarray
    pred: np.ndarray
    tp: np.ndarray
    reachable: tuple[np.ndarray, ...]

    def next_waypoint(self, alpha: np.ndarray, target: int) -> np.ndarray:
        """Where to steer from the cranks ``alpha`` (rad) toward T.P. ``target``:
        the next cell on the shortest free path from the nearest free cell
        connected to the target, or the T.P. itself from its own cell."""
        reachable = self.reachable[target]
        node = reachable[np.argmin(np.linalg.norm(self.points[reachable] - alpha, axis=1))]
        if node == self.entry[target]:
            return self.tp[target]
        return self.points[self.pred[target, node]]


class GridPathPolicy(PathFollowingPolicy):
    """Follows :class:`GridPathPlanner`'s path in ``CaPaManCollisionFree-v0``."""

    def __init__(self, max_joint_step: float = 2 * DEG, planner: GridPathPlanner | None = None) -> None:
        super().__init__(planner or GridPathPlanner(), max_joint_step)


class GridFieldPolicy:
    """A feedback form of :class:`GridPathPlanner`: from wherever the cranks
    are, the next cell of the shortest free path to the current target T.P.
    (``info["target_index"]``), in steps of at most ``max_joint_step`` rad.

    From the start of an episode it moves as :class:`GridPathPolicy` does,
    up to where the cells are entered; unlike a path follower it answers in
    any state, which is what an expert queried in states it did not visit
    (DAgger, :mod:`paragym.baselines.dagger`) needs."""

    def __init__(self, max_joint_step: float = 2 * DEG, planner: GridPathPlanner | None = None) -> None:
        if not max_joint_step > 0:
            raise ValueError(f"max_joint_step must be > 0 rad; got {max_joint_step}")
        self.planner = planner or GridPathPlanner()
        self.max_joint_step = max_joint_step
        self.field: GridField | None = None

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        self.field = self.planner.field(info["scenario"])
        if not np.all(np.isfinite(self.field.dist[:, self.field.entry])):
            raise PlanningError("the T.P.s are not connected in Theta at the grid's resolution")

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        if self.field is None:
            raise RuntimeError("call reset(obs, info) before act")
        alpha = info["alpha"]
        delta = self.field.next_waypoint(alpha, int(info["target_index"])) - alpha
        return (delta / max(self.max_joint_step, np.max(np.abs(delta)))).astype(np.float32)
