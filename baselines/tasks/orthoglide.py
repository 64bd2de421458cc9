"""The 2PRR Orthoglide's bench (paper 003): its leaderboard metrics, policies, physics settings and CLI adapters."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from paragym import registry
from paragym.baselines.tasks import (
    Bench,
    BuiltIn,
    Column,
    Target,
    best_constant_floors,
    init_defaults,
    zero_factory,
)
from paragym.rollout import Episode
from paragym.sim.orthoglide_dynamic import OrthoglideDynamics
from paragym.tasks import orthoglide as scenarios_module

#: the rungs of the Orthoglide's difficulty ladders (:func:`paragym.registry.ladder_of`), the ladder v0's first
LADDER = tuple(r.id for r in registry.ladder_of("orthoglide"))
#: the ids whose policy drives the joints (a rung's ``actions``), and the ids whose policy moves the table along
#: n (every other id of the task, in its default action mode)
JOINT_IDS = tuple(r.id for rungs in registry.ladders("orthoglide")
                  for r, rung in zip(rungs, scenarios_module.LADDER, strict=True) if rung.actions == "joint_velocity")
NULL_SPACE_IDS = tuple(env_id for env_id in (*(r.id for r in registry.rows_of("orthoglide")), *LADDER)
                       if env_id not in JOINT_IDS)
#: the best constant null-space action of each rung: :func:`paragym.baselines.simple.best_constant` over
#: {-1, -0.5, -0.25, 0, 0.25, 0.5, 1} on reset seeds 0-29 (no constant succeeds on any rung: the first, -1, has the
#: highest return; a test searches again; the ladder v1's rungs are the ladder v0's in the kinematic fidelity). On
#: v0 and v1 the best constant is zero, a floor already.
BEST_CONSTANT = {env_id: (-1.0,) for env_id in LADDER if env_id not in JOINT_IDS}
#: the best constant joint rates of each rung that drives the joints: the same search over {-1, -0.5, 0, 0.5, 1}
#: for each joint (every constant leaves the path within a few steps; a test searches again)
JOINT_BEST_CONSTANT = {env_id: (1.0, 1.0, 0.0) for env_id in JOINT_IDS}


def metrics(ep: Episode) -> dict[str, float]:
    """The per-episode numbers the leaderboard averages into the bench's columns."""
    kappa = np.array([i["kappa"] for i in ep.infos])
    err = np.array([i["tracking_error"] for i in ep.infos])
    ok = np.isfinite(kappa)
    last = len(ep.infos[0]["scenario"].t) - 1
    return {"mean_kappa": float(kappa[ok].mean()), "max_kappa": float(kappa[ok].max()),
            "mean_tracking_error_mm": float(err.mean() * 1000), "max_tracking_error_mm": float(err.max() * 1000),
            "path_completed": float(ep.infos[-1]["step"] / last)}


def in_env_actions(env: gym.Env, policy: Any) -> Any:
    """A null-space policy as it plays ``env``: itself in the null-space action mode, in joint rates through
    :class:`~paragym.planners.nullspace_gradient.JointRates` in the joint-velocity mode."""
    from paragym.planners.nullspace_gradient import JointRates

    u = env.unwrapped
    if u.action_mode == "null_space":
        return policy
    return JointRates(policy, u.geometry, u.max_null_rate, u.max_joint_rate)


