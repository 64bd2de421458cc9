"""The CaPaMan's bench (paper 000): its leaderboard metrics, policies, physics settings and CLI adapters."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from paragym import registry
from paragym.baselines.tasks import (
    Ablation,
    AblationRow,
    Bench,
    BuiltIn,
    Column,
    Option,
    Target,
    best_constant_floors,
    init_defaults,
    tightest,
    zero_factory,
)
from paragym.rollout import Episode
from paragym.sim.capaman_dynamic import CaPaManDynamics
from paragym.units import DEG

#: the rungs of the CaPaMan's difficulty ladder (:func:`paragym.registry.ladder_of`): v1's rules on their own scenes
LADDER = tuple(r.id for r in registry.ladder_of("capaman"))
V1 = ("paragym/CaPaManCollisionFree-v1", *LADDER)
#: the best constant crank rates of the rungs: :func:`paragym.baselines.simple.best_constant` over
#: {-1, -0.5, 0, 0.5, 1} for each crank on reset seeds 0-29. No constant succeeds on any rung (a constant rate runs
#: a crank into its stop and cannot visit three targets); on the easy rung the best (by return) is zero, a floor
#: already
BEST_CONSTANT = {LADDER[1]: (-1.0, -1.0, 1.0), LADDER[2]: (0.0, 1.0, -1.0)}


def metrics(ep: Episode) -> dict[str, float]:
    """The per-episode numbers the leaderboard averages into the bench's columns."""
    alpha = np.array([i["alpha"] for i in ep.infos])
    clearance = np.array([i["clearance"] for i in ep.infos])
    return {"path_length_rad": float(np.linalg.norm(np.diff(alpha, axis=0), axis=1).sum()),
            "min_clearance_mm": float(clearance.min() * 1000), "collision": float(ep.infos[-1]["collision"]),
            "tcs_reached": float(ep.infos[-1]["reached"])}


