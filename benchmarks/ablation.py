"""The ablation behind the v1 envs (issue 17): each row a design change, trained and measured the same way.

    python benchmarks/ablation.py --task tripod --out runs/ablation [--rows 0 3]
    python benchmarks/ablation.py --task capaman --out runs/ablation
    python benchmarks/ablation.py --task hybrid --out runs/ablation

Every row trains PPO (Stable-Baselines3) from scratch on the native vector
env of 64 robots with its task's settings (:data:`PROTOCOL`; the hybrid's:
its ``baselines/hyperparams/ppo.yml`` entry); only ``env_kwargs`` and the
row's overrides change, for the row's env
steps and the same training seed, then evaluates the deterministic
policy on the leaderboard's first evaluation seeds (reset seeds 100000 +
k, random scenarios; ``--full-suite``: the full leaderboard's 50) in the
single env of the row's settings. It prints
one markdown row per design, with the row of each floor and reference, and
writes them to ``<out>/ablation-<task>.md``; the numbers in
``baselines/ABLATION.md`` come from it.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import paragym  # noqa: F401
from paragym.baselines.policies import get_policy
from paragym.baselines.training import load_model, train
from paragym.planners.base import PlanningError
from paragym.units import DEG

#: task -> [(row label, env id, env kwargs, PPO overrides, env steps)], in the order they were tried
ROWS: dict[str, list[tuple[str, str, dict[str, Any], dict[str, Any], int]]] = {
    "tripod": [
        ("v0 (accumulated corrections, world-frame obs), PPO", "paragym/MobileTripodOdometry-v0", {},
         {"policy_kwargs": {"net_arch": [64, 64], "log_std_init": -3.0}}, 2_000_000),
        ("v1 action and obs, trust 1 per sample, v0's reward", "paragym/MobileTripodOdometry-v1",
         {"trust_rate": 1.0, "relative_reward": False}, {}, 1_000_000),
        ("+ initial action std e^-1", "paragym/MobileTripodOdometry-v1", {"trust_rate": 1.0, "relative_reward": False},
         {"policy_kwargs": {"net_arch": [64, 64], "log_std_init": -1.0}}, 2_000_000),
        ("+ trust rate 0.2 per sample", "paragym/MobileTripodOdometry-v1", {"relative_reward": False},
         {"policy_kwargs": {"net_arch": [64, 64], "log_std_init": -1.0}}, 2_000_000),
        ("+ reward against odometry (v1 as released)", "paragym/MobileTripodOdometry-v1", {},
         {"policy_kwargs": {"net_arch": [64, 64], "log_std_init": -1.0}}, 2_000_000),
        ("+ gamma 0.999, lambda 0.98, std e^-2", "paragym/MobileTripodOdometry-v1", {},
         {"gamma": 0.999, "gae_lambda": 0.98, "policy_kwargs": {"net_arch": [64, 64], "log_std_init": -2.0}},
         3_000_000),
    ],
    "capaman": [
        ("v0 (absolute obs, no look-ahead, v0 reward), PPO", "paragym/CaPaManCollisionFree-v0", {}, {}, 1_500_000),
        ("v1 as released: goal-relative obs + look-ahead, time penalty, 3 deg reach",
         "paragym/CaPaManCollisionFree-v1", {}, {}, 1_500_000),
        ("v1 with v0's reward (no time penalty, collision -5)", "paragym/CaPaManCollisionFree-v1",
         {"time_penalty": 0.0, "collision_penalty": 5.0}, {}, 1_500_000),
        ("v1 with v0's reach tolerance (1 deg)", "paragym/CaPaManCollisionFree-v1", {"reach_tolerance": 1 * DEG}, {},
         1_500_000),
    ],
    "hybrid": [
        ("v0, the shipped PPO setup", "paragym/HybridSingularityFree-v0", {}, {}, 2_000_000),
        ("v1 as released: P1, P1 solved at the split, its stroke excess and look-ahead in the observation",
         "paragym/HybridSingularityFree-v1", {}, {}, 2_000_000),
        ("v1 + shaping toward a feasible end, w_end 10", "paragym/HybridSingularityFree-v1", {"w_end": 10.0}, {},
         2_000_000),
        ("the same, longer", "paragym/HybridSingularityFree-v1", {"w_end": 10.0}, {}, 3_000_000),
        ("v1 + shaping, w_end 30", "paragym/HybridSingularityFree-v1", {"w_end": 30.0}, {}, 2_000_000),
    ],
}
#: the policies each task's table compares with (floors and reference)
BESIDE = {"tripod": ("paragym/MobileTripodOdometry-v1", ["zero", "encoder-correction"]),
          "capaman": ("paragym/CaPaManCollisionFree-v1", ["zero", "rrt-ga"]),
          "hybrid": ("paragym/HybridSingularityFree-v1", ["zero", "polynomial-detour"])}
#: the PPO of every row of a task, before the row's overrides: for the tripod and the CaPaMan the
#: settings the 0.4.0 rows were run with (the v1 entries of ppo.yml now fine-tune a behaviour clone),
#: for the hybrid its ppo.yml entry; never started from a clone
PROTOCOL = {"n_envs": 64, "policy": "MlpPolicy", "n_steps": 64, "batch_size": 1024, "n_epochs": 10, "gamma": 0.99,
            "gae_lambda": 0.95, "learning_rate": 3e-4, "ent_coef": 0.0, "clip_range": 0.2,
            "policy_kwargs": {"net_arch": [64, 64]}, "normalize": "{'norm_obs': False, 'norm_reward': True}"}


def protocol(task: str) -> dict[str, Any]:
    """The PPO settings of ``task``'s rows (:data:`PROTOCOL`)."""
    from paragym.baselines.training import load_hyperparams

    base = load_hyperparams("ppo", "paragym/HybridSingularityFree-v1") if task == "hybrid" else dict(PROTOCOL)
    return {**base, "vec_env": "native", "init_from": None}
