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
4. **Detours where the split cannot follow** (``max_repairs`` > 0): the split may change by at most
   ``max_delta_step`` a sample, so a path on which some Delta works at every pose can still have no
   schedule, where the working splits jump (a band closes and another opens far from it). Then the
   first sample that no schedule reaches is treated as step 3 treats a blocked one, with one
   difference: the via offset must make a split work there that the schedule can reach from the
   sample before (the same x, then y, then z search); the serial optimisation is run again, up to
   ``max_repairs`` times. Paper 002 has no rate limit on Delta, so it has no such case; this is
   step 3 applied to it, and 0 turns it off (the planner as first written).

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
        max_repairs: how many samples step 4 (module docstring) may detour where the split schedule
            dies; 0: none.
    """

    def __init__(self, geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY, tau: float = 0.01,
                 delta0: float = 0.5, delta_points: int = 101, max_delta_step: float = 0.05,
                 j_bar: float = 0.02, detour_step: float = 0.001, prefer_weight: float = 0.05,
                 stroke_margin: float = 0.0, max_repairs: int = 0) -> None:
        if not 0 <= delta0 <= 1:
            raise ValueError(f"delta0 must lie in [0, 1]; got {delta0}")
        if not (np.isfinite(stroke_margin) and 0 <= stroke_margin < (geometry.l_max - geometry.l_min) / 2):
            raise ValueError(f"stroke_margin must be >= 0 m and under half the stroke range; got {stroke_margin!r}")
        if isinstance(max_repairs, bool) or not isinstance(max_repairs, int | np.integer) or max_repairs < 0:
            raise ValueError(f"max_repairs must be a whole number >= 0; got {max_repairs!r}")
        self.stroke_margin, self.max_repairs = float(stroke_margin), int(max_repairs)
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

    def _dead_end(self, table: np.ndarray) -> tuple[int, np.ndarray]:
        """Where the split schedule dies on a feasibility table (K, D) that :meth:`_serial` found no schedule
        on: the first sample that no schedule from the start reaches, and the splits (D,) one step of the rate
        limit can reach there from those reachable at the sample before."""
        d = self.deltas
        step_ok = np.abs(d[:, None] - d[None, :]) <= self.max_delta_step + 1e-12
        start = np.isclose(d, self.delta0) & table[0]
        reach = start if start.any() else table[0]
        for i in range(1, len(table)):
            near = step_ok[reach].any(axis=0)
            if not (near & table[i]).any():
                return i, near
            reach = near & table[i]
        raise AssertionError("the table has a schedule")  # _serial found none: unreachable

    def _need(self, pose: np.ndarray, allowed: np.ndarray, i: int) -> np.ndarray:
        """The via offset (3,) of one blocked sample ``i`` at ``pose`` (6,): the smallest offset along x, then y,
        then z that lets some Delta of ``allowed`` (D,) work."""
        steps = np.arange(self.detour_step, self.j_bar + 1e-12, self.detour_step)
        candidates = np.concatenate([steps, -steps])[np.argsort(np.concatenate([steps, steps]), kind="stable")]
        need = np.zeros(3)
        for axis in range(3):  # each axis searched in one batch
            trial = np.repeat(pose[None], len(candidates), axis=0)
            trial[:, axis] += candidates
            ok = (self._table(trial) & allowed).any(axis=1)
            if ok.any():
                need[axis] = candidates[np.argmax(ok)]
                return need
        raise PlanningError(f"no via pose within j_bar = {self.j_bar * 1000:.0f} mm at u = {i * self.tau:.2f}")

    def _detour(self, nominal: np.ndarray, blocked: np.ndarray, allowed: np.ndarray | None = None,
                found: dict[tuple[int, bytes], np.ndarray] | None = None) -> np.ndarray:
        """Offsets (K, 3): for every blocked sample its :meth:`_need` (with the splits of ``allowed`` (K, D),
        where given; ``found`` keeps the needs already searched); each stretch of blocked samples becomes one
        smooth bump per axis."""
        need = np.zeros((len(nominal), 3))
        found = {} if found is None else found
        for i in np.flatnonzero(blocked):
            mask = np.ones(len(self.deltas), bool) if allowed is None else allowed[i]
            key = (int(i), mask.tobytes())
            if key not in found:
                found[key] = self._need(nominal[i], mask, int(i))
            need[i] = found[key]
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
                                            self.prefer_weight, max_repairs=self.max_repairs)
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
        allowed, found = np.ones_like(table), {}
        for repair in range(self.max_repairs + 1):
            if blocked.any():
                offsets = self._detour(nominal, blocked, allowed, found)
                path = nominal.copy()
                path[:, :3] += offsets
                table = self._table(path)
            delta = self._serial(table)
            if delta is not None:
                break
            if repair == self.max_repairs:
                raise PlanningError("no Delta(u) keeps the path singularity-free within the rate limit"
                                    + (f" after {self.max_repairs} detours where the split could not follow"
                                       if self.max_repairs else ""))
            i, near = self._dead_end(table)  # step 4: a detour there, to a split the schedule reaches
            if blocked[i] and not (allowed[i] & ~near).any():
                raise PlanningError(f"no Delta(u) keeps the path singularity-free within the rate limit: the "
                                    f"detour at u = {i * self.tau:.2f} leaves no split the schedule reaches")
            blocked[i], allowed[i] = True, allowed[i] & near
        state = hybrid.solve(path, delta, self.geometry, validate=False)
        method = np.where(np.any(offsets != 0, axis=1), 2, np.where(np.abs(delta - self.delta0) > 1e-12, 1, 0))
        base = hybrid.home_pose(self.geometry)
        return HybridPlan(u, nominal, path, offsets, delta, state.lengths, state.mu_hexapod, state.mu_tripod,
                          state.free, method, nominal_free, hybrid._pose_of(state.t_a), path + base)


class PolynomialDetourPolicy:
    """The reference policy of ``HybridSingularityFree-v0``: plans at reset,
    then commands the plan's Delta and offsets step by step (``split_only``: Delta's rate alone, the action of
    the ladder v1, whose planner has ``j_bar`` 0 so that it plans no offset)."""

    def __init__(self, planner: PolynomialDetourPlanner | None = None, split_only: bool = False) -> None:
        self.planner = planner
        self.split_only = split_only
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
        d_delta = np.clip((self.plan.delta[k] - info["delta"]) / self._max_step, -1, 1)
        if self.split_only:
            return np.array([d_delta], np.float32)
        return np.concatenate([[d_delta], self.plan.offsets[k] / self._j_bar]).astype(np.float32)
