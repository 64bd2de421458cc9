"""The ablation behind the v1 envs: each row a design change, trained and measured the same way.

    python benchmarks/ablation.py --task tripod --out runs/ablation [--rows 0 3]
    python benchmarks/ablation.py --task capaman --out runs/ablation
    python benchmarks/ablation.py --task hybrid --out runs/ablation

The rows are each task's bench's (``Bench.ablation``). Every row trains PPO
(Stable-Baselines3) from scratch on the native vector
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

from paragym import registry
from paragym.baselines.policies import get_policy
from paragym.baselines.tasks import Ablation, bench_of
from paragym.baselines.training import load_model, train
from paragym.planners.base import PlanningError

#: the PPO of every row of a task, before the row's overrides: for the tripod and the CaPaMan the
#: settings the 0.4.0 rows were run with (the v1 entries of ppo.yml now fine-tune a behaviour clone),
#: for the hybrid its ppo.yml entry; never started from a clone
PROTOCOL = {"n_envs": 64, "policy": "MlpPolicy", "n_steps": 64, "batch_size": 1024, "n_epochs": 10, "gamma": 0.99,
            "gae_lambda": 0.95, "learning_rate": 3e-4, "ent_coef": 0.0, "clip_range": 0.2,
            "policy_kwargs": {"net_arch": [64, 64]}, "normalize": "{'norm_obs': False, 'norm_reward': True}"}


def ablations() -> dict[str, Ablation]:
    """Every task whose bench has an ablation (:attr:`paragym.baselines.tasks.Bench.ablation`), by task."""
    found = {}
    for task in dict.fromkeys(r.task for r in registry.rows()):
        bench = bench_of(registry.rows_of(task)[0].id)
        if bench.ablation is not None:
            found[task] = bench.ablation
    return found


def protocol(ablation: Ablation) -> dict[str, Any]:
    """The PPO settings of the ablation's rows: its env's ``ppo.yml`` entry, or :data:`PROTOCOL`."""
    from paragym.baselines.training import load_hyperparams

    base = load_hyperparams("ppo", ablation.ppo_from) if ablation.ppo_from else dict(PROTOCOL)
    return {**base, "vec_env": "native", "init_from": None}


def evaluate(ablation: Ablation, env_id: str, kwargs: dict[str, Any], act: Any, seeds: list[int],
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
        metric.append(ablation.metric[1](infos))
    env.close()
    return {"success": float(np.mean(success)), "return": float(np.mean(returns)), "metric": float(np.mean(metric)),
            "unplanned": unplanned}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    found = ablations()
    parser.add_argument("--task", choices=sorted(found), required=True)
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
    ablation = found[args.task]
    metric = ablation.metric[0]
    seeds = ([100_000 + 1000 * s + e for s in range(5) for e in range(10)] if args.full_suite
             else [100_000 + k for k in range(args.episodes)])
    lines = [f"| design | env steps | success | return | {metric} | train [s] |", "|---|---|---|---|---|---|"]
    env_id, names = ablation.beside
    for name in [] if args.no_beside else names:
        spec = get_policy(env_id, name)
        env = gym.make(env_id)
        policy = spec.factory(env, 0)
        r = evaluate(ablation, env_id, {}, policy.act, seeds, policy.reset)
        unplanned = f" (no plan in {r['unplanned']}; return and metric over the rest)" if r["unplanned"] else ""
        lines.append(f"| `{name}` ({spec.kind}){unplanned} | - | {r['success']:.2f} | {r['return']:.2f} | "
                     f"{r['metric']:.2f} | - |")
        print(lines[-1], flush=True)
    for index, (label, row_env, kwargs, overrides, steps) in enumerate(
            (r.label, r.env_id, r.env_kwargs, r.overrides, r.steps) for r in ablation.rows):
        if args.rows is not None and index not in args.rows:
            continue
        hp = {**protocol(ablation), **overrides, "env_kwargs": kwargs, "eval_freq": 10 ** 12, "n_eval_episodes": 1}
        t0 = time.perf_counter()
        steps = args.steps or steps
        res = train(row_env, "ppo", seed=args.seed, timesteps=steps, models_dir=out / f"{args.task}-{index}",
                    progress_bar=False, force=True, vectorized=True, hyperparams=hp)
        seconds = time.perf_counter() - t0
        model = load_model(res.files.model)
        r = evaluate(ablation, row_env, kwargs, lambda obs, info, m=model: m.predict(obs, deterministic=True)[0],
                     seeds)
        lines.append(f"| {label} | {steps:,} | {r['success']:.2f} | {r['return']:.2f} | {r['metric']:.2f} | "
                     f"{seconds:.0f} |")
        print(lines[-1], flush=True)
        (out / f"{args.task}-{index}.json").write_text(json.dumps({"label": label, **r, "seconds": seconds}))
    (out / f"ablation-{args.task}.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