#: the task's metric column: (label, value of an episode from its infos)
METRIC = {"tripod": ("final unit error [cm]", lambda infos: infos[-1]["unit_error"] * 100),
          "capaman": ("collisions", lambda infos: float(infos[-1]["collision"])),
          "hybrid": ("singular/limit poses", lambda infos: float(sum(not i["free"] for i in infos)))}


def evaluate(task: str, env_id: str, kwargs: dict[str, Any], act: Any, seeds: list[int],
             reset: Any = None) -> dict[str, float]:
    """Success, mean return and the task's metric over episodes reset with ``seeds``."""
    env = gym.make(env_id, **kwargs)
    success, returns, metric, unplanned = [], [], [], 0
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        if reset is not None:
            try:
                reset(obs, info)
            except PlanningError:  # a planner that finds no plan fails the episode (as in the leaderboard)
                success.append(False)
                unplanned += 1
                continue
        total, done, infos = 0.0, False, []
        while not done:
            obs, reward, terminated, truncated, info = env.step(act(obs, info))
            total += float(reward)
            infos.append(info)
            done = terminated or truncated
        success.append(bool(info["is_success"]))
        returns.append(total)
        metric.append(METRIC[task][1](infos))
    env.close()
    return {"success": float(np.mean(success)), "return": float(np.mean(returns)), "metric": float(np.mean(metric)),
            "unplanned": unplanned}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", choices=sorted(ROWS), required=True)
    parser.add_argument("--steps", type=int, default=None, help="env steps of every row (default: each row's own)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--full-suite", action="store_true",
                        help="evaluate on the full leaderboard's 50 episodes (reset seeds 100000 + 1000 s + e, "
                             "s < 5, e < 10) instead of --episodes at 100000 + k")
    parser.add_argument("--rows", type=int, nargs="*", default=None, help="row indices to run (default all)")
    parser.add_argument("--out", default="runs/ablation")
    parser.add_argument("--no-beside", action="store_true", help="skip the floor and reference rows")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    metric = METRIC[args.task][0]
    seeds = ([100_000 + 1000 * s + e for s in range(5) for e in range(10)] if args.full_suite
             else [100_000 + k for k in range(args.episodes)])
    lines = [f"| design | env steps | success | return | {metric} | train [s] |", "|---|---|---|---|---|---|"]
    env_id, names = BESIDE[args.task]
    for name in [] if args.no_beside else names:
        spec = get_policy(env_id, name)
        env = gym.make(env_id)
        policy = spec.factory(env, 0)
        r = evaluate(args.task, env_id, {}, policy.act, seeds, policy.reset)
        unplanned = f" (no plan in {r['unplanned']}; return and metric over the rest)" if r["unplanned"] else ""
        lines.append(f"| `{name}` ({spec.kind}){unplanned} | - | {r['success']:.2f} | {r['return']:.2f} | "
                     f"{r['metric']:.2f} | - |")
        print(lines[-1], flush=True)
    for index, (label, row_env, kwargs, overrides, steps) in enumerate(ROWS[args.task]):
        if args.rows is not None and index not in args.rows:
            continue
        hp = {**protocol(args.task), **overrides, "env_kwargs": kwargs, "eval_freq": 10 ** 12, "n_eval_episodes": 1}
        t0 = time.perf_counter()
        steps = args.steps or steps
        res = train(row_env, "ppo", seed=args.seed, timesteps=steps, models_dir=out / f"{args.task}-{index}",
                    progress_bar=False, force=True, vectorized=True, hyperparams=hp)
        seconds = time.perf_counter() - t0
        model = load_model(res.files.model)
        r = evaluate(args.task, row_env, kwargs, lambda obs, info, m=model: m.predict(obs, deterministic=True)[0],
                     seeds)
        lines.append(f"| {label} | {steps:,} | {r['success']:.2f} | {r['return']:.2f} | {r['metric']:.2f} | "
                     f"{seconds:.0f} |")
        print(lines[-1], flush=True)
        (out / f"{args.task}-{index}.json").write_text(json.dumps({"label": label, **r, "seconds": seconds}))
    (out / f"ablation-{args.task}.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
