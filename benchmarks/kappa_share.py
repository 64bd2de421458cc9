"""How far into the least-norm motion's excess each method's mean kappa lies on the Orthoglide's rungs: whether a
tighter success threshold (the rung's ``share``) could separate the paper's method from the cheap ones.

A rung asks for a mean kappa at most ``share`` of the way from 1 to the least-norm motion's on the same lap
(:class:`~paragym.tasks.orthoglide.OrthoglideRung`). For every episode of the committed leaderboard
(``leaderboard/episodes.csv``) on the Orthoglide's rungs, the lap's threshold is read back from the env reset
with the episode's seed (``info["kappa_bound"]``), and the episode's mean kappa is placed on the same scale: the
share of the least-norm excess it reached. Printed per rung and method: the successes, and the median and 90th
percentile of that share over the successful episodes. A share between the reference's and a cheap method's
would separate them; where they coincide, no threshold can.

    python benchmarks/kappa_share.py
"""

from __future__ import annotations

import argparse
import csv
import warnings
from collections import defaultdict
from pathlib import Path

import gymnasium as gym
import numpy as np

import paragym  # noqa: F401
from paragym import registry
from paragym.tasks.orthoglide import LADDER

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", default=str(ROOT / "leaderboard" / "episodes.csv"))
    args = parser.parse_args()
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    rungs = {r.id: r for r in registry.ladder_of("orthoglide")}
    with open(args.episodes, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["env"] in rungs and r["mean_kappa"]]
    print(f"{'rung':32s} {'policy':20s} {'success':>8s} {'median share':>13s} {'p90 share':>10s}")
    for env_id, row in rungs.items():
        share = LADDER[row.rung].share
        env, bounds = gym.make(env_id), {}
        reached: dict[str, list[tuple[float, bool]]] = defaultdict(list)
        for r in rows:
            if r["env"] != env_id:
                continue
            seed = int(r["reset_seed"])
            if seed not in bounds:
                bounds[seed] = float(env.reset(seed=seed)[1]["kappa_bound"])
            reached[r["policy"]].append((share * (float(r["mean_kappa"]) - 1) / (bounds[seed] - 1),
                                         r["success"] == "1"))
        env.close()
        for policy, got in sorted(reached.items()):
            frac = np.array([x for x, _ in got])
            ok = np.array([w for _, w in got])
            cells = (f"{np.median(frac[ok]):13.3f} {np.quantile(frac[ok], 0.9):10.3f}" if ok.any()
                     else f"{'-':>13s} {'-':>10s}")
            print(f"{row.name:32s} {policy:20s} {ok.mean():8.2f} {cells}")


if __name__ == "__main__":
    main()
