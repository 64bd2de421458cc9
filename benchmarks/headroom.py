"""Headroom on both sides: floors' and reference's success per scenario family of the newest ids and the rungs.

A task separates methods when its floors fail, the paper's method succeeds and learned agents sit between.
For each newest id and each rung (or ``--env``) and each of its named scenarios, every floor (zero, random and
the task's naive controller), the reference and the shipped learned agents of training seed 0 play ``--episodes``
episodes (the leaderboard's reset seeds, 100000 + k), and the table gives each success rate with Wilson's
95 % interval against the headroom bounds: zero and random at most 0.10, a naive floor at most 0.30 and its
interval below the reference's, the reference at least 0.90 (the learned agents have none), and each family's
verdict by the ladder's rule (:func:`paragym.baselines.leaderboard.summary.rung_verdict`): hard only where
the reference's interval lies above that of every other method played, floors and learned agents alike (PPO,
BC, linear CEM). A family that misses a bound is one a difficulty ladder has to redesign. The figure shows every
rate with its interval.

    python benchmarks/headroom.py [--env ID ...] [--episodes 50] [--figure PNG] [--record]
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import gymnasium as gym
from results_file import RESULTS, add_record_option, paragraph, record

import paragym  # noqa: F401
from paragym import registry
from paragym.baselines.leaderboard.suite import episode_seed
from paragym.baselines.leaderboard.summary import rung_verdict
from paragym.baselines.policies import policies_for
from paragym.baselines.stats import ahead, wilson
from paragym.baselines.tasks import bench_of
from paragym.planners.base import PlanningError
from paragym.rollout import run_episode

#: the headroom bounds on every rung: (kind of row, highest or lowest success, which side)
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
    parser.add_argument("--figure", default=None, help="where the figure goes (default with --record: "
                                                       "docs/reports/headroom.png, or beside a result file written "
                                                       "to another folder; else none)")
    add_record_option(parser)
    args = parser.parse_args()
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    ids = [registry.check_env_id(e) for e in args.env] if args.env else [
        *registry.newest(), *(r.id for task in dict.fromkeys(r.task for r in registry.rows())
                              for r in registry.ladder_of(task))]
    rows, missed, points, hard = [], 0, [], 0
    for env_id in ids:
        bench = bench_of(env_id)
        specs = {name: spec for name, spec in policies_for(env_id).items()
                 if spec.kind == "floor" or name == bench.reference
                 or (spec.kind == "learned" and name.endswith("-seed0"))}
        for scenario in registry.row(env_id).scenario_names:
            found = {name: successes(env_id, scenario, spec, args.episodes) for name, spec in specs.items()}
            ref = wilson(found[bench.reference], args.episodes)
            for name, wins in found.items():
                rate, ci = wins / args.episodes, wilson(wins, args.episodes)
                role = ("reference" if name == bench.reference else "learned" if specs[name].kind == "learned"
                        else name if name in ("zero", "random") else "naive")
                points.append((env_id.split("/")[-1], scenario, name, role, rate, ci))
                if role == "learned":
                    rows.append([env_id.split("/")[-1], scenario, name, role,
                                 f"{rate:.2f} [{ci[0]:.2f}, {ci[1]:.2f}]", "-", "-"])
                    print(" | ".join(rows[-1]), flush=True)
                    continue
                bound, side = BOUNDS[role]
                ok = rate >= bound if side == "at least" else rate <= bound
                if role == "naive":
                    ok = ok and ahead(ref, ci, +1)
                missed += not ok
                rows.append([env_id.split("/")[-1], scenario, name, role, f"{rate:.2f} [{ci[0]:.2f}, {ci[1]:.2f}]",
                             f"{side} {bound:.2f}" + (", apart from the reference" if role == "naive" else ""),
                             "ok" if ok else "MISSED"])
                print(" | ".join(rows[-1]), flush=True)
            # the ladder's rule (docs/ladders.md): hard only where the reference's interval lies above every other's
            cis = {("reference" if n == bench.reference else n): {env_id: dict(zip(
                ("success_ci_low", "success_ci_high"), wilson(w, args.episodes), strict=True))}
                for n, w in found.items()}
            verdict = rung_verdict(cis, env_id)
            hard += verdict == "hard"
            rows.append([env_id.split("/")[-1], scenario, "(every method)", "verdict", "-",
                         "the reference's interval above every other's", verdict])
            print(" | ".join(rows[-1]), flush=True)
    judged = sum(r[-1] != "-" and r[3] != "verdict" for r in rows)
    families = sum(r[3] == "verdict" for r in rows)
    print(f"\n{missed} of {judged} rows miss their bound ({args.episodes} episodes each); {hard} of {families} "
          f"scenario families hard, the rest sanity")
    figure = Path(args.figure) if args.figure else None
    if figure is None and args.record:  # the speed page's picture, or beside a result file written elsewhere
        folder = Path(args.record).resolve()
        figure = DOCS / FIGURE if folder == RESULTS.resolve() else folder / "headroom.png"
    if figure is not None:
        plot(points, figure, args.episodes)
        print(f"wrote {figure}")
    if args.record:
        record("headroom", "Headroom: floors, learned agents and reference per scenario family",
               paragraph(__doc__, 1), ["env", "scenario", "policy", "role", "success [95% CI]", "bound", "verdict"],
               rows, order=70, folder=args.record, figure=FIGURE)


DOCS = Path(__file__).resolve().parents[1] / "docs"
#: the figure the speed page shows beside the table (under docs/)
FIGURE = "reports/headroom.png"
#: each role's colour in the figure
COLOURS = {"reference": "tab:green", "learned": "tab:blue", "naive": "tab:orange", "zero": "tab:gray",
           "random": "tab:red"}


def plot(points: list[tuple], path: Path, episodes: int) -> None:
    """Success against scenario family, one panel per env, a marker per policy with its interval."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = list(dict.fromkeys(p[0] for p in points))
    fig, axes = plt.subplots(1, len(envs), figsize=(4.2 * len(envs), 3.6), squeeze=False)
    for ax, env in zip(axes[0], envs, strict=True):
        mine = [p for p in points if p[0] == env]
        families = list(dict.fromkeys(p[1] for p in mine))
        names = list(dict.fromkeys(p[2] for p in mine))
        for j, name in enumerate(names):
            xs, ys, lo, hi, role = [], [], [], [], ""
            for p in mine:
                if p[2] == name:
                    xs.append(families.index(p[1]) + (j - (len(names) - 1) / 2) * 0.12)
                    ys.append(p[4])
                    lo.append(p[4] - p[5][0])
                    hi.append(p[5][1] - p[4])
                    role = p[3]
            ax.errorbar(xs, ys, yerr=[lo, hi], fmt="o", ms=4, capsize=2, label=name, color=COLOURS[role])
        ax.set_xticks(range(len(families)), families, rotation=30, ha="right")
        ax.set_ylim(-0.05, 1.05)
        ax.set_title(env, fontsize=9)
        ax.axhline(0.9, color="tab:green", lw=0.6, ls=":")
        ax.axhline(0.1, color="tab:gray", lw=0.6, ls=":")
        ax.legend(fontsize=6, loc="best")
    axes[0][0].set_ylabel(f"success ({episodes} episodes, 95 % CI)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
