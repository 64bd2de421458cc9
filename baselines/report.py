"""Learning curves and aggregate scores, as RL papers plot them (``paragym report``).

From the training logs (each model's JSON: its periodic evaluations) and the
leaderboard's database (every evaluated episode), :func:`write_report` writes
PNGs and a markdown page:

* per env, the learning curve of every algorithm: the mean evaluation return
  over its training seeds and a 95 % bootstrap confidence interval of that
  mean (seeds resampled with replacement), against env steps and against
  wall-clock seconds of training (evaluations included; for a log written
  before paragym 0.4.0, which has no clock per evaluation, the seconds are
  spread evenly over the steps);
* across tasks, each learned run's score normalised between the floor (0:
  the better of the ``zero`` and ``random`` policies' mean return) and the
  reference (1: the paper's method's mean return) on the latest version of
  every task, aggregated with rliable: the interquartile mean with a
  stratified-bootstrap 95 % interval, and the probability of improvement of
  each algorithm over each other.
"""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

import paragym
from paragym import registry
from paragym.baselines.policies import policies_for
from paragym.baselines.stats import BOOTSTRAP_REPS, bootstrap_mean_ci
from paragym.baselines.store import ResultStore
from paragym.baselines.tasks import bench_of
from paragym.baselines.training import env_name
from paragym.models import shipped_models_dir, shipped_models_folder

__all__ = ["bootstrap_mean_ci", "latest_versions", "learning_curves", "normalized_scores", "task_scores",
           "write_report"]



def latest_versions() -> list[str]:
    """The newest registered version of every task (:func:`paragym.registry.newest`: a ladder's rungs are not
    versions of their task)."""
    return list(registry.newest())


def _runs(models_dirs: list[Path]) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """env id -> algo -> the training logs (JSON) of its seeds."""
    found: dict[str, dict[str, list[dict[str, Any]]]] = defaultdict(lambda: defaultdict(list))
    for folder in models_dirs:
        for env_id in (r.id for r in registry.rows()):
            shipped = folder.resolve() == shipped_models_dir().resolve()
            for path in sorted((shipped_models_folder(env_id) if shipped else folder / env_name(env_id)
                                ).glob("*_seed*.json")):
                meta = json.loads(path.read_text())
                curve = meta.get("curve") or {}
                if meta.get("algo") in ("ppo", "sac", "td3", "tqc") and curve.get("eval_timesteps"):
                    found[env_id][meta["algo"]].append(meta)
    return found


def learning_curves(runs: list[dict[str, Any]], rng: np.random.Generator, points: int = 50
                    ) -> dict[str, np.ndarray]:
    """The seeds' evaluation returns interpolated onto a common grid of env
    steps (up to the shortest run) and of wall-clock seconds: their mean and
    95 % bootstrap interval on each (``steps``/``seconds``, ``mean``/``low``/``high``
    and ``*_s`` for the clock)."""
    out: dict[str, np.ndarray] = {}
    for axis, key in (("steps", "eval_timesteps"), ("seconds", "eval_seconds")):
        xs, ys = [], []
        for meta in runs:
            curve = meta["curve"]
            x = np.asarray(curve.get(key) or [], float)
            if key == "eval_seconds" and len(x) != len(curve["eval_timesteps"]):  # an older log: no clock
                total = meta.get("num_timesteps") or meta["timesteps"]
                x = np.asarray(curve["eval_timesteps"], float) / max(total, 1) * meta["train_seconds"]
            xs.append(x)
            ys.append(np.asarray(curve["eval_mean_return"], float))
        end = min(x[-1] for x in xs)
        grid = np.linspace(min(x[0] for x in xs), end, points)
        values = np.array([np.interp(grid, x, y) for x, y in zip(xs, ys, strict=True)])
        mean, low, high = bootstrap_mean_ci(values, rng)
        suffix = "" if axis == "steps" else "_s"
        out[axis] = grid
        out["mean" + suffix], out["low" + suffix], out["high" + suffix] = mean, low, high
    return out


