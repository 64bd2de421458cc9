"""The train-test gap: PPO trained on K fixed scenarios (``train_scenarios=K``), then played on them and on unseen ones.

A rung of a task can be learned from a finite set of scenarios, as Procgen's ``num_levels`` does, and
evaluated on scenarios it never saw. For each K of ``--levels`` (0: a new scenario every episode) and each
seed, ``paragym.baselines.training.train`` trains PPO with the env's ``ppo.yml`` settings on the native vector
env for ``--timesteps`` steps; then the deterministic policy plays ``--episodes`` episodes on the training
levels (reset seeds 0 to K-1, which draw exactly those scenarios, each once) and on unseen scenarios (the
leaderboard's reset seeds, 100000 + 1000 seed + episode of evaluation seed 0). The table gives both
success rates with Wilson's 95 % intervals and their gap; a gap whose intervals do not overlap is marked.

    python benchmarks/generalisation.py [--env ID] [--levels 5 50 0] [--seeds 1] [--timesteps 300000]
                                        [--episodes 50] [--out results/generalisation] [--record]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gymnasium as gym
from results_file import add_record_option, paragraph, record

import paragym  # noqa: F401
from paragym.baselines.leaderboard.suite import episode_seed
from paragym.baselines.stats import separable, wilson
from paragym.baselines.training import train


def success(model: object, env_id: str, seeds: list[int]) -> int:
    """Successes of ``model``'s deterministic actions over the episodes reset with ``seeds`` (no fixed levels)."""
    env = gym.make(env_id)
    wins = 0
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        while True:
            action, _ = model.predict(obs, deterministic=True)
            obs, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
        wins += bool(info["is_success"])
    env.close()
    return wins


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="paragym/HybridSingularityFree-v2")
    parser.add_argument("--levels", type=int, nargs="+", default=[5, 50, 0],
                        help="training set sizes K (0: a new scenario every episode)")
    parser.add_argument("--seeds", type=int, default=1, help="training seeds per K")
    parser.add_argument("--timesteps", type=int, default=300_000)
    parser.add_argument("--episodes", type=int, default=50, help="evaluation episodes on each side")
    parser.add_argument("--out", default="results/generalisation", help="folder of the trained models")
    add_record_option(parser)
    args = parser.parse_args()
    unseen = [episode_seed(0, k) for k in range(args.episodes)]
    rows = []
    for levels in args.levels:
        for seed in range(args.seeds):
            start = time.perf_counter()
            kwargs = {"train_scenarios": levels} if levels else {}
            run = train(args.env, "ppo", seed=seed, timesteps=args.timesteps, progress_bar=False, vectorized=True,
                        models_dir=Path(args.out) / f"K{levels or 'all'}", hyperparams={"env_kwargs": kwargs})
            # the training levels are the scenarios of reset seeds 0..K-1, each played once (a deterministic
            # policy on one scenario is one outcome, not K); with no K, scenarios of seeds 0 on
            trained = list(range(min(levels, args.episodes) if levels else args.episodes))
            n, m = len(trained), len(unseen)
            on_train, on_unseen = success(run.model, args.env, trained), success(run.model, args.env, unseen)
            ci_train, ci_unseen = wilson(on_train, n), wilson(on_unseen, m)
            rows.append([str(levels or "all"), seed,
                         f"{on_train / n:.2f} [{ci_train[0]:.2f}, {ci_train[1]:.2f}] of {n}",
                         f"{on_unseen / m:.2f} [{ci_unseen[0]:.2f}, {ci_unseen[1]:.2f}] of {m}",
                         f"{on_train / n - on_unseen / m:+.2f}"
                         + (" (apart)" if separable(ci_train, ci_unseen) else ""),
                         f"{(time.perf_counter() - start) / 60:.1f}"])
            print(" | ".join(map(str, rows[-1])), flush=True)
    columns = ["train scenarios K", "seed", "success on the K [95% CI]", "success unseen [95% CI]", "gap",
               "minutes"]
    print("\n" + " | ".join(columns))
    for r in rows:
        print(" | ".join(map(str, r)))
    if args.record:
        record("generalisation", f"Train-test gap of PPO on {args.env.split('/')[-1]}", paragraph(__doc__, 1),
               columns, rows, order=60, folder=args.record)


if __name__ == "__main__":
    main()