def rrt_ga(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode, seeded (a :class:`BuiltIn` factory)."""
    from paragym.planners import RrtGaPlanner, RrtGaPolicy

    return RrtGaPolicy(max_joint_step=env.unwrapped.max_joint_step, planner=RrtGaPlanner(seed=seed))


def rrt_ga_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners import RrtGaPlanner, RrtGaPolicy
    from paragym.planners.rrt_ga import RrtGaSettings

    # the planner as these rows were made: Theta from Psi alone (the collision model had no name then)
    return {"policy": {**init_defaults(RrtGaPolicy, planner=None), "arrival": RrtGaPolicy.ARRIVAL},
            "planner": init_defaults(RrtGaPlanner, omit=("collision_model", "capsule_margin"),
                                     settings=RrtGaSettings(), seed="the episode's seed")}


#: the rungs' reference plans in the capsule model the rungs' generator proves a tour in (Theta at its witness's
#: 2 deg, 1 mm from every post), with RRT iterations enough for its narrowest passages: in the paper's 5 mm Psi
#: the passages between posts close, and RRT + GA missed 5 of the hard rung's 50 leaderboard draws
RUNG_SETTINGS = {"theta_points": 46, "rrt_iterations": 6000}


def rrt_ga_capsules(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode of a rung, seeded (a :class:`BuiltIn` factory): :func:`rrt_ga` with Theta
    from the capsule model (:data:`RUNG_SETTINGS`)."""
    from paragym.planners import RrtGaPlanner, RrtGaPolicy
    from paragym.planners.rrt_ga import RrtGaSettings

    planner = RrtGaPlanner(RrtGaSettings(**RUNG_SETTINGS), seed=seed, collision_model="capsules")
    return RrtGaPolicy(max_joint_step=env.unwrapped.max_joint_step, planner=planner)


def rrt_ga_capsules_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners import RrtGaPlanner, RrtGaPolicy
    from paragym.planners.rrt_ga import RrtGaSettings

    return {"policy": {**init_defaults(RrtGaPolicy, planner=None), "arrival": RrtGaPolicy.ARRIVAL},
            "planner": init_defaults(RrtGaPlanner, settings=RrtGaSettings(**RUNG_SETTINGS),
                                     seed="the episode's seed", collision_model="capsules")}


class StraightLine:
    """The CaPaMan's naive controller: every crank straight at the current target T.P., as fast as the action
    allows (``a = clip((target - alpha) / max_joint_step, -1, 1)``), blind to the obstacles. It reads the target
    offset from the observation: v0 gives the cranks and the target (indices 0-2 and 6-8), v1 their difference
    (3-5), each in units of 45 deg."""

    def __init__(self, env: gym.Env) -> None:
        params = env.unwrapped.params
        self.offset = (slice(6, 9), slice(0, 3)) if not params.goal_relative else (slice(3, 6), None)
        self.gain = 45 * DEG / params.max_joint_step

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        target, cranks = self.offset
        delta = obs[target] - (0.0 if cranks is None else obs[cranks])
        return np.clip(delta * self.gain, -1.0, 1.0).astype(np.float32)


def straight_line(env: gym.Env, seed: int) -> StraightLine:
    """The naive controller (:class:`StraightLine`): a floor."""
    return StraightLine(env)


class SlideRule(StraightLine):
    """A rule read from v1's observation, two lines beyond the naive controller: go straight at the target, and
    where the clearance is low, slide along the obstacle. Near an obstacle (the observed clearance under
    ``threshold`` of its cap) the straight action loses its component along the clearance's falling gradient
    (the observed look-ahead: how the clearance changes if each crank alone moves 3 deg, normalised), gains
    ``push`` along its rising one, and is rescaled so that its largest crank moves at full speed.

    A floor that reads the obstacles, beside the blind one: its two numbers are the best of a grid
    (:data:`SLIDE_GRID`) on reset seeds 0-29 of the easy and the hard rung (success 0.80 and 0.23 there; the
    straight line 0.03 and 0). v1's observation only: v0 has no look-ahead."""

    def __init__(self, env: gym.Env, threshold: float = 0.1, push: float = 0.25) -> None:
        super().__init__(env)
        if not env.unwrapped.params.goal_relative:
            raise ValueError("slide-rule reads v1's clearance look-ahead; v0's observation has none")
        self.threshold, self.push = threshold, push

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        a = np.clip(obs[3:6] * self.gain, -1.0, 1.0)
        clearance, ahead = obs[-5], obs[-4:-1]  # v1's tail: clearance / cap, its look-ahead / cap, progress
        norm = float(np.linalg.norm(ahead))
        if clearance < self.threshold and norm > 1e-9:
            up = ahead / norm
            a = a - min(float(a @ up), 0.0) * up + self.push * up
            a = a / max(float(np.abs(a).max()), 1e-12)
        return np.clip(a, -1.0, 1.0).astype(np.float32)


#: the grid :class:`SlideRule`'s two numbers were searched over, on reset seeds 0-29 of the easy and the hard
#: rung, in two forms: as the class plays it, and with the push alone added to the straight action (no
#: projection, no rescaling; at best 0.30 and 0.03). Threshold 0.1 of the cap came first on both rungs, push 0.25
#: first of those tied with it
SLIDE_GRID = {"threshold": (0.05, 0.1, 0.2, 0.3), "push": (0.25, 0.5, 1.0)}


def slide_rule(env: gym.Env, seed: int) -> SlideRule:
    """The obstacle-reading rule (:class:`SlideRule`): a floor."""
    return SlideRule(env)


def slide_rule_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    return {"policy": init_defaults(SlideRule)}


def grid_path(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode, seeded (a :class:`BuiltIn` factory)."""
    from paragym.planners import GridPathPolicy

    return GridPathPolicy(max_joint_step=env.unwrapped.max_joint_step)


def grid_path_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners import GridPathPolicy
    from paragym.planners.grid_path import GridPathPlanner

    return {"policy": {**init_defaults(GridPathPolicy, planner=None), "arrival": GridPathPolicy.ARRIVAL},
            "planner": init_defaults(GridPathPlanner)}


def grid_field(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode, seeded (a :class:`BuiltIn` factory)."""
    from paragym.planners import GridFieldPolicy

    return GridFieldPolicy(max_joint_step=env.unwrapped.max_joint_step)


def grid_field_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners import GridFieldPolicy
    from paragym.planners.grid_path import GridPathPlanner

    return {"policy": init_defaults(GridFieldPolicy, planner=None), "planner": init_defaults(GridPathPlanner)}


def plot_episode(ep: Episode, path: Path) -> Path:
    """The demo's picture of one episode, written to ``path``."""
    from paragym.plots.capaman import plot_episode as plot_capaman_episode

    return plot_capaman_episode(ep, path)


def plan(env: gym.Env, args: argparse.Namespace, out: Path, stem: str) -> int:
    """RRT + GA on the env's scenario: stats, the Fig 3 picture against time, and a JSON."""
    import json

    import numpy as np

    from paragym.mechanisms import capaman
    from paragym.plots.capaman import plot_motion as plot_capaman_motion

    obs, info = env.reset(seed=args.seed)
    scenario = info["scenario"]
    frame = env.render()
    planner = BENCH.reference_of(env.spec.id).factory(env, args.seed).planner  # as the id's reference plans
    result = planner.solve(scenario)
    planner.close()
    traj = result.trajectory(args.dt)
    t, alpha, _, _ = traj.sample(rate=200.0)
    tips = capaman.tool_tip(capaman.forward(alpha, validate=False))
    axis = np.array(scenario.obstacles[0].center[:2])
    radius = np.hypot(*(tips[:, :2] - axis).T)
    marks = traj.times[list(result.path.via_indices)]
    stats = {
        "scenario": scenario.name, "seed": args.seed,
        "planning_seconds": result.timings, "fitness_J": result.fitness,
        "initial_best_J": result.initial_best_fitness, "joint_path_length_rad": result.path.length,
        "close_configurations": result.close_configurations, "min_clearance_m": result.min_clearance,
        "tool_radius_about_obstacle_axis_m": [float(radius.min()), float(radius.max())],
        "dt_s": traj.dt, "duration_s": traj.duration, "peak_joint_speed_rad_s": traj.peak_velocity,
        "via_points_rad": result.path.waypoints.tolist(), "task_point_indices": list(result.path.via_indices),
    }
    title = (f"RRT + GA, {scenario.name} scenario: J = {result.fitness:.3f}, joint path "
             f"{result.path.length:.2f} rad, {len(result.path.waypoints)} via points, dt = {traj.dt:.2f} s")
    png = plot_capaman_motion(scenario, t, alpha, tips, marks, out / f"{stem}.png", title, frame=frame)
    (out / f"{stem}.json").write_text(json.dumps(stats, indent=2))
    print(f"planning {result.timings['total']:.2f} s (theta {result.timings['theta']:.2f}, rrt "
          f"{result.timings['rrt']:.2f}, ga {result.timings['ga']:.2f}, pybullet check {result.timings['check']:.2f})")
    print(f"fitness J {result.fitness:.3f} (RRT population best {result.initial_best_fitness:.3f}); joint path "
          f"{result.path.length:.3f} rad; {result.close_configurations} configurations closer than delta")
    print(f"min clearance {result.min_clearance * 1000:.1f} mm (PyBullet); tool tip {radius.min() * 1000:.1f}-"
          f"{radius.max() * 1000:.1f} mm from the first obstacle's axis (paper: within 60 mm)")
    print(f"trajectory: 21 via points, dt {traj.dt:.3f} s, {traj.duration:.2f} s, peak joint speed "
          f"{traj.peak_velocity:.2f} rad/s")
    print(f"wrote {png} and {out / (stem + '.json')}")
    return 0


def validate_plan(env: gym.Env, args: argparse.Namespace, out: Path, stem: str) -> int:
    """Plan (RRT + GA), execute in the dynamic simulation, validate (paper 000, section 5), report."""
    from paragym.planners import RrtGaPlanner
    from paragym.validation.capaman import validate_capaman
    from paragym.validation.report import write_report

    stem += f"_dt{args.dt:g}"
    obs, info = env.reset(seed=args.seed)
    planner = RrtGaPlanner(seed=args.seed)
    result = planner.solve(info["scenario"])
    planner.close()
    traj = result.trajectory(args.dt)
    print(f"plan: J {result.fitness:.3f}, {len(result.path.waypoints)} via points, dt {traj.dt:.3f} s, "
          f"{traj.duration:.2f} s; executing in the dynamic simulation ...")
    val = validate_capaman(traj, seed=args.seed)
    rep = val.report
    print(f"execution: loop closure error at most {val.run.closure_error * 1000:.3f} mm; crank tracking error "
          f"at most {np.degrees(np.abs(val.run.alpha - traj.position(val.run.t)).max()):.2f} deg")
    print(f"eq 21 (direct formulas) against eq 17 (least squares), filtered a_H: largest gap {rep.eq21_gap:.2e} m/s^2")
    print(rep.table())
    title = f"{info['scenario'].name} scenario, dt = {traj.dt:.2f} s: {'PASS' if rep.passed else 'FAIL'}"
    return write_report(rep, out / stem, title, {"dt_s": traj.dt, "duration_s": traj.duration,
                                                 "closure_error_m": val.run.closure_error, "eq21_gap": rep.eq21_gap})


def validated_plan(seed: int) -> tuple[bool, dict[str, Any]]:
    """The leaderboard's KF validation of the reference plan on the paper's case: (passed, its summary)."""
    from paragym.planners import RrtGaPlanner
    from paragym.tasks.capaman import paper_scenario
    from paragym.validation.capaman import validate_capaman

    planner = RrtGaPlanner(seed=seed)
    result = planner.solve(paper_scenario())
    planner.close()
    traj = result.trajectory(0.45)
    rep = validate_capaman(traj, seed=seed).report
    return rep.passed, {"text": f"RRT+GA plan at dt = 0.45 s ({traj.duration:.1f} s) executed by the closed-chain "
                                f"dynamics, accelerometer array + Kalman filter (RTS); {tightest(rep)}",
                        "duration_s": traj.duration}


#: the ablation behind v1 (``benchmarks/ablation.py --task capaman``), its rows in the order they were tried
ABLATION = Ablation(
    rows=(
        AblationRow("v0 (absolute obs, no look-ahead, v0 reward), PPO", "paragym/CaPaManCollisionFree-v0", {}, {},
                    1_500_000),
        AblationRow("v1 as released: goal-relative obs + look-ahead, time penalty, 3 deg reach",
         "paragym/CaPaManCollisionFree-v1", {}, {}, 1_500_000),
        AblationRow("v1 with v0's reward (no time penalty, collision -5)", "paragym/CaPaManCollisionFree-v1",
         {"time_penalty": 0.0, "collision_penalty": 5.0}, {}, 1_500_000),
        AblationRow("v1 with v0's reach tolerance (1 deg)", "paragym/CaPaManCollisionFree-v1",
                    {"reach_tolerance": 1 * DEG}, {},
         1_500_000),
    ),
    beside=("paragym/CaPaManCollisionFree-v1", ("zero", "rrt-ga")),
    metric=("collisions", lambda infos: float(infos[-1]["collision"])),
    ppo_from=None,
)


BENCH = Bench(
    ablation=ABLATION,
    task="capaman",
    options=(Option(("plan", "validate"), "--dt", float, {"plan": 0.45, "validate": 0.9},
                    "seconds between via points (paper: 0.09, 0.45, 0.9)"),),
    metrics=metrics,
    columns=(Column("path_length_rad", "joint path [rad]", ".2f"),
             Column("min_clearance_mm", "min clearance [mm]", ".1f"),
             Column("collision", "collisions", ".2f", exact=True),
             Column("tcs_reached", "T.C.s reached", ".2f", exact=True)),
    # RRT+GA has the best return and the shortest joint path but not the best success rate: with the paper's
    # m = 21 via configurations it finds no tour in about 2% of the random scenarios, where Dijkstra on Theta
    # (no limit on via points) always does
    primary=("return", +1),
    reference="rrt-ga",
    reference_success=0.9,  # 0.98 over the full suite
    policies=(
        BuiltIn("rrt-ga", rrt_ga, "reference",
                "RRT + GA on the joint matrix Theta (paper 000, eqs 1-5), followed at 2 deg per step", rrt_ga_params,
                ids=tuple(r.id for r in registry.rows_of("capaman"))),
        BuiltIn("rrt-ga", rrt_ga_capsules, "reference",
                "RRT + GA (paper 000, eqs 3-5) on a joint matrix Theta of the capsule posts' exact clearance at "
                "2 deg, followed at 2 deg per step", rrt_ga_capsules_params, ids=LADDER),
        BuiltIn("grid-dijkstra", grid_path, "other",
                "shortest path on the free cells of Theta (Dijkstra); no GA, no clearance term", grid_path_params),
        BuiltIn("grid-field", grid_field, "other", "grid-dijkstra's shortest free paths on Theta, followed from "
                "wherever the cranks are (DAgger's expert)", grid_field_params, ids=V1),
        BuiltIn("zero", zero_factory, "floor", "stand still at T.P.1"),
        BuiltIn("straight-line", straight_line, "floor", "the naive controller: each crank straight at the current "
                "target, blind to the obstacles"),
        *best_constant_floors(BEST_CONSTANT, "crank rates {action} of max_joint_step, the best of "
                              "{{-1, -0.5, 0, 0.5, 1}} per crank on reset seeds 0-29"),
        BuiltIn("slide-rule", slide_rule, "floor", "a two-line rule on v1's observation: straight at the target, "
                "sliding along the clearance's look-ahead where the clearance is low", slide_rule_params, ids=V1),
    ),
    # within 1 mm of the released settings, with joint stops, at a fraction of their cost (paragym.sim.capaman_dynamic)
    dynamics=CaPaManDynamics.split,
    demo="RRT + GA (paper 000)",
    plot_episode=plot_episode,
    plan=plan,
    validate_plan=validate_plan,
    validated_plan=validated_plan,
    solved=(Target("success", +1, 0.80),),  # the reference succeeds in 0.98
)