def normalized_scores(db: str | Path, env_ids: list[str] | None = None) -> tuple[dict[str, np.ndarray], list[str]]:
    """algo -> (runs, tasks) normalised scores from the leaderboard's rows
    (module docstring), for the algorithms with a run on every task (the runs:
    the seeds they have on all of them); and the tasks."""
    per_task = task_scores(db, env_ids)
    tasks = list(per_task)
    out = {}
    for algo in sorted({a for scores in per_task.values() for a in scores}):  # those with runs on every task
        matrix = _matrix(per_task, algo, tasks)
        if matrix is not None:
            out[algo] = matrix
    return out, tasks


def _matrix(per_task: dict[str, dict[str, dict[int, float]]], algo: str, tasks: list[str]) -> np.ndarray | None:
    """(runs, tasks) scores of ``algo``: the seeds it has on every one of ``tasks`` (None: none)."""
    if not tasks or not all(per_task[e].get(algo) for e in tasks):
        return None
    seeds = sorted(set.intersection(*(set(per_task[e][algo]) for e in tasks)))
    return np.array([[per_task[e][algo][s] for e in tasks] for s in seeds]) if seeds else None


def task_scores(db: str | Path, env_ids: list[str] | None = None) -> dict[str, dict[str, dict[int, float]]]:
    """env id -> algo -> seed -> normalised score (module docstring), for the
    envs of ``env_ids`` (default: every task's latest version) that have a
    reference and a floor in the database."""
    env_ids = env_ids or latest_versions()
    per_task: dict[str, dict[str, dict[int, float]]] = {}
    with ResultStore(db) as store:
        for env_id in env_ids:
            returns: dict[str, list[float]] = defaultdict(list)
            kinds: dict[str, str] = {}
            producers = {name: spec.producer() for name, spec in policies_for(env_id).items()}
            for row in store.rows(env_id):  # the episodes of today's policies (their producer), as the table's
                if producers.get(row.policy) != row.producer:
                    continue
                returns[row.policy].append(row.episode_return)
                kinds[row.policy] = bench_of(env_id).kind_of(env_id, row.policy, row.kind)
            mean = {name: float(np.mean(r)) for name, r in returns.items()}
            refs = [n for n, k in kinds.items() if k == "reference"]
            floors = [mean[n] for n in ("zero", "random") if n in mean]
            if not refs or not floors:
                continue
            floor, ref = max(floors), mean[refs[0]]
            scores: dict[str, dict[int, float]] = defaultdict(dict)
            for name, value in mean.items():
                algo, _, seed = name.rpartition("-seed")
                if kinds[name] == "learned" and algo and seed.isdigit() and not algo.startswith("user-"):
                    scores[algo][int(seed)] = (value - floor) / (ref - floor) if ref != floor else np.nan
            per_task[env_id] = scores
    return per_task


