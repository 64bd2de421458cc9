"""The paper's method under physics: each newest id's reference over many dynamic episodes, with the KF check.

For each newest id and each rung of each task's newest ladder (or ``--env``) the bench's reference plays
``--episodes`` episodes in the dynamic fidelity (PyBullet's dynamics under force-limited motors, the
leaderboard's settings): the paper's scenario first, then random scenarios of reset seeds 300001, 300002, ...
(apart from the leaderboard's 200001-200002). Each is run and measured by the leaderboard's own
:func:`~paragym.baselines.leaderboard.evaluate.evaluate_dynamic`: success, and the KF check of what the motors
executed against what the policy commanded. The table gives success, KF PASS and both, each with Wilson's 95 %
interval, against a target of 0.90 for both; the failing episodes are printed with their figures of merit.

    python benchmarks/reference_dynamic.py [--env ID ...] [--episodes 30] [--policy NAME] [--engine mujoco]
                                           [--record]
"""

from __future__ import annotations

import argparse
import time

from results_file import add_record_option, engine_versions, paragraph, record

from paragym import registry
from paragym.baselines.leaderboard.evaluate import evaluate_dynamic
from paragym.baselines.policies import get_policy
from paragym.baselines.stats import wilson
from paragym.baselines.tasks import bench_of

#: the first random scenario's reset seed (the leaderboard's dynamic episodes use 200001 onwards)
FIRST_SEED = 300_001
#: the target: the reference succeeds with KF PASS in at least this share of dynamic episodes
TARGET = 0.90


def scenario_of(i: int) -> tuple[str, int]:
    """Episode ``i``'s scenario and reset seed: the paper's case first, then random ones from :data:`FIRST_SEED`."""
    return ("paper", 0) if i == 0 else ("random", FIRST_SEED + i - 1)


def default_ids() -> list[str]:
    """Every newest id, each followed by the rungs of its task's newest ladder, easiest first."""
    ids = []
    for env_id in registry.newest():
        ladders = registry.ladders(registry.task_of(env_id))
        ids += [env_id] + [r.id for r in (ladders[-1] if ladders else ())]
    return ids


def rate(k: int, n: int) -> str:
    low, high = wilson(k, n)
    return f"{k}/{n} = {k / n:.2f} [{low:.2f}, {high:.2f}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", default=None,
                        help="an env id (repeatable; default: the newest ids and the rungs of each newest ladder)")
    parser.add_argument("--episodes", type=int, default=30, help="dynamic episodes per env, the paper's first")
    parser.add_argument("--policy", default=None, help="a policy name (default: each bench's reference)")
    parser.add_argument("--engine", default="pybullet", choices=("pybullet", "mujoco"),
                        help="the dynamic fidelity's engine (ids whose task does not run it are left out)")
    add_record_option(parser)
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    rows = []
    for env_id in args.env or default_ids():
        if args.engine not in registry.row(env_id).engines:
            print(f"{env_id}: its task's dynamic fidelity does not run in {args.engine}; left out", flush=True)
            continue
        name = args.policy or bench_of(env_id).reference
        spec = get_policy(env_id, name)
        t0 = time.perf_counter()
        won = passed = both = 0
        for i in range(args.episodes):
            scenario, seed = scenario_of(i)
            row = evaluate_dynamic(spec, scenario, seed, engine=args.engine)
            won, passed, both = won + row.success, passed + row.kf_passed, both + (row.success and row.kf_passed)
            if not (row.success and row.kf_passed):
                merit = ", ".join(f"{k} {v:.3g}" for k, v in row.metrics.items())
                verdict = "PASS" if row.kf_passed else "FAIL"
                print(f"  {env_id} {scenario} seed {seed}: success {row.success}, KF {verdict} ({row.kf['worst']}); "
                      f"{merit}", flush=True)
        n = args.episodes
        rows.append([env_id, args.engine, name, rate(won, n), rate(passed, n), rate(both, n),
                     "meets" if both / n >= TARGET else "misses",
                     f"{time.perf_counter() - t0:.0f}"])
        print(" | ".join(rows[-1]), flush=True)
    columns = ["env", "engine", "policy", "success", "KF PASS", "both", f"target {TARGET:.2f}", "seconds"]
    if args.record:
        suffix, title = ("", "") if args.engine == "pybullet" else (f"_{args.engine}", ", in MuJoCo")
        record(f"reference_dynamic{suffix}", f"The paper's method under physics{title}", paragraph(__doc__),
               columns, rows, order=60, folder=args.record, source=engine_versions())


if __name__ == "__main__":
    main()
