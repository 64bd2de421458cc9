"""Headroom on both sides: the floors' and the reference's success on every scenario family of the newest ids.

A task separates methods when its floors fail and the paper's method succeeds. For each newest id (or
``--env``) and each of its named scenarios, every floor (zero, random and the task's naive controller) and
the reference play ``--episodes`` episodes (the leaderboard's reset seeds, 100000 + k), and the table gives
each success rate with Wilson's 95 % interval against issue 40's bounds: zero and random at most 0.10, a
naive floor at most 0.30 and its interval below the reference's, the reference at least 0.90. A family that
misses a bound is one a difficulty ladder has to redesign.

    python benchmarks/headroom.py [--env ID ...] [--episodes 50] [--record]
"""

from __future__ import annotations

import argparse
import warnings

import gymnasium as gym
from results_file import add_record_option, paragraph, record

import paragym  # noqa: F401
from paragym import registry
from paragym.baselines.leaderboard.suite import episode_seed
from paragym.baselines.policies import policies_for
from paragym.baselines.stats import ahead, wilson
from paragym.baselines.tasks import bench_of
from paragym.planners.base import PlanningError
from paragym.rollout import run_episode

#: issue 40's bounds on every rung: (kind of row, highest or lowest success, which side)
BOUNDS = {"zero": (0.10, "at most"), "random": (0.10, "at most"), "naive": (0.30, "at most"),
          "reference": (0.90, "at least")}


def successes(env_id: str, scenario: str, spec: object, episodes: int) -> int:
    """Successes of ``spec`` over ``episodes`` episodes of ``scenario`` (a planner that finds no plan fails)."""
    env = gym.make(env_id, scenario=scenario)
    wins = 0
    for k in range(episodes):
        seed = episode_seed(0, k)
        try:
            wins += bool(run_episode(env, spec.factory(env, seed), seed=seed).success)
        except PlanningError:
            pass
    env.close()
    return wins


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", default=None, help="only this env id (repeatable)")
    parser.add_argument("--episodes", type=int, default=50)
    add_record_option(parser)
    args = parser.parse_args()
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    ids = [registry.check_env_id(e) for e in args.env] if args.env else list(registry.newest())
    rows, missed = [], 0
    for env_id in ids:
        bench = bench_of(env_id)
        specs = {name: spec for name, spec in policies_for(env_id).items()
                 if spec.kind == "floor" or name == bench.reference}
        for scenario in registry.row(env_id).scenario_names:
            found = {name: successes(env_id, scenario, spec, args.episodes) for name, spec in specs.items()}
            ref = wilson(found[bench.reference], args.episodes)
            for name, wins in found.items():
                role = "reference" if name == bench.reference else name if name in ("zero", "random") else "naive"
                bound, side = BOUNDS[role]
                rate, ci = wins / args.episodes, wilson(wins, args.episodes)
                ok = rate >= bound if side == "at least" else rate <= bound
                if role == "naive":
                    ok = ok and ahead(ref, ci, +1)
                missed += not ok
                rows.append([env_id.split("/")[-1], scenario, name, role, f"{rate:.2f} [{ci[0]:.2f}, {ci[1]:.2f}]",
                             f"{side} {bound:.2f}" + (", apart from the reference" if role == "naive" else ""),
                             "ok" if ok else "MISSED"])
                print(" | ".join(rows[-1]), flush=True)
    print(f"\n{missed} of {len(rows)} rows miss their bound ({args.episodes} episodes each)")
    if args.record:
        record("headroom", "Headroom: floors and reference per scenario family", paragraph(__doc__, 1),
               ["env", "scenario", "policy", "role", "success [95% CI]", "bound", "verdict"], rows, order=70,
               folder=args.record)


if __name__ == "__main__":
    main()