def _plot_curves(env_id: str, curves: dict[str, dict[str, np.ndarray]], path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for k, (algo, c) in enumerate(sorted(curves.items())):
        for ax, x, suffix in ((axes[0], c["steps"], ""), (axes[1], c["seconds"], "_s")):
            ax.plot(x, c["mean" + suffix], color=f"C{k}", label=f"{algo.upper()} ({c['n']} seeds)")
            ax.fill_between(x, c["low" + suffix], c["high" + suffix], color=f"C{k}", alpha=0.25, lw=0)
    axes[0].set_xlabel("env steps")
    axes[1].set_xlabel("wall-clock seconds of training")
    for ax in axes:
        ax.set_ylabel("evaluation return (higher is better)")
        ax.legend(fontsize=8, loc="lower right")
    fig.suptitle(f"{env_id}: mean over seeds, 95 % bootstrap CI", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _plot_aggregate(point: dict[str, np.ndarray], interval: dict[str, np.ndarray], path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    algos = sorted(point)
    fig, ax = plt.subplots(figsize=(6, 0.6 * len(algos) + 1.2))
    for k, algo in enumerate(algos):
        low, high = interval[algo][:, 0]
        ax.barh(k, high - low, left=low, height=0.5, color=f"C{k}", alpha=0.6)
        ax.plot([point[algo][0]] * 2, [k - 0.25, k + 0.25], color="k")
    ax.axvline(0, color="0.5", ls=":", lw=1)
    ax.axvline(1, color="0.5", ls="--", lw=1)
    ax.set_yticks(range(len(algos)), [a.upper() for a in algos])
    ax.set_xlabel("IQM of the normalised score (0: floor, 1: reference; higher is better)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def write_report(out: str | Path, db: str | Path | None, models_dirs: list[str | Path] | None = None,
                 seed: int = 0, progress: bool = False) -> Path:
    """The report (module docstring) under ``out``: ``REPORT.md`` and its
    PNGs. ``db``: the leaderboard's database (None: curves only);
    ``models_dirs``: folders of trained models beside the shipped ones."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out} is a file, not a folder")
    if db is not None and not Path(db).is_file():
        raise ValueError(f"no leaderboard database at {db}: run `paragym leaderboard --db {db}` first")
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    runs = _runs([shipped_models_dir(), *(Path(d) for d in models_dirs or [])])
    steps = len(runs) + (1 if db is not None else 0)
    bar = task = None
    if progress:
        from rich.progress import Progress

        bar = Progress(transient=True)
        bar.start()
        task = bar.add_task("report", total=steps)
    lines = ["# paragym report", "",
             f"paragym {paragym.__version__}. Learning curves: mean evaluation return over training seeds, with a "
             f"95 % bootstrap confidence interval of the mean ({BOOTSTRAP_REPS} resamples of the seeds), against env "
             f"steps and wall-clock. Written by `paragym report`.", ""]
    try:
        for env_id in (r.id for r in registry.rows()):
            if env_id not in runs:
                continue
            curves = {}
            for algo, metas in runs[env_id].items():
                curves[algo] = {**learning_curves(metas, rng), "n": len(metas)}
            png = _plot_curves(env_id, curves, out / f"curves-{env_name(env_id)}.png")
            lines += [f"## `{env_id}`", "", "| algorithm | seeds | final evaluation return (mean, 95 % CI) | "
                      "env steps | wall-clock [s] |", "|---|---|---|---|---|"]
            for algo, c in sorted(curves.items()):
                lines.append(f"| {algo.upper()} | {c['n']} | {c['mean'][-1]:.2f} [{c['low'][-1]:.2f}, "
                             f"{c['high'][-1]:.2f}] | {c['steps'][-1]:,.0f} | {c['seconds'][-1]:.0f} |")
            lines += ["", f"![{env_id}]({png.name})", ""]
            if bar is not None:
                bar.advance(task)
        if db is not None:
            lines += _aggregate(db, out, rng)
            if bar is not None:
                bar.advance(task)
    finally:
        if bar is not None:
            bar.stop()
    page = out / "REPORT.md"
    page.write_text("\n".join(lines) + "\n")
    return page


def _aggregate(db: str | Path, out: Path, rng: np.random.Generator) -> list[str]:
    """The rliable section: IQM with stratified-bootstrap intervals and the probability of improvement."""
    from rliable import library as rly
    from rliable import metrics

    scores, tasks = normalized_scores(db)
    lines = ["## Across tasks (rliable)", "", evidence(db, tasks), ""]
    state = np.random.RandomState(int(rng.integers(2 ** 31)))
    if not scores:
        return lines + ["No learning algorithm has a run on every task's latest version in the database.", "",
                        *_improvement(db, state)]
    point, interval = rly.get_interval_estimates(scores, lambda x: np.array([metrics.aggregate_iqm(x)]),
                                                 reps=BOOTSTRAP_REPS, random_state=state)
    png = _plot_aggregate(point, interval, out / "aggregate-iqm.png")
    lines += [f"Tasks (the latest version of each): {', '.join(f'`{t}`' for t in tasks)}. Score per run: its mean "
              f"return, normalised between the floor (0: the better of `zero` and `random`) and the reference (1). "
              f"An algorithm with runs on only some of these tasks is left out here (its curves are above).",
              "", "| algorithm | runs | IQM of the normalised score | 95 % CI (stratified bootstrap) |",
              "|---|---|---|---|"]
    for algo in sorted(point):
        lines.append(f"| {algo.upper()} | {len(scores[algo])} | {point[algo][0]:.3f} | "
                     f"[{interval[algo][0, 0]:.3f}, {interval[algo][1, 0]:.3f}] |")
    lines += ["", f"![aggregate]({png.name})", ""]
    return lines + _improvement(db, state)


def evidence(db: str | Path, env_ids: list[str]) -> str:
    """What the scores rest on: the episodes per policy and the evaluation
    seeds in ``db`` for ``env_ids`` (today's policies' rows), said plainly,
    and flagged when it is fewer than the full suite's."""
    from paragym.baselines.leaderboard.suite import FULL

    counts: dict[tuple[str, str], int] = defaultdict(int)
    seeds: set[int] = set()
    with ResultStore(db) as store:
        for env_id in env_ids:
            producers = {name: spec.producer() for name, spec in policies_for(env_id).items()}
            for row in store.rows(env_id):
                if producers.get(row.policy) == row.producer:
                    counts[env_id, row.policy] += 1
                    seeds.add(row.seed)
    if not counts:
        return f"The database `{Path(db).name}` holds no episodes of today's policies on these tasks."
    low, high = min(counts.values()), max(counts.values())
    text = (f"The scores rest on {low if low == high else f'{low} to {high}'} episodes per policy and task "
            f"(evaluation seeds {', '.join(map(str, sorted(seeds)))}) in the leaderboard database "
            f"`{Path(db).name}`.")
    full = len(FULL.keys())
    if low < full:
        text += (f" **Fewer than the full suite's {full}: a smoke test, not a ranking** (run `paragym leaderboard` "
                 f"without --quick).")
    return text


def _improvement(db: str | Path, state: np.random.RandomState) -> list[str]:
    """rliable's probability of improvement of every algorithm over every
    other, each pair on the tasks where both have runs."""
    from rliable import library as rly
    from rliable import metrics

    per_task = task_scores(db)
    algos = sorted({a for scores in per_task.values() for a in scores})
    pairs, shared = {}, {}
    for x in algos:
        for y in algos:
            tasks = [e for e in per_task if per_task[e].get(x) and per_task[e].get(y)]
            mx, my = _matrix(per_task, x, tasks), _matrix(per_task, y, tasks)
            if x != y and mx is not None and my is not None:
                pairs[f"{x},{y}"], shared[f"{x},{y}"] = (mx, my), tasks
    if not pairs:
        return []
    point, interval = rly.get_interval_estimates(
        pairs, lambda a, b: np.array([metrics.probability_of_improvement(a, b)]), reps=BOOTSTRAP_REPS,
        random_state=state)
    lines = ["Probability of improvement P(X > Y) (rliable), with its 95 % CI, each pair on the tasks where both "
             "have runs:", "", "| X | Y | tasks | P(X > Y) | 95 % CI |", "|---|---|---|---|---|"]
    for key, tasks in shared.items():
        x, y = key.split(",")
        names = ", ".join(env_name(t) for t in tasks)
        lines.append(f"| {x.upper()} | {y.upper()} | {names} | {point[key][0]:.2f} | "
                     f"[{interval[key][0, 0]:.2f}, {interval[key][1, 0]:.2f}] |")
    return lines + [""]
