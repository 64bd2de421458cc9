"""Paper 003's three cases for the 2PRR + table (sections 5-6).

* **Case (a)**, fixed table: the table stays at the one position, among
  those that keep the whole task inside the limits, with the lowest mean
  kappa; rho2 and rho3 by the inverse kinematics.
* **Case (b)**, least norm: ``rho_dot = J^+ t_dot`` (eq 5 with z = 0) from the
  optimal initial configuration (the table position with the lowest kappa
  at the first path point); integrated for the table, rho2 and rho3 then
  follow the inverse kinematics so that tracking is exact.
* **Case (c)**, global minimisation of kappa (eqs 9-10): at each path point,
  ``rho' = rho + (I - J^+ J) z' dt`` with ``z' = -grad kappa``, repeated while
  kappa decreases (dt grown by half after a successful step, halved after a
  failed one, until it falls below 1e-7), then the next point. The
  null space of J is one-dimensional (n), so ``(I - J^+ J) z' = (n . z') n``;
  all path points iterate together, each stopping on its own.

A task is a path in the table frame sampled on a time grid: :class:`OrthoglideScenario`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym.mechanisms import orthoglide as og
from paragym.planners.base import PlanningError
from paragym.tasks.base import renamed
from paragym.tasks.orthoglide import OrthoglideScenario, paper_scenario

__all__ = ["CaseResult", "GradientPolicy", "JointRates", "OrthoglideScenario", "case_fixed_table", "case_gradient",
           "case_least_norm", "paper_scenario", "pointwise_optimum"]


@dataclass(frozen=True)
class CaseResult:
    """Joint trajectory (K, 3) and kappa (K,) of one case."""

    name: str
    t: np.ndarray
    rho: np.ndarray
    kappa: np.ndarray


def _admissible(rho1: np.ndarray, points: np.ndarray, g: og.OrthoglideGeometry) -> tuple[np.ndarray, np.ndarray]:
    """rho and admissibility (reachable, working mode, inside the limits) for every (rho1, point) pair."""
    rho, ok = og.inverse(rho1, points, g)
    return rho, ok & og.within_limits(rho, g)


def pointwise_optimum(task: OrthoglideScenario, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                      samples: int = 2001) -> tuple[np.ndarray, np.ndarray]:
    """For every path point, the lowest kappa over the admissible table
    positions (a brute-force sweep of rho1) and the rho1 that gives it."""
    r1 = np.linspace(geometry.rho_min[0], geometry.rho_max[0], samples)
    k, n = len(task.points), len(r1)
    rho, ok = _admissible(np.tile(r1, k), np.repeat(task.points, n, 0), geometry)
    with np.errstate(divide="ignore", invalid="ignore"):
        kap = np.where(ok, og.kappa(rho, geometry), np.inf).reshape(k, n)
    kap = np.where(np.isfinite(kap), kap, np.inf)
    best = kap.argmin(axis=1)
    return kap[np.arange(k), best], r1[best]


def case_fixed_table(task: OrthoglideScenario, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                     samples: int = 401) -> CaseResult:
    """Case (a): the best constant table position for the task."""
    r1 = np.linspace(geometry.rho_min[0], geometry.rho_max[0], samples)
    k, n = len(task.points), len(r1)
    rho, ok = _admissible(np.repeat(r1, k), np.tile(task.points, (n, 1)), geometry)
    with np.errstate(divide="ignore", invalid="ignore"):
        kap = og.kappa(rho, geometry).reshape(n, k)
    usable = ok.reshape(n, k).all(axis=1) & np.isfinite(kap).all(axis=1)
    if not usable.any():
        raise PlanningError("no fixed table position keeps the whole task inside the limits")
    best = np.flatnonzero(usable)[np.argmin(kap[usable].mean(axis=1))]
    return CaseResult("(a) fixed table", task.t, rho.reshape(n, k, 3)[best], kap[best])


def case_least_norm(task: OrthoglideScenario, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY) -> CaseResult:
    """Case (b): rho_dot = J^+ t_dot from the optimal initial configuration
    (midpoint integration of the table; rho2, rho3 by inverse kinematics)."""
    first = OrthoglideScenario(task.name, task.t[:1], task.points[:1], task.velocities[:1])
    _, r1_opt = pointwise_optimum(first, geometry)
    r1 = float(r1_opt[0])
    out = np.empty((len(task.t), 3))
    for i in range(len(task.t)):  # an integration: each step needs the last
        rho, ok = _admissible(np.array([r1]), task.points[i:i + 1], geometry)
        if not ok[0]:
            raise PlanningError(f"the least-norm motion leaves the admissible set at t = {task.t[i]:.2f} s")
        out[i] = rho[0]
        if i + 1 < len(task.t):
            dt = task.t[i + 1] - task.t[i]
            j, _, _ = og.jacobian_at(r1, *task.points[i], geometry)
            half = r1 + 0.5 * dt * og.least_norm(j, task.velocities[i])[0, 0]
            mid = 0.5 * (task.points[i] + task.points[i + 1])
            vmid = 0.5 * (task.velocities[i] + task.velocities[i + 1])
            j, _, _ = og.jacobian_at(half, *mid, geometry)
            r1 = r1 + dt * og.least_norm(j, vmid)[0, 0]
    return CaseResult("(b) least norm", task.t, out, og.kappa(out, geometry))


def case_gradient(task: OrthoglideScenario, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY, step: float = 0.05,
                  max_iter: int = 300, start: CaseResult | None = None) -> CaseResult:
    """Case (c): at every path point, null-space steps along -grad kappa
    (eqs 9-10) while kappa decreases, halving the step when it does not;
    from ``start`` (default: case (b)'s configurations)."""
    g = geometry
    rho = (start or case_least_norm(task, g)).rho.copy()
    kap = og.kappa(rho, g)
    dt = np.full(len(rho), step)
    active = np.ones(len(rho), bool)
    for _ in range(max_iter):  # iterations, each over all still-improving path points at once
        if not active.any():
            break
        idx = np.flatnonzero(active)
        n = og.null_direction(rho[idx], g)
        z = -og.kappa_gradient(rho[idx], g)
        move = np.sum(n * z, axis=1)[:, None] * n  # (I - J^+ J) z' = (n . z') n
        trial_r1 = rho[idx, 0] + dt[idx] * move[:, 0]
        trial, ok = _admissible(trial_r1, task.points[idx], g)  # back onto the path: exact tracking
        with np.errstate(divide="ignore", invalid="ignore"):
            trial_k = np.where(ok, og.kappa(trial, g), np.inf)
        better = trial_k < kap[idx]
        rho[idx[better]], kap[idx[better]] = trial[better], trial_k[better]
        dt[idx[better]] *= 1.5  # a successful step grows, a failed one halves
        dt[idx[~better]] *= 0.5
        active[idx[~better & (dt[idx] < 1e-7)]] = False
    return CaseResult("(c) global minimisation of kappa", task.t, rho, kap)


class GradientPolicy:
    """Case (c) in ``Orthoglide2PRRKappa-v0`` (default action mode): the
    null-space rate along -grad kappa, ``gain`` per unit of gradient, clipped.

    ``max_accel`` (m/s^2 along n; None: unlimited, the paper's rule as written) limits how fast that rate may
    change: each path step the action moves at most ``max_accel * h / max_null_rate`` from the last one (h: the
    path's time step, s), from rest at the start. Near its optimum kappa has a kink (two singular values of J
    cross), so the plain rule's sign flips between -1 and +1 from one step to the next; a kinematic model
    follows, motors do not (under PyBullet's dynamics the plain rule fails on tracking, and the KF check with
    it: docs/guides/dynamics.md). The limit is the actuators' acceleration, which paper 003 leaves out.
    """

    def __init__(self, gain: float = 5.0, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                 max_accel: float | None = None, max_null_rate: float = 0.5) -> None:
        self.gain, self.geometry = gain, geometry
        self.max_accel, self.max_null_rate = max_accel, max_null_rate
        self.last = 0.0

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        self.last, self.task = 0.0, info.get("scenario")

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        rho = np.asarray(info["rho"])[None]
        slope = float(np.sum(og.null_direction(rho, self.geometry) * og.kappa_gradient(rho, self.geometry)))
        rate = float(np.clip(-self.gain * slope, -1.0, 1.0))
        if self.max_accel is not None:
            t, k = self.task.t, min(int(info["step"]), len(self.task.t) - 2)
            most = self.max_accel * float(t[k + 1] - t[k]) / self.max_null_rate
            rate = float(np.clip(rate, self.last - most, self.last + most))
        self.last = rate
        return np.array([rate], np.float32)

class JointRates:
    """A null-space policy (one action in [-1, 1], as :class:`GradientPolicy`) played in the env's
    joint-velocity action mode: each step, the joints that the null-space step would reach (eq 5 over the path
    step, then the sliders by inverse kinematics at the next path point: :func:`og.k_null_space_step`, the
    transition's own), taken from where the joints are, with J and n at the tool point they give, as joint rates
    in units of ``max_joint_rate``, clipped. The inverse kinematics closes the loop: an error left by a clipped
    step is corrected the next. Paper 003's eq 5 in full, as the robot's joint controller runs it."""

    def __init__(self, policy: Any, geometry: og.OrthoglideGeometry, max_null_rate: float, max_joint_rate: float
                 ) -> None:
        self.policy, self.geometry = policy, geometry
        self.max_null_rate, self.max_joint_rate = max_null_rate, max_joint_rate
        self.p = og.params(geometry)

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        self.task = info["scenario"]
        self.policy.reset(obs, info)

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        null = float(np.asarray(self.policy.act(obs, info)).reshape(-1)[0])
        task, k = self.task, int(info["step"])
        if k >= len(task.t) - 1:
            return np.zeros(3, np.float32)
        rho = np.asarray(info["rho"], float)
        tool = og.forward(rho[None], self.geometry)[0]
        j, _, n = og.jacobian_at(rho[:1], tool[:1], tool[1:], self.geometry)
        h = float(task.t[k + 1] - task.t[k])
        jt = tuple(float(x) for x in j.reshape(6))
        target = og.k_null_space_step(rho[0], jt, n[0, 0], tuple(float(x) for x in task.velocities[k]),
                                      null * self.max_null_rate, h, tuple(float(x) for x in task.points[k + 1]),
                                      self.p)
        rates = (np.array(target) - rho) / (h * self.max_joint_rate)
        return np.clip(np.nan_to_num(rates), -1.0, 1.0).astype(np.float32)


#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = renamed(__name__, {"Task": "OrthoglideScenario", "paper_task": "paper_scenario"})
