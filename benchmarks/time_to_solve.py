"""Time to solve: wall-clock minutes of PPO from scratch (or SAC, TQC, a linear search) until a task counts as solved.

For each env id (default: the newest version of every task) and each seed, ``paragym train`` trains PPO from scratch
with the env's settings in ``baselines/hyperparams/ppo.yml`` (as a user would run it, its own evaluations and
checkpoints included; ``init_from``, a behaviour clone to start from, is dropped); ``--algo sac`` or ``tqc`` trains
that algorithm with its own yml's settings instead; with ``--algo cem``, the cross-entropy search of linear policies
(:mod:`paragym.baselines.cem`, its default settings) runs instead, its mean checked the same way. ``--fidelity
dynamic`` trains and checks under physics (``--engine``, the leaderboard's settings: ``paragym train --fidelity
dynamic``), its runs apart from the kinematic ones. Every ``--check-every`` seconds of learning, the deterministic
policy plays ``--episodes`` validation episodes and the task's targets are checked (:mod:`paragym.baselines.solve`;
the targets are the task bench's ``solved``, e.g. CaPaMan: success >= 0.80). The checks' own time is left out of the
clock. A run stops when solved or after ``--budget`` minutes of learning.

Each run is written to ``OUT/<env name>-seed<N>.json`` (the points, the
targets and their bounds, what produced it) as soon as it ends, and a run
already there is taken as it is, so an interrupted benchmark goes on where it
stopped. A run checked against other targets than the task states today (a
floor beaten on the mean, before the paired comparison) is run again;
``--force`` runs every run again; ``--report-only`` trains nothing and
reports the runs found. Then the table (minutes to solve per seed; the mean
of the solved seeds with its 95 % interval, Student t, cut to [0, budget]),
the learning curves with their interval over seeds
(``OUT/time_to_solve.png``) and ``OUT/time_to_solve.md``.

    python benchmarks/time_to_solve.py [--env ID ...] [--seeds 3] [--budget 30] [--out results/time_to_solve]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from results_file import add_record_option, record  # this folder is on the path when it runs

import paragym
from paragym.baselines.cem import CemSettings, train_cem
from paragym.baselines.solve import SolveCheck, stop_search_when_solved, stop_when_solved
from paragym.baselines.stats import mean_ci
from paragym.baselines.tasks import bench_of, dynamic_kwargs
from paragym.baselines.training import train
from paragym.registry import check_env_id, newest, row

#: the speed page's paragraph above this script's table (``--record``)
PARAGRAPH = (
    "PPO trained from scratch, 3 seeds per task, and the wall-clock minutes of learning on 2 cores until "
    "the task counts as solved (its bench's solved targets), checked every minute of learning on 20 "
    "validation episodes; a target against another policy is met when the 95 % interval (Student's t) of "
    "the paired gap lies wholly on the better side. "
)


def run_one(env_id: str, seed: int, args: argparse.Namespace) -> dict[str, Any]:
    """One training run of ``args.algo`` on ``env_id`` from ``seed``, checked as it learns (module docstring)."""
    dynamic = {} if args.fidelity == "kinematic" else dynamic_kwargs(env_id, args.engine)
    check = SolveCheck(env_id, args.episodes, env_kwargs=dynamic)
    points: list[Any] = []
    t0 = time.perf_counter()
    if args.algo == "cem":  # the linear search: its budget, its checks' time left out
        train_cem(env_id, seed, CemSettings(budget_seconds=args.budget * 60, generations=10**9),
                  models_dir=args.out / "models", force=True,
                  stop=stop_search_when_solved(check, args.check_every, points))
    else:  # from scratch, also where PPO's yml starts from a behaviour clone
        stop = stop_when_solved(check, args.check_every, args.budget * 60, points)
        train(env_id, args.algo, seed, timesteps=args.max_timesteps, models_dir=args.out / "models",
              progress_bar=False, threads=args.threads, force=True, callbacks=[stop], vectorized=args.vectorized,
              hyperparams={"init_from": None} if args.algo == "ppo" else None, fidelity=args.fidelity,
              engine=args.engine)
    wall = time.perf_counter() - t0
    check.close()
    solved = next((p for p in points if p.solved), None)
    return {
        "env_id": env_id, "seed": seed, "targets": check.describe(), "keys": [t.key for t in check.targets],
        "bounds": list(check.bounds),
        "algo": args.algo, "vectorized": args.vectorized, "episodes": args.episodes, "fidelity": args.fidelity,
        "engine": args.engine if args.fidelity == "dynamic" else None,
        "budget_minutes": args.budget, "check_every_seconds": args.check_every,
        "solved": solved is not None,
        "minutes": None if solved is None else solved.seconds / 60,
        "timesteps": None if solved is None else solved.timesteps,
        "points": [{"timesteps": p.timesteps, "minutes": p.seconds / 60, "figures": p.figures, "solved": p.solved}
                   for p in points],
        "wall_minutes": wall / 60,
        "produced_by": {"paragym": paragym.__version__, "command": " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]),
                        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
                        "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")},
    }


def rules(targets: str) -> list[str]:
    """The targets of a run's ``targets`` record without their bounds: "a (0.8); b < zero's (paired, 95 %) (9.5)"
    gives ["a", "b < zero's (paired, 95 %)"]."""
    return [part.rsplit(" (", 1)[0] for part in targets.split("; ")]


def stored_run(path: Path, env_id: str, fidelity: str = "kinematic") -> dict[str, Any] | None:
    """The run stored at ``path`` if it was checked against the targets ``env_id``'s task states today, in
    ``fidelity``, else None (a run checked under other targets, e.g. a floor beaten on the mean before the paired
    comparison, is not today's result)."""
    result = json.loads(path.read_text())
    today = [t.describe() for t in bench_of(env_id).solved if t.applies(env_id)]
    return result if rules(result["targets"]) == today and result.get("fidelity", "kinematic") == fidelity else None


def tag(args: argparse.Namespace) -> str:
    """What the runs' files and rows add to the env's name: nothing for the kinematic fidelity."""
    return "" if args.fidelity == "kinematic" else f"-dynamic-{args.engine}"


def curve(runs: list[dict[str, Any]], key: str, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mean of ``key`` over the runs at each time of ``grid`` (min) and its 95 % interval; each run holds
    its last checked figure (and, once it stopped, its last figure) until its next check."""
    values = []
    for r in runs:
        t = np.array([p["minutes"] for p in r["points"]])
        v = np.array([p["figures"][key] for p in r["points"]])
        idx = np.searchsorted(t, grid, side="right") - 1
        values.append(np.where(idx >= 0, v[np.maximum(idx, 0)], np.nan))
    values = np.array(values)
    mean, low, high = [], [], []
    for col in values.T:
        col = col[np.isfinite(col)]
        mean.append(col.mean() if len(col) else np.nan)
        lo, hi = mean_ci(col) if len(col) > 1 else (np.nan, np.nan)
        low.append(lo)
        high.append(hi)
    return np.array(mean), np.array(low), np.array(high)


def how_far(runs: list[dict[str, Any]]) -> str:
    """How far the unsolved runs got, per seed: the steps learned and the first target's figure at the last check
    (and its range over the checks); "-" where every run solved."""
    shown = []
    for r in runs:
        if r["minutes"] is not None or not r["points"]:
            continue
        key, last = r["keys"][0], r["points"][-1]
        seen = [p["figures"][key] for p in r["points"]]
        shown.append(f"seed {r['seed']}: {last['timesteps']:,} steps, {key} {last['figures'][key]:.2f} at the "
                     f"last check ({min(seen):.2f}-{max(seen):.2f} over the checks)")
    return "; ".join(shown) or "-"


def report(by_env: dict[str, list[dict[str, Any]]], budget: float, out: Path) -> str:
    """The table as markdown, and the curves' picture."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lines = ["| environment | targets | seeds solved | minutes to solve, per seed | mean [95% CI] "
             "| steps to solve, mean | unsolved runs at the budget's end |", "|---|---|---|---|---|---|---|"]
    fig, axes = plt.subplots(1, len(by_env), figsize=(4.2 * len(by_env), 3.4), squeeze=False)
    for ax, (env_id, runs) in zip(axes[0], by_env.items(), strict=True):
        minutes = [r["minutes"] for r in runs]
        solved = [m for m in minutes if m is not None]
        per_seed = ", ".join(f"{m:.1f}" if m is not None else f"> {budget:g}" for m in minutes)
        if len(solved) > 1:
            lo, hi = mean_ci(solved)
            lo, hi = max(lo, 0.0), min(hi, budget)  # minutes of learning lie between 0 and the budget
            mean = f"{np.mean(solved):.1f} [{lo:.1f}, {hi:.1f}]"
            mean += "" if len(solved) == len(runs) else " (solved only)"
        else:
            mean = f"{solved[0]:.1f} (one seed)" if solved else "not solved"
        steps = [r["timesteps"] for r in runs if r["timesteps"] is not None]
        lines.append(f"| {env_id.split('/')[-1]} | {runs[0]['targets']} | {len(solved)} of {len(runs)} | {per_seed} | "
                     f"{mean} | {f'{np.mean(steps):,.0f}' if steps else '-'} | {how_far(runs)} |")
        if not any(r["points"] for r in runs):
            continue
        key = runs[0]["keys"][0]  # the first target's figure
        end = max(p["minutes"] for r in runs for p in r["points"])
        runs = [r for r in runs if r["points"]]
        grid = np.linspace(0, end, 200)
        mean_c, low, high = curve(runs, key, grid)
        ax.plot(grid, mean_c, color="tab:blue", label=f"mean of {len(runs)} seeds")
        ax.fill_between(grid, low, high, color="tab:blue", alpha=0.25, label="95% CI")
        for r in runs:
            ax.plot([p["minutes"] for p in r["points"]], [p["figures"][key] for p in r["points"]], ".",
                    color="grey", ms=3)
        if "bounds" in runs[0]:
            ax.axhline(runs[0]["bounds"][0], color="tab:red", lw=0.8, ls="--", label="target")
        ax.set_xlim(0, end)
        ax.set_title(env_id.split("/")[-1], fontsize=9)
        ax.set_xlabel("minutes of learning (2 cores)")
        ax.set_ylabel(key)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "time_to_solve.png", dpi=110)
    plt.close(fig)
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", help="only this env id (repeatable; the 'paragym/' may be omitted)")
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..N-1 per env (default %(default)s)")
    parser.add_argument("--budget", type=float, default=30.0, help="minutes of learning per run (default %(default)s)")
    parser.add_argument("--check-every", type=float, default=60.0, help="seconds of learning between checks")
    parser.add_argument("--episodes", type=int, default=20, help="validation episodes per check")
    parser.add_argument("--max-timesteps", type=int, default=200_000_000, help="a bound the budget ends first")
    parser.add_argument("--threads", type=int, default=2, help="PyTorch's threads")
    parser.add_argument("--vectorized", action="store_true",
                        help="train on the native vector env (n_envs robots) whatever paragym.yml says")
    parser.add_argument("--algo", choices=("ppo", "sac", "tqc", "cem"), default="ppo",
                        help="PPO from scratch, SAC or TQC with their yml settings, or cem: the search of linear "
                             "policies, its budget the same minutes")
    parser.add_argument("--fidelity", choices=("kinematic", "dynamic"), default="kinematic",
                        help="train and check under physics with 'dynamic' (default %(default)s)")
    parser.add_argument("--engine", choices=("pybullet", "mujoco"), default="pybullet",
                        help="the dynamic fidelity's engine (default %(default)s)")
    parser.add_argument("--out", type=Path, default=None,
                        help="where the runs go (default results/time_to_solve, and results/time_to_solve_<algo> "
                             "for another algorithm)")
    parser.add_argument("--force", action="store_true", help="run again the runs already in OUT")
    parser.add_argument("--report-only", action="store_true", help="train nothing: the report of the runs in OUT")
    add_record_option(parser)
    args = parser.parse_args()
    if args.seeds < 1 or args.budget <= 0 or args.check_every <= 0:
        parser.error("--seeds, --budget and --check-every must be positive")
    if args.episodes < 2:
        parser.error(f"--episodes must be at least 2 (a target against another policy compares episode by "
                     f"episode); got {args.episodes}")
    if args.fidelity == "dynamic" and args.algo == "cem":
        parser.error("--fidelity dynamic trains ppo, sac or tqc (the linear search runs the kinematic fidelity)")
    if args.engine != "pybullet" and args.fidelity != "dynamic":
        parser.error("--engine is the dynamic fidelity's: give --fidelity dynamic too")
    ids = [check_env_id(e) for e in args.env] if args.env else list(newest())
    args.out = args.out or Path("results/time_to_solve" + ("" if args.algo == "ppo" else f"_{args.algo}"))
    args.out.mkdir(parents=True, exist_ok=True)
    by_env: dict[str, list[dict[str, Any]]] = {}
    missing: list[str] = []
    for env_id in ids:
        for seed in range(args.seeds):
            path = args.out / f"{row(env_id).name}{tag(args)}-seed{seed}.json"
            result = stored_run(path, env_id, args.fidelity) if path.exists() and not args.force else None
            if result is not None:
                print(f"{env_id} seed {seed}: taken from {path}")
            elif args.report_only:
                why = f"under today's targets ({path} was checked against others)" if path.exists() else f"(no {path})"
                print(f"{env_id} seed {seed}: not run yet {why}")
                missing.append(f"{env_id.split('/')[-1]} seed {seed}")
                continue
            else:
                result = run_one(env_id, seed, args)
                path.write_text(json.dumps(result, indent=1))
            shown = (f"solved in {result['minutes']:.1f} min" if result["solved"] else
                     f"not solved in {result['budget_minutes']:g} min")
            print(f"{env_id} seed {seed}: {shown}, {result['targets']}", flush=True)
            by_env.setdefault(env_id + tag(args), []).append(result)
    if not by_env:
        raise SystemExit(f"no runs in {args.out}")
    table = report(by_env, args.budget, args.out)
    first = next(iter(by_env.values()))[0]["produced_by"]
    text = (f"# Time to solve\n\nPPO from scratch with each env's `ppo.yml` settings, {args.seeds} seeds, "
            f"{args.fidelity} fidelity{f' ({args.engine})' if args.fidelity == 'dynamic' else ''}, "
            f"a budget of {args.budget:g} minutes of learning; checked every {args.check_every:g} s of learning on "
            f"{args.episodes} validation episodes. {first['machine']}, paragym {first['paragym']}, {first['date']}.\n\n"
            f"{table}\n\n![learning curves](time_to_solve.png)\n"
            + (f"\nNot run yet: {', '.join(missing)}.\n" if missing else ""))
    (args.out / "time_to_solve.md").write_text(text)
    if args.record:
        lines = [r for r in table.splitlines() if r.startswith("|")]
        cells = [[c.strip() for c in r.strip("|").split("|")] for r in lines]
        title = "Time to solve: PPO from scratch until the task counts as solved" + (
            "" if args.fidelity == "kinematic" else f", under {args.engine}'s dynamics")
        paragraph = PARAGRAPH if args.fidelity == "kinematic" else (
            f"PPO trained from scratch under {args.engine}'s dynamics (the leaderboard's physics settings; the "
            f"robots of the task's native dynamic vector env where it has one, MuJoCo alone, all stepped at once, "
            f"else one env per process; the checks under the leaderboard's physics), "
            f"{args.seeds} seed{'s' * (args.seeds > 1)} per task, "
            f"and the wall-clock minutes of learning on 2 cores until the task counts as solved, checked every "
            f"{args.check_every:g} s of learning on {args.episodes} validation episodes; the yml's settings are the "
            f"kinematic fidelity's.")
        record(f"time_to_solve{tag(args).replace('-', '_')}", title, paragraph,
               cells[0], cells[2:], order=30, folder=args.record,
               figure="reports/time_to_solve.png" if args.fidelity == "kinematic" else None)
    print("\n" + table + f"\n\nwrote {args.out / 'time_to_solve.md'} and {args.out / 'time_to_solve.png'}")


if __name__ == "__main__":
    main()
