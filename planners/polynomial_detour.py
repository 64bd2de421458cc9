"""Paper 002's planner: a 7th-degree nominal path, serial optimisation of the
split Delta, and detour via poses (section 2).

1. **Nominal path** (eqs 15-17): ``P(u) = P0 + (P1 - P0) s(u)`` with
   ``s(u) = 35u^4 - 84u^5 + 70u^6 - 20u^7`` (zero velocity, acceleration and
   jerk at both ends), sampled every tau = 0.01.
2. **Serial optimisation** (2.2): the end-effector path stays nominal; Delta
   is chosen along u on a grid of [0, 1], among the values that make each
   pose singularity-free and within limits (eq 14), by dynamic programming
   that weighs the total change of Delta against its distance from Delta0 =
   0.5 (eq 24), each step changing Delta by at most ``max_delta_step``: Delta
   stays at Delta0 where that works and leaves it smoothly where it does not.
3. **Detour optimisation** (2.3): at poses where no Delta works, a via offset
   is searched by changing x, then y, then z (the paper's loop), each at most
   ``j_bar`` from the nominal; the offsets of a stretch of such poses are
   joined into one smooth bump (zero value and slope at its ends, so the path
   stays C1) and the serial optimisation is run again on the detoured path.

All poses are displacements of E from home (m, rad); see
:mod:`paragym.mechanisms.hybrid`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from paragym.mechanisms import hybrid
from paragym.planners.base import PlanningError
from paragym.trajectories import nominal_path

__all__ = ["HybridPlan", "PolynomialDetourPlanner", "PolynomialDetourPolicy", "nominal_path"]


@dataclass(frozen=True)
class HybridPlan:
    """The planner's output along u (K samples).

    Attributes: ``nominal`` and ``path`` (K, 6) E displacements (the path is
    the nominal plus ``offsets`` (K, 3) in x, y, z); ``delta`` (K,);
    ``lengths`` (K, 9) the nine strokes (m); ``mu_hexapod``, ``mu_tripod``
    (K,); ``free`` (K,) eq 14; ``method`` (K,) 0 nominal (Delta0 works), 1
    serial, 2 detour; ``nominal_free`` (K,) eq 14 of the nominal path at
    Delta0; ``a_pose`` and ``e_pose`` (K, 6) platform A and E in the base frame.
    """

    u: np.ndarray
    nominal: np.ndarray
    path: np.ndarray
    offsets: np.ndarray
    delta: np.ndarray
    lengths: np.ndarray
    mu_hexapod: np.ndarray
    mu_tripod: np.ndarray
    free: np.ndarray
    method: np.ndarray
    nominal_free: np.ndarray
    a_pose: np.ndarray
    e_pose: np.ndarray


class PolynomialDetourPlanner:
    """Paper 002's method (module docstring).

    Args:
        geometry: the robot.
        tau: step of u (paper: 0.01).
        delta0: the default split (eq 24: 0.5).
        delta_points: grid of Delta over [0, 1].
        max_delta_step: largest change of Delta between consecutive samples.
        j_bar: largest detour offset per axis (m; the paper's J-bar).
        detour_step: resolution of the detour search (m).
        prefer_weight: cost, per sample and per unit of |Delta - Delta0|, of
            staying away from Delta0 (against 1 per unit of change of Delta).
        stroke_margin: plan the strokes this far (m) inside their limits, where
            the path allows it (else at the limits, as paper 002 does): a
            simulated actuator that chases a stroke planned at its limit
            overshoots it (0: the paper's plan).
    """

    def __init__(self, geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY, tau: float = 0.01,
                 delta0: float = 0.5, delta_points: int = 101, max_delta_step: float = 0.05,
                 j_bar: float = 0.02, detour_step: float = 0.001, prefer_weight: float = 0.05,
                 stroke_margin: float = 0.0) -> None:
        if not 0 <= delta0 <= 1:
            raise ValueError(f"delta0 must lie in [0, 1]; got {delta0}")
        if not (np.isfinite(stroke_margin) and 0 <= stroke_margin < (geometry.l_max - geometry.l_min) / 2):
            raise ValueError(f"stroke_margin must be >= 0 m and under half the stroke range; got {stroke_margin!r}")
        self.stroke_margin = float(stroke_margin)
        self.geometry, self.tau, self.delta0 = geometry, tau, delta0
        self.deltas = np.linspace(0.0, 1.0, delta_points)
        self.max_delta_step, self.j_bar, self.detour_step = max_delta_step, j_bar, detour_step
        self.prefer_weight = prefer_weight

    def _table(self, path: np.ndarray) -> np.ndarray:
        """Feasibility (K, D) of every pose at every Delta of the grid, in one batch."""
        k, d = len(path), len(self.deltas)
        poses = np.repeat(path, d, axis=0)
        return hybrid.solve(poses, np.tile(self.deltas, k), self.geometry, validate=False).free.reshape(k, d)

    def _serial(self, table: np.ndarray) -> np.ndarray | None:
        """Delta along u by dynamic programming over the feasible grid values
        (None if some sample has no feasible Delta reachable within the rate limit)."""
        d = self.deltas
        step_ok = np.abs(d[:, None] - d[None, :]) <= self.max_delta_step + 1e-12
        change = np.abs(d[:, None] - d[None, :])
        prefer = self.prefer_weight * np.abs(d - self.delta0)
        start = np.isclose(d, self.delta0) & table[0]  # at rest at P0 with the default split, if it works there
        cost = np.where(start if start.any() else table[0], prefer, np.inf)
        back = np.zeros(table.shape, int)
        for i in range(1, len(table)):  # the path is sequential; each step is a (D, D) array operation
            total = cost[:, None] + np.where(step_ok, change, np.inf)
            back[i] = np.argmin(total, axis=0)
            cost = total[back[i], np.arange(len(d))] + prefer
            cost = np.where(table[i], cost, np.inf)
        if not np.isfinite(cost).any():
            return None
        idx = np.empty(len(table), int)
        idx[-1] = int(np.argmin(cost))
        for i in range(len(table) - 1, 0, -1):
            idx[i - 1] = back[i, idx[i]]
        return d[idx]

    def _detour(self, nominal: np.ndarray, blocked: np.ndarray) -> np.ndarray:
        """Offsets (K, 3): for every blocked sample the smallest offset along x,
        then y, then z that lets some Delta work; each stretch of blocked samples
        becomes one smooth bump per axis."""
        steps = np.arange(self.detour_step, self.j_bar + 1e-12, self.detour_step)
        candidates = np.concatenate([steps, -steps])[np.argsort(np.concatenate([steps, steps]), kind="stable")]
        need = np.zeros((len(nominal), 3))
        for i in np.flatnonzero(blocked):  # the blocked samples only, each searched in one batch
            for axis in range(3):
                trial = np.repeat(nominal[i:i + 1], len(candidates), axis=0)
                trial[:, axis] += candidates
                ok = self._table(trial).any(axis=1)
                if ok.any():
                    need[i, axis] = candidates[np.argmax(ok)]
                    break
            else:
                raise PlanningError(f"no via pose within j_bar = {self.j_bar * 1000:.0f} mm at u = "
                                    f"{i * self.tau:.2f}")
        offsets = np.zeros_like(need)
        u = np.arange(len(nominal))
        runs = np.split(np.flatnonzero(blocked), np.flatnonzero(np.diff(np.flatnonzero(blocked)) > 1) + 1)
        for run in runs:
            if len(run) == 0:
                continue
            lo, hi = run[0] - 3, run[-1] + 3  # the bump starts and ends three samples outside the stretch
            if lo < 0 or hi > len(nominal) - 1:
                raise PlanningError("the path's end pose itself needs a detour: it is not reachable")
            x = (u[lo:hi + 1] - lo) / (hi - lo)
            bump = (16 * x * x * (1 - x) * (1 - x)) ** 2  # 1 in the middle, value and slope 0 at the ends
            peak = need[run][np.argmax(np.abs(need[run]), axis=0), np.arange(3)]
            core = np.clip(bump / bump[run - lo].min(), 0.0, 1.0)  # full offset over the whole stretch
            offsets[lo:hi + 1] += core[:, None] * peak
        return np.clip(offsets, -self.j_bar, self.j_bar)

    def plan(self, p0: np.ndarray, p1: np.ndarray) -> HybridPlan:
        """Plan from ``p0`` to ``p1`` (E displacements from home, (6,), m and rad): with the strokes
        ``stroke_margin`` inside their limits where that plan exists, else at them."""
        if self.stroke_margin > 0:
            g = self.geometry
            inner = PolynomialDetourPlanner(replace(g, l_min=g.l_min + self.stroke_margin,
                                                    l_max=g.l_max - self.stroke_margin), self.tau, self.delta0,
                                            len(self.deltas), self.max_delta_step, self.j_bar, self.detour_step,
                                            self.prefer_weight)
            try:
                plan = inner.plan(p0, p1)
            except PlanningError:
                pass
            else:  # the strokes, measures and verdicts of the robot itself, at the plan's poses and splits
                state = hybrid.solve(plan.path, plan.delta, g, validate=False)
                nominal_free = hybrid.solve(plan.nominal, self.delta0, g, validate=False).free
                return replace(plan, lengths=state.lengths, mu_hexapod=state.mu_hexapod,
                                  mu_tripod=state.mu_tripod, free=state.free, nominal_free=nominal_free)
        p0, p1 = hybrid.check_pose(p0, "p0")[0], hybrid.check_pose(p1, "p1")[0]
        u, nominal = nominal_path(p0, p1, self.tau)
        nominal_free = hybrid.solve(nominal, self.delta0, self.geometry, validate=False).free
        table = self._table(nominal)
        if not (table[0].any() and table[-1].any()):
            raise PlanningError("the start or end pose is not singularity-free within limits for any Delta")
        offsets = np.zeros((len(u), 3))
        path = nominal
        blocked = ~table.any(axis=1)
        if blocked.any():
            offsets = self._detour(nominal, blocked)
            path = nominal.copy()
            path[:, :3] += offsets
            table = self._table(path)
        delta = self._serial(table)
        if delta is None:
            raise PlanningError("no Delta(u) keeps the path singularity-free within the rate limit")
        state = hybrid.solve(path, delta, self.geometry, validate=False)
        method = np.where(np.any(offsets != 0, axis=1), 2, np.where(np.abs(delta - self.delta0) > 1e-12, 1, 0))
        base = hybrid.home_pose(self.geometry)
        return HybridPlan(u, nominal, path, offsets, delta, state.lengths, state.mu_hexapod, state.mu_tripod,
                          state.free, method, nominal_free, hybrid._pose_of(state.t_a), path + base)


class PolynomialDetourPolicy:
    """The reference policy of ``HybridSingularityFree-v0``: plans at reset,
    then commands the plan's Delta and offsets step by step."""

    def __init__(self, planner: PolynomialDetourPlanner | None = None) -> None:
        self.planner = planner
        self.plan: HybridPlan | None = None

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        scenario = info["scenario"]
        if self.planner is None:
            self.planner = PolynomialDetourPlanner(scenario.geometry, j_bar=info["j_bar"])
        self.plan = self.planner.plan(scenario.p0, scenario.p1)
        self._max_step, self._j_bar = info["max_delta_step"], info["j_bar"]

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        if self.plan is None:
            raise RuntimeError("call reset(obs, info) before act")
        k = min(info["step"] + 1, len(self.plan.u) - 1)
        d_delta = (self.plan.delta[k] - info["delta"]) / self._max_step
        return np.concatenate([[np.clip(d_delta, -1, 1)], self.plan.offsets[k] / self._j_bar]).astype(np.float32)
