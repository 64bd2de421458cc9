"""Paper 000's planner for CaPaMan: an RRT population optimised by a genetic algorithm.

Section 2 of paper 000 (Carbone, Gomez-Bravo, Selvi), Figs 1-2, eqs 1-5:

1. **Theta** (Fig 2): the collision map of an epsilon-grid over the joint
   space Omega = [45, 135] deg^3, from the Cartesian matrix Psi (eq 1) and the
   manipulator's cluster points (eq 2), all grid configurations at once
   (:func:`paragym.sim.capaman_grid.joint_matrix`).
2. **rho**: the joint-space distance from a configuration to the nearest
   colliding one, a Euclidean distance transform of Theta (scipy.ndimage),
   interpolated between grid nodes.
3. **RRT** (LaValle and Kuffner; bidirectional, as their RRT-Connect): N
   pairs of trees grown in lockstep (one numpy step advances all N) from
   T.P.1 to T.P.2, T.P.2 to T.P.3 and T.P.3 to T.P.1, give N collision-free
   tours; each is shortcut and resampled to
   the paper's m = 21 configurations (T.P.s at fixed indices) to form the
   initial population.
4. **GA**: tournament selection, leg-wise and one-point crossover, Gaussian
   and smoothing mutation, elitism; the fitness is eq 3,
   ``J = Lambda + sum d(Xi_i, Xi_i+1) + beta * sum k_i`` with Lambda = inf
   when any configuration *or segment* collides (eq 4; segments are sampled
   every ``check_step`` and tested with eq 2) and ``k_i = 1 when rho_i <
   delta`` (eq 5 as the text explains it; the printed inequality is the other
   way round).
5. **Final check**: PyBullet, the exact judge, tests the chosen path and its
   time-parameterised curve densely; the best individual that passes is the
   plan.

Collision validity everywhere comes from the paper's model: a configuration
is free when the Theta nodes around it are (eq 2 at the configuration itself
within two cells of a task point, which may sit closer to an obstacle than a
cell); segments are sampled every ``check_step``. Only the last step
consults PyBullet.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from paragym.mechanisms import capaman
from paragym.planners.base import PathFollowingPolicy, PlanningError
from paragym.planners.rrt_ga_space import (
    LEG_INTERVALS,
    CapsuleSpaceModel,
    Forest,
    JointSpaceModel,
    RrtGaSettings,
    fitness,
)
from paragym.sim.capaman_scene import CaPaManScene
from paragym.tasks.capaman import LADDER_MAX_OBSTACLES, MAX_OBSTACLES, CaPaManScenario, validate_scenario
from paragym.trajectories import JointPath, JointTrajectory
from paragym.units import DEG

__all__ = ["JointSpaceModel", "RrtGaPlanner", "RrtGaPolicy", "RrtGaResult", "RrtGaSettings", "fitness"]


@dataclass(frozen=True)
class RrtGaResult:
    """What one planning run produced.

    Attributes:
        path: the plan, 21 configurations (rad); T.P.s at ``path.via_indices``.
        fitness: J of the plan (eq 3).
        initial_best_fitness: the best J of the RRT population.
        history: best J after each generation.
        min_clearance: smallest PyBullet distance along the plan (m).
        close_configurations: sum k_i of the plan.
        timings: seconds spent in "theta", "rrt", "ga", "check" and "total".
    """

    path: JointPath
    fitness: float
    initial_best_fitness: float
    history: np.ndarray
    min_clearance: float
    close_configurations: int
    timings: dict[str, float] = field(default_factory=dict)

    def trajectory(self, dt: float = 0.45, max_velocity: float = 3.0) -> JointTrajectory:
        """The plan in time: via points ``dt`` s apart (paper: 0.09, 0.45, 0.9)."""
        return JointTrajectory.from_path(self.path, dt, max_velocity)


class RrtGaPlanner:
    """Paper 000's RRT + GA planner for ``CaPaManCollisionFree-v0`` scenarios.

    Args:
        settings: the planner's parameters.
        geometry: the CaPaMan's dimensions.
        seed: seed of the planner's random generator (RRT samples, GA).
        collision_model: what Theta is made from: "psi", the paper's Cartesian matrix of ``settings.cell``
            cells and the cluster points (eqs 1-2); "capsules", the capsule model's exact clearance at Theta's
            nodes, for scenes of capsule posts only (:class:`~paragym.planners.rrt_ga_space.CapsuleSpaceModel`,
            ``capsule_margin`` m from every post).
        capsule_margin: the clearance (m) a node of Theta must keep in the capsule model.
    """

    def __init__(self, settings: RrtGaSettings | None = None,
                 geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, seed: int = 0,
                 collision_model: str = "psi", capsule_margin: float = 0.001) -> None:
        if collision_model not in ("psi", "capsules"):
            raise ValueError(f"collision_model must be 'psi' or 'capsules'; got {collision_model!r}")
        if not (isinstance(capsule_margin, int | float) and 0 <= capsule_margin < 0.01):
            raise ValueError(f"capsule_margin must be a clearance in [0, 0.01) m; got {capsule_margin!r}")
        self.settings = settings or RrtGaSettings()
        self.geometry = geometry
        self.seed = seed
        self.collision_model, self.capsule_margin = collision_model, float(capsule_margin)
        self._scene: CaPaManScene | None = None

    @property
    def scene(self) -> CaPaManScene:
        """The planner's own PyBullet scene for the final check (made on first use)."""
        if self._scene is None:
            self._scene = CaPaManScene(self.geometry, draws=False)  # checks, never drawn
        return self._scene

    def close(self) -> None:
        """Free the PyBullet scene."""
        if self._scene is not None:
            self._scene.close()
            self._scene = None

    def model(self, scenario: CaPaManScenario) -> JointSpaceModel:
        """Validate the scenario (PyBullet: ``ValueError`` if a task
        configuration collides) and build its :class:`JointSpaceModel`
        (:class:`PlanningError` if a task point collides in the grid model)."""
        validate_scenario(scenario, self.scene, max(MAX_OBSTACLES, LADDER_MAX_OBSTACLES))  # a rung's too
        model = (JointSpaceModel(scenario, self.settings, self.geometry) if self.collision_model == "psi" else
                 CapsuleSpaceModel(scenario, self.settings, self.geometry, self.capsule_margin))
        bad = np.flatnonzero(~model.configs(scenario.alpha))
        if len(bad):
            raise PlanningError(f"T.P.{bad[0] + 1} collides in the grid model (eq 2): it lies within the "
                                f"{self.settings.cell * 1000:.0f} mm cells' margin of an obstacle")
        return model

    def plan(self, scenario: CaPaManScenario) -> JointPath:
        """The tour T.P.1 -> T.P.2 -> T.P.3 -> T.P.1 as a 21-configuration joint path."""
        return self.solve(scenario).path

    # --- the method -------------------------------------------------------------------
    def solve(self, scenario: CaPaManScenario, seed: int | None = None) -> RrtGaResult:
        """Run the whole method (module docstring) and report on it.

        Raises ``ValueError`` for a scenario whose task configurations collide
        and :class:`PlanningError` when no path is found within the settings'
        iterations and ``time_budget``.
        """
        s = self.settings
        t0 = time.perf_counter()
        deadline = t0 + s.time_budget
        rng = np.random.default_rng(self.seed if seed is None else seed)
        checker = self.model(scenario)
        tp = scenario.alpha
        rho = checker.rho
        t_theta = time.perf_counter()
        legs = [self._rrt_leg(tp[i], tp[j], checker, rng, deadline, leg)
                for leg, (i, j) in enumerate(((0, 1), (1, 2), (2, 0)))]
        population = np.concatenate(legs, axis=1)  # (N, 21, 3)
        population = np.concatenate([population, tp[None, :1].repeat(len(population), axis=0)], axis=1)
        t_rrt = time.perf_counter()

        evaluate = checker.fitness
        scores = evaluate(population)
        if not np.isfinite(scores).any():
            raise PlanningError("the RRT population has no collision-free path")
        initial_best = float(scores.min())
        history = []
        for _ in range(s.generations):
            if time.perf_counter() > deadline:
                break
            population, scores = self._generation(population, scores, evaluate, rng)
            history.append(float(scores.min()))
        t_ga = time.perf_counter()

        for idx in np.argsort(scores):  # best first; PyBullet is the judge
            if not np.isfinite(scores[idx]):
                break
            path = JointPath(population[idx], (0, 7, 14, 20))
            clearance = self._pybullet_clearance(path)
            if clearance > 0:
                t_end = time.perf_counter()
                return RrtGaResult(
                    path, float(scores[idx]), initial_best, np.array(history), clearance,
                    int((rho(path.waypoints) < s.delta).sum()),
                    {"theta": t_theta - t0, "rrt": t_rrt - t_theta, "ga": t_ga - t_rrt,
                     "check": t_end - t_ga, "total": t_end - t0})
        raise PlanningError("no path of the final population passes PyBullet's dense check")

    def _rrt_leg(self, start: np.ndarray, goal: np.ndarray, checker: JointSpaceModel,
                 rng: np.random.Generator, deadline: float, leg: int) -> np.ndarray:
        """N bidirectional RRTs (Kuffner and LaValle's RRT-Connect) from
        ``start`` to ``goal``, grown in lockstep (:meth:`_grow`) until
        ``rrt_quorum`` of the pairs have met or the time is up. Returns the N
        paths shortcut and resampled to ``LEG_INTERVALS[leg]`` intervals,
        without the goal: (N, intervals, 3); the pairs that have not met take
        the path of one that has (the GA's mutations then tell them apart)."""
        s = self.settings
        n = s.population
        forest = Forest(n, s.rrt_iterations + 2, start, goal)
        if checker.evaluate(start[None], goal[None])[0]:  # straight line is free
            forest.join_straight(goal)
        quorum = max(1, int(np.ceil(s.rrt_quorum * n)))
        for it in range(s.rrt_iterations):
            active = np.flatnonzero(forest.meet[:, 0] < 0)
            if n - len(active) >= quorum or time.perf_counter() > deadline:
                break
            self._grow(forest, active, it % 2, checker, rng)
        found = np.flatnonzero(forest.meet[:, 0] >= 0)
        if len(found) == 0:
            raise PlanningError(f"RRT found no path from T.P.{leg + 1} to T.P.{(leg + 1) % 3 + 1} in "
                                f"{s.rrt_iterations} iterations (or the time budget)")
        out = np.empty((n, LEG_INTERVALS[leg], 3))
        for row in range(n):  # each pair's path, shortcut and resampled
            i = found[row % len(found)] if forest.meet[row, 0] < 0 else row
            out[row] = self._resample(self._shortcut(forest.path(i, goal), checker), LEG_INTERVALS[leg])[:-1]
        return out

    def _grow(self, forest: Forest, active: np.ndarray, a: int, checker: JointSpaceModel,
              rng: np.random.Generator) -> None:
        """One iteration of RRT-Connect for the ``active`` pairs: tree ``a``
        extends toward a uniform sample (as far as is free, at most
        ``rrt_step``), then the other tree tries to connect to the new node in
        one straight, checked move; pairs whose trees join are marked met."""
        s, g, b = self.settings, self.geometry, 1 - a
        target = rng.uniform(g.alpha_min, g.alpha_max, (len(active), 3))
        near = forest.nearest(active, a, target)
        base = forest.nodes[active, a, near]
        step = target - base
        dist = np.linalg.norm(step, axis=1, keepdims=True)
        new = base + step * np.minimum(1.0, s.rrt_step / np.maximum(dist, 1e-12))
        new = base + checker.reach(base, new)[:, None] * (new - base)  # extend as far as is free
        ok = np.linalg.norm(new - base, axis=1) > 0.5 * s.check_step
        grow, new = active[ok], new[ok]
        if len(grow) == 0:
            return
        slot_a = forest.add(grow, a, new, near[ok])
        # connect: the other tree's nearest node straight to the new one, as far as is free
        near_b = forest.nearest(grow, b, new)
        base_b = forest.nodes[grow, b, near_b]
        frac = checker.reach(base_b, new)
        moved = np.linalg.norm(new - base_b, axis=1) * frac > 0.5 * s.check_step
        slot_b = np.full(len(grow), -1)
        if moved.any():
            q = base_b[moved] + frac[moved, None] * (new[moved] - base_b[moved])
            slot_b[moved] = forest.add(grow[moved], b, q, near_b[moved])
        joined = frac >= 1.0
        slot_b = np.where(joined & ~moved, near_b, slot_b)  # already within a sample of the new node
        done = grow[joined]
        forest.meet[done, a], forest.meet[done, b] = slot_a[joined], slot_b[joined]

    @staticmethod
    def _shortcut(points: np.ndarray, checker: JointSpaceModel) -> np.ndarray:
        """Greedy shortcut: from each kept point jump to the farthest point in
        view (all candidates tested in one batch)."""
        kept, i = [0], 0
        while i < len(points) - 1:
            cand = np.arange(i + 1, len(points))
            ok = checker.evaluate(np.broadcast_to(points[i], (len(cand), 3)), points[cand])
            i = int(cand[ok].max()) if ok.any() else i + 1
            kept.append(i)
        return points[kept]

    @staticmethod
    def _resample(points: np.ndarray, intervals: int) -> np.ndarray:
        """``intervals + 1`` configurations on the polyline, every corner kept
        (so every new segment lies on a checked one): each of its segments gets
        intervals in proportion to its length, at least one."""
        seg = np.diff(points, axis=0)
        if len(seg) > intervals:  # more corners than slots: keep the shape, cut corners
            t = np.linspace(0, 1, intervals + 1)
            cum = np.concatenate([[0], np.cumsum(np.linalg.norm(seg, axis=1))])
            return np.stack([np.interp(t * cum[-1], cum, points[:, j]) for j in range(3)], axis=1)
        length = np.linalg.norm(seg, axis=1)
        share = 1 + (intervals - len(seg)) * length / max(length.sum(), 1e-12)
        alloc = np.floor(share).astype(int)
        extra = intervals - alloc.sum()
        alloc[np.argsort(alloc - share)[:extra]] += 1  # largest remainders
        parts = [points[k] + np.outer(np.arange(c) / c, seg[k]) for k, c in enumerate(alloc)]
        return np.vstack(parts + [points[-1:]])

    def _generation(self, pop: np.ndarray, scores: np.ndarray, evaluate: Any,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """One generation: elites kept; the rest are children of tournament
        winners, crossed and mutated, all at once."""
        s, g = self.settings, self.geometry
        n, m, _ = pop.shape
        kids = n - s.elite
        bounds = np.cumsum((0,) + LEG_INTERVALS)  # 0, 7, 14, 20: the T.P.s
        fixed = np.zeros(m, bool)
        fixed[bounds] = True

        def tournament() -> np.ndarray:
            entrants = rng.integers(0, n, (kids, s.tournament))
            return entrants[np.arange(kids), np.argmin(scores[entrants], axis=1)]

        a, b = pop[tournament()], pop[tournament()]
        child = a.copy()
        cross = rng.random(kids) < s.crossover_rate
        # leg-wise uniform crossover: each leg from either parent (legs meet at the T.P.s)
        leg_of = np.searchsorted(bounds[1:], np.arange(m), side="right").clip(0, 2)
        from_b = (rng.random((kids, 3)) < 0.5)[:, leg_of] & cross[:, None]
        child[from_b] = b[from_b]
        # one-point crossover inside one leg: the tail of that leg from the other parent
        leg = rng.integers(0, 3, kids)
        cut = bounds[leg] + 1 + (rng.random(kids) * (np.array(LEG_INTERVALS)[leg] - 1)).astype(int)
        idx = np.arange(m)[None]
        tail = cross[:, None] & (idx >= cut[:, None]) & (idx < bounds[leg + 1][:, None])
        other = np.where(from_b[..., None], a, b)
        child[tail] = other[tail]
        # mutation: Gaussian steps, and smoothing toward the neighbours' midpoint
        move = (rng.random((kids, m)) < s.mutation_rate) & ~fixed
        child[move] += rng.normal(0.0, s.mutation_sigma, (int(move.sum()), 3))
        smooth = (rng.random((kids, m)) < s.smoothing_rate) & ~fixed
        mid = np.zeros_like(child)
        mid[:, 1:-1] = 0.5 * (child[:, :-2] + child[:, 2:])
        child[smooth] = mid[smooth]
        np.clip(child, g.alpha_min, g.alpha_max, out=child)
        elite = np.argsort(scores)[:s.elite]
        new_pop = np.concatenate([pop[elite], child])
        return new_pop, np.concatenate([scores[elite], evaluate(child)])

    def _pybullet_clearance(self, path: JointPath) -> float:
        """Smallest PyBullet distance along the path and along its
        time-parameterised curve (both sampled every ``final_step`` or finer)."""
        scene = self.scene
        curve = JointTrajectory(np.arange(len(path.waypoints), dtype=float), path.waypoints, np.inf)
        t = np.linspace(0.0, curve.duration, int(path.length / self.settings.final_step) + 2)
        configs = np.vstack([path.densify(self.settings.final_step), curve.position(t)])
        configs = np.clip(configs, self.geometry.alpha_min, self.geometry.alpha_max)
        best = np.inf
        for q in configs:  # PyBullet answers one configuration per call
            scene.set_configuration(q)
            best = min(best, scene.clearance()[0])
            if best <= 0:
                break
        return float(best)


class RrtGaPolicy(PathFollowingPolicy):
    """The reference policy of ``CaPaManCollisionFree-v0``: plans with
    :class:`RrtGaPlanner` at reset, then follows the 21-configuration path."""

    def __init__(self, max_joint_step: float = 2 * DEG, planner: RrtGaPlanner | None = None) -> None:
        super().__init__(planner or RrtGaPlanner(), max_joint_step)