def gradient(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode, seeded (a :class:`BuiltIn` factory)."""
    from paragym.planners.nullspace_gradient import GradientPolicy

    return in_env_actions(env, GradientPolicy(geometry=env.unwrapped.geometry))


def least_norm(env: gym.Env, seed: int) -> Any:
    """Paper 003's case (b), the least-norm motion (the zero null-space rate), in the env's actions."""
    from paragym.baselines.simple import ZeroPolicy

    return in_env_actions(env, ZeroPolicy(gym.spaces.Box(-1.0, 1.0, (1,), np.float32)))


class KappaHillClimb:
    """A two-line rule read from the observation: drive the table along n at ``gain`` of the full null-space
    rate, and reverse it whenever the observed log kappa (index 7) rose over the last step. Extremum seeking
    with no model of the mechanism: the naive way to lower kappa, beside the paper's gradient (eqs 9-10) that
    computes which way it falls. ``gain`` 1 is the best of {0.1, 0.25, 0.5, 1} by the mean return over reset
    seeds 0-29 of v2, the easy and the medium rung together (0.5 is 0.1 % better on v2 alone). Played in joint
    rates (:func:`in_env_actions`) where the policy drives the joints."""

    def __init__(self, gain: float = 1.0) -> None:
        self.gain = gain
        self.direction, self.last = 1.0, math.inf

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        self.direction, self.last = 1.0, math.inf

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        log_kappa = float(obs[7])
        if log_kappa > self.last:
            self.direction = -self.direction
        self.last = log_kappa
        return np.array([self.gain * self.direction], np.float32)


def hill_climb(env: gym.Env, seed: int) -> Any:
    """The extremum-seeking rule (:class:`KappaHillClimb`) in the env's actions: a floor."""
    return in_env_actions(env, KappaHillClimb())


def hill_climb_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    return {"policy": init_defaults(KappaHillClimb)}


#: the table's acceleration along n (m/s^2) that the reference ``gradient-c-limited`` allows itself: the change
#: of 0.05 of ``max_null_rate`` per 10 ms path step
MAX_ACCEL = 2.5


def gradient_limited(env: gym.Env, seed: int) -> Any:
    """Case (c)'s gradient with the table's acceleration limited to :data:`MAX_ACCEL` (a :class:`BuiltIn`
    factory): the reference."""
    from paragym.planners.nullspace_gradient import GradientPolicy

    u = env.unwrapped
    return in_env_actions(env, GradientPolicy(geometry=u.geometry, max_accel=MAX_ACCEL, max_null_rate=u.max_null_rate))


def gradient_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners.nullspace_gradient import GradientPolicy

    settings = init_defaults(GradientPolicy)
    del settings["max_accel"], settings["max_null_rate"]  # unlimited: the plain rule, as its rows recorded it
    return {"policy": settings}


def gradient_limited_params() -> dict[str, Any]:
    """The settings the reference plays with, as the leaderboard records them."""
    return {"policy": {**gradient_params()["policy"], "max_accel": MAX_ACCEL, "max_null_rate": "the env's"}}


class FixedTablePolicy:
    """Paper 003's case (a) in the env's null-space action: the null-space rate
    that cancels the least-norm motion of the table (rho1), so the table
    stays where the env put it. The paper's case (a) picks, offline, the
    table position with the lowest mean kappa over the whole task; the env
    starts at the optimum for the first point instead, and a policy cannot
    move the start, so this is case (a) from the env's start."""

    def __init__(self, env: gym.Env) -> None:
        self.geometry = env.unwrapped.geometry
        self.max_null_rate = env.unwrapped.max_null_rate

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        self.task = info["scenario"]

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        from paragym.mechanisms import orthoglide as og

        k = min(info["step"], len(self.task.t) - 1)
        r1 = float(info["rho"][0])
        px, py = self.task.points[k]
        j, _, n = og.jacobian_at(r1, px, py, self.geometry)
        rate = og.least_norm(j, self.task.velocities[k])[0]
        if abs(n[0, 0]) < 1e-9:
            return np.zeros(1, np.float32)
        return np.array([np.clip(-rate[0] / (self.max_null_rate * n[0, 0]), -1.0, 1.0)], np.float32)


def fixed_table(env: gym.Env, seed: int) -> FixedTablePolicy:
    """A fresh policy for one episode, seeded (a :class:`BuiltIn` factory)."""
    return in_env_actions(env, FixedTablePolicy(env))


def plot_episode(ep: Episode, path: Path) -> Path:
    """The demo's picture of one episode, written to ``path``."""
    from paragym.plots.orthoglide import plot_episode as plot_kappa_episode

    return plot_kappa_episode(ep, path)


def plan(env: gym.Env, args: argparse.Namespace, out: Path, stem: str) -> int:
    """Paper 003's three cases offline: kappa per case, against the pointwise best; Figs 5-13."""
    import json
    import time

    from paragym.planners import nullspace_gradient as ng
    from paragym.plots.orthoglide import plot_cases as plot_orthoglide_cases

    obs, info = env.reset(seed=args.seed)
    task, g = info["scenario"], env.unwrapped.geometry
    cases = [ng.case_fixed_table(task, g)]
    t0 = time.perf_counter()
    cases.append(ng.case_least_norm(task, g))
    cases.append(ng.case_gradient(task, g, start=cases[1]))
    t_c = time.perf_counter() - t0  # case (c) starts from case (b)
    optimum, _ = ng.pointwise_optimum(task, g)
    print(f"{'case':36s} {'mean kappa':>10s} {'max kappa':>10s} {'worst at t':>11s}")
    stats = {}
    for c in cases:
        print(f"{c.name:36s} {c.kappa.mean():10.3f} {c.kappa.max():10.3f} {c.t[np.argmax(c.kappa)]:9.2f} s")
        stats[c.name] = {"mean_kappa": float(c.kappa.mean()), "max_kappa": float(c.kappa.max())}
    print(f"{'best reachable at each point':36s} {optimum.mean():10.3f} {optimum.max():10.3f}")
    print(f"case (c) within {100 * (cases[2].kappa / optimum - 1).max():.3f}% of the pointwise best; "
          f"computed in about {t_c:.2f} s; geometry: theta1 {np.degrees(g.theta1):.0f} deg, table origin "
          f"{g.table_origin} m, slider origins {g.slider2_origin}, {g.slider3_origin} m")
    png = plot_orthoglide_cases(task, cases, optimum, g, out / f"{stem}.png")
    (out / f"{stem}.json").write_text(json.dumps({"task": task.name, **stats, "optimum_mean": float(optimum.mean()),
                                                  "optimum_max": float(optimum.max())}, indent=2))
    print(f"wrote {png} and {out / (stem + '.json')}")
    return 0


BENCH = Bench(
    task="orthoglide",
    metrics=metrics,
    columns=(Column("mean_kappa", "mean kappa", ".3f"), Column("max_kappa", "max kappa", ".2f"),
             Column("mean_tracking_error_mm", "tracking error [mm]", ".2f"),
             Column("max_tracking_error_mm", "max tracking error [mm]", ".2f"),
             Column("path_completed", "path completed", ".2f", exact=True)),
    primary=("mean_kappa", -1),  # case (c) minimises kappa
    reference="gradient-c-limited",
    reference_success=0.95,  # 1.00 over the full suite
    policies=(
        BuiltIn("gradient-c-limited", gradient_limited, "reference",
                f"null-space gradient of kappa (paper 003, case c, eqs 9-10), the table's acceleration limited to "
                f"{MAX_ACCEL:g} m/s^2", gradient_limited_params),
        BuiltIn("gradient-c", gradient, "paper case",
                "null-space gradient of kappa as the paper states it (case c, eqs 9-10), its rate unlimited",
                gradient_params),
        BuiltIn("fixed-table-a", fixed_table, "paper case",
                "case (a): the table held still (at the env's start; see FixedTablePolicy)"),
        BuiltIn("zero", zero_factory, "floor",
                "= least norm, case (b): rho_dot = J^+ t_dot (paper 003, eq 5 with z = 0)", ids=NULL_SPACE_IDS),
        BuiltIn("zero", zero_factory, "floor", "the joints stand still", ids=JOINT_IDS),
        BuiltIn("least-norm", least_norm, "floor",
                "case (b) in joint rates: rho_dot = J^+ t_dot (paper 003, eq 5 with z = 0), the path tracked and "
                "kappa left alone", ids=JOINT_IDS),
        BuiltIn("hill-climb", hill_climb, "floor", "a two-line rule: the table along n at full rate, reversed "
                "whenever the observed kappa rose (extremum seeking, no model)", hill_climb_params),
        *best_constant_floors(BEST_CONSTANT, "the table driven along n at {action} of max_null_rate, the best of "
                              "{{-1, -0.5, -0.25, 0, 0.25, 0.5, 1}} on reset seeds 0-29"),
        *best_constant_floors(JOINT_BEST_CONSTANT, "joint rates {action} of max_joint_rate, the best of "
                              "{{-1, -0.5, 0, 0.5, 1}} per joint on reset seeds 0-29"),
    ),
    dynamics=OrthoglideDynamics,  # the env's default
    demo="null-space gradient of kappa (paper 003, case c)",
    plot_episode=plot_episode,
    plan=plan,
    solved=(Target("mean_kappa", -1, against="gradient-c", factor=1.01), Target("success", +1, 0.95)),
)
