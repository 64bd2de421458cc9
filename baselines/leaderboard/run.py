"""The leaderboard's run: choose the policies, plan the missing episodes, run them, validate, summarise, report."""

from __future__ import annotations

import itertools
import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import paragym
from paragym import registry
from paragym.baselines.agents import unreadable
from paragym.baselines.leaderboard.executors import EXECUTORS, RUNNERS, Job, Row
from paragym.baselines.leaderboard.render import smoke_note, terminal_table, write_reports
from paragym.baselines.leaderboard.results import write_episodes_csv, write_results
from paragym.baselines.leaderboard.suite import FULL, EvalSuite, dynamic_engines, dynamic_job, dynamic_producer
from paragym.baselines.leaderboard.summary import Summary, dynamic_summary, noise_floor, summarise
from paragym.baselines.policies import PolicySpec, policies_for
from paragym.baselines.store import DynamicRow, EpisodeRow, ResultStore
from paragym.baselines.tasks import bench_of
from paragym.baselines.training import check_env_id, env_name

__all__ = ["LeaderboardInterrupted", "LeaderboardRun", "run_leaderboard"]


class LeaderboardInterrupted(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM in the CLI) during a run: what was saved by then."""

    def __init__(self, saved: int, planned: int, db: Path) -> None:
        super().__init__(f"interrupted: {saved} episodes saved in {db} ({planned - saved} of this run left); "
                         f"run the same command again to continue from there")
        self.saved, self.planned, self.db = saved, planned, db


@dataclass
class LeaderboardRun:
    """What :func:`run_leaderboard` did and produced."""

    summaries: dict[str, list[Summary]]
    new_episodes: int
    skipped_episodes: int
    files: list[Path]
    seconds: float
    #: the dynamic-fidelity episodes run now, and those taken from the database
    new_dynamic: int = 0
    skipped_dynamic: int = 0


def _select(env_ids: list[str] | None, policy_names: list[str] | None,
            models_dir: Path | None) -> dict[str, dict[str, PolicySpec]]:
    envs = [check_env_id(e) for e in env_ids] if env_ids else [r.id for r in registry.rows()]
    chosen: dict[str, dict[str, PolicySpec]] = {}
    for env in envs:
        specs = policies_for(env, models_dir)
        if policy_names:
            chosen[env] = {n: specs[n] for n in policy_names if n in specs}
        else:
            chosen[env] = specs
    if policy_names:
        known = {n for env in envs for n in policies_for(env, models_dir)}
        unknown = [n for n in policy_names if n not in known]
        if unknown:
            raise ValueError(f"unknown policy {', '.join(map(repr, unknown))}; known: {', '.join(sorted(known))}")
    return chosen


def run_leaderboard(db: str | Path = "results/paragym.sqlite", suite: EvalSuite = FULL, *,
                    env_ids: list[str] | None = None, policies: list[str] | None = None,
                    models_dir: str | Path | None = None, executor: str = "local", workers: int = 1,
                    ray_address: str | None = None, out: str | Path | None = "results",
                    markdown_path: str | Path | None = None, validate: bool = True, progress: bool = True,
                    on_row: Callable[[EpisodeRow], None] | None = None, echo: Callable[[str], None] = print,
                    command: str = "", resume_from: str | Path | None = None) -> LeaderboardRun:
    """Evaluate what is missing from ``db`` for ``suite``, then write the
    reports (to ``out``: ``LEADERBOARD.md`` unless ``markdown_path``,
    ``leaderboard.csv``, ``<env>.png``, every episode in ``episodes.csv`` and
    the self-describing ``results.json.gz`` that ``paragym verify`` checks,
    which records ``command``; nothing written when ``out`` is None).
    ``on_row`` sees each new row after it is stored. The shipped models
    always take part; ``models_dir`` adds your own (``user-...``). An
    episode is taken from ``db`` only when its stored row has the policy's
    current producer (model hash, planner parameters); the others are run
    again, and ``echo`` says so. ``resume_from``: a results file (``results.json.gz``) whose rows are put into
    ``db`` first (:func:`~paragym.baselines.leaderboard.results.rows_of_results`), so that a fresh checkout
    extends the committed leaderboard instead of running it all again; its rows are taken on the same terms
    (this paragym version, each policy's current producer).

    The steps: choose the policies (:func:`_select`), plan the missing
    episodes (:func:`_plan`), the missing dynamic episodes
    (:func:`_plan_dynamic`) and validations of the reference plans
    (:func:`_plan_validations`), run them all in one stream of jobs with the
    executor (:func:`_execute`: the longest first, so that no worker waits
    for another at a phase's end), summarise (:func:`_summaries`) and write
    the reports (:func:`_write_reports`)."""
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; known: {', '.join(EXECUTORS)}")
    if not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a positive integer; got {workers!r}")
    models = Path(models_dir) if models_dir is not None else None
    chosen = _select(env_ids, policies, models)
    out = _report_folder(out, markdown_path, env_ids, policies)
    producers = {(env, name): spec.producer() for env, specs in chosen.items() for name, spec in specs.items()}
    t0 = time.perf_counter()
    imported = None
    if resume_from is not None:
        from paragym.baselines.leaderboard.results import read_results, rows_of_results

        written = read_results(resume_from)["written_by"]["paragym"]
        if written != paragym.__version__:
            raise ValueError(f"resume_from: {resume_from} was written by paragym {written}, this is "
                             f"{paragym.__version__}; its rows would not be taken")
        imported = rows_of_results(resume_from)
    with ResultStore(db) as store:
        if imported is not None:
            store.add_all(*imported)
            echo(f"took {len(imported[0])} episodes and {len(imported[1])} dynamic episodes from {resume_from}")
        jobs, total = _plan(store, chosen, suite, producers, echo)
        echo(f"paragym {paragym.__version__} leaderboard ({suite.name}: seeds {list(suite.seeds)} x "
             f"{suite.episodes} episodes): {len(chosen)} envs, {total} episodes, {total - len(jobs)} already in "
             f"{store.path}; running {len(jobs)} with the {executor} executor")
        dynamic_jobs: list[Job] = []
        dynamic_total = 0
        validations: list[Job] = []
        shared: Shared = {}
        if validate and suite.dynamic:
            dynamic_jobs, dynamic_total = _plan_dynamic(store, chosen, suite, producers)
            who = "" if suite.dynamic_all else (": on each task's newest id, the references, the other methods, each "
                                                "learned algorithm's seed 0")
            echo(f"dynamic fidelity: {len(dynamic_jobs)} episodes to run ({len(suite.dynamic)} per policy{who}; "
                 f"each with the KF validation of what it executed)")
        if validate:
            validations, shared = _plan_validations(store, chosen, producers)
            for job in validations:
                echo(f"KF validation of {job[1].name}'s plan on {job[1].env_id} (dynamic fidelity)")
        # the validations and the dynamic episodes (seconds each) first, then the episodes (mostly a fraction of
        # a second): the workers finish together
        _execute(store, validations + dynamic_jobs + jobs, shared, executor, workers, ray_address, models, progress,
                 on_row)
        rows, dynamic_rows = _selected(store, chosen, suite, producers)
        all_summaries = _summaries(store, chosen, suite, rows, dynamic_rows)
        files = write_reports(all_summaries, suite, out, markdown_path, env_ids, policies) if out is not None else []
        if out is not None:  # the raw episodes, and the file anyone can check (paragym verify)
            specs = {(env, name): spec for env, named in chosen.items() for name, spec in named.items()}
            files[-1:-1] = [write_episodes_csv(out / "episodes.csv", rows),
                            write_results(out / "results.json.gz", rows, dynamic_rows, specs, suite, command)]
    seconds = time.perf_counter() - t0
    if smoke_note(suite):
        echo("\n" + smoke_note(suite).replace("**", ""))
    for env, ss in all_summaries.items():
        echo(f"\n{env}\n{terminal_table(ss)}\n{noise_floor(ss).sentence().replace('**', '').replace('`', '')}")
    return LeaderboardRun(all_summaries, len(jobs), total - len(jobs), files, seconds, len(dynamic_jobs),
                          dynamic_total - len(dynamic_jobs))


def _report_folder(out: str | Path | None, markdown_path: str | Path | None, env_ids: list[str] | None,
                   policies: list[str] | None) -> Path | None:
    """Where the reports go, checked writable before any episode runs: a
    filtered run writes apart (``partial-<filter>``), so that it cannot be
    taken for the full table."""
    if out is None:
        return None
    partial = _partial_label(env_ids, policies)
    folder = Path(out) / f"partial-{partial}" if partial else Path(out)
    _check_writable(folder)
    if markdown_path is not None:
        _check_writable(Path(markdown_path).parent)
    return folder


def _plan(store: ResultStore, chosen: dict[str, dict[str, PolicySpec]], suite: EvalSuite,
          producers: dict[tuple[str, str], str], echo: Callable[[str], None]) -> tuple[list[Job], int]:
    """The episodes ``store`` lacks for the current producers (saying which
    stored ones are run again), and how many episodes the suite has."""
    done = store.done_keys()
    jobs = [("episode", spec, s, k, producers[spec.env_id, spec.name]) for specs in chosen.values()
            for spec in specs.values()
            for s, k in suite.keys()
            if (spec.env_id, spec.name, s, k, store.version, producers[spec.env_id, spec.name]) not in done]
    _say_what_is_rerun(jobs, done, store.version, producers, echo)
    for (env, name), made in producers.items():
        if unreadable(json.loads(made)):
            echo(f"{env_name(env)} {name}: its source cannot be read (defined in an interactive session?), so "
                 f"nothing identifies its code: its stored rows are never reused, and its episodes run every time")
    return _by_turns(jobs), sum(len(specs) for specs in chosen.values()) * len(suite.keys())


def _by_turns(jobs: list[Any]) -> list[Any]:
    """``jobs`` taken a task at a time in turn (each task's own order kept): the
    workers start on different tasks, so from a cold numba cache each compiles
    another task's kernels instead of both compiling the same ones."""
    groups: dict[str, list[Any]] = {}
    for job in jobs:
        groups.setdefault(registry.task_of(job[1].env_id), []).append(job)
    return [job for turn in itertools.zip_longest(*groups.values()) for job in turn if job is not None]


def _plan_dynamic(store: ResultStore, chosen: dict[str, dict[str, PolicySpec]], suite: EvalSuite,
                  producers: dict[tuple[str, str], str]) -> tuple[list[Job], int]:
    """The dynamic-fidelity episodes ``store`` lacks for the current producers
    (the policy's, the physics settings and the engine: :func:`dynamic_producer`), in every engine the env's
    task runs (:func:`dynamic_engines`), and how many the suite has."""
    done = store.dynamic_keys()
    wanted = [(dynamic_job(engine), spec, scenario, seed, dynamic_producer(spec, engine))
              for env, specs in chosen.items() if bench_of(env).dynamics is not None
              for engine in dynamic_engines(env) for spec in specs.values() if suite.runs_dynamic(spec)
              for scenario, seed in suite.dynamic]
    return _by_turns([job for job in wanted
                      if (job[1].env_id, job[1].name, job[2], job[3], store.version, job[4]) not in done]), len(wanted)


#: a validation job's (env, reference) -> every (env, reference, producer) its verdict is stored for
Shared = dict[tuple[str, str], list[tuple[str, str, str]]]


def _execute(store: ResultStore, jobs: list[Job], shared: Shared, executor: str, workers: int,
             ray_address: str | None, models: Path | None, progress: bool,
             on_row: Callable[[EpisodeRow], None] | None) -> None:
    """Run ``jobs`` (of every kind) with the executor, storing each row as it comes (Ctrl-C keeps what is stored
    and stops the workers); ``on_row`` sees each episode's row. A reference plan's validation is stored for
    each env ``shared`` lists for it."""
    from tqdm.auto import tqdm

    run = RUNNERS[executor]
    stream = run(jobs, workers, ray_address, str(models) if models is not None else None)
    saved = 0
    try:
        with tqdm(total=len(jobs), disable=not progress or not jobs, unit="job", dynamic_ncols=True) as bar:
            for row in stream:
                _store(store, row, shared)
                saved += 1
                bar.set_postfix_str(f"{env_name(row.env)} {row.policy}", refresh=False)
                bar.update()
                if on_row is not None and isinstance(row, EpisodeRow):
                    on_row(row)
    except KeyboardInterrupt:
        stream.close()  # stops the workers now
        raise LeaderboardInterrupted(saved, len(jobs), store.path) from None


def _store(store: ResultStore, row: Row, shared: Shared) -> None:
    if isinstance(row, EpisodeRow):
        store.add(row)
    elif isinstance(row, DynamicRow):
        store.add_dynamic(row)
    else:
        for env, name, producer in shared[row.env, row.policy]:
            store.set_validation(env, name, row.passed, row.summary, producer)


def _plan_validations(store: ResultStore, chosen: dict[str, dict[str, PolicySpec]],
                      producers: dict[tuple[str, str], str]) -> tuple[list[Job], Shared]:
    """The KF validation of each validated reference plan that takes part and has none stored for its producer
    (dynamic fidelity): one job per plan, run for the first env whose reference has it, and the envs its
    verdict is stored for (the hybrid's v1 and v2 validate v0's plan: the same check, run once)."""
    by_check: dict[Any, list[tuple[str, str, str]]] = {}
    for env in chosen:
        bench = bench_of(env)
        name = bench.reference
        if bench.validated_plan is not None and name in chosen[env] and \
                store.validation(env, name, producers[env, name]) is None:
            by_check.setdefault(bench.validated_plan, []).append((env, name, producers[env, name]))
    jobs: list[Job] = [("validation", chosen[env][name], 0, None, made)
                       for (env, name, made), *_ in by_check.values()]
    return jobs, {(envs[0][0], envs[0][1]): envs for envs in by_check.values()}


def _selected(store: ResultStore, chosen: dict[str, dict[str, PolicySpec]], suite: EvalSuite,
              producers: dict[tuple[str, str], str]) -> tuple[list[EpisodeRow], list[DynamicRow]]:
    """The stored rows of the suite's episodes made by the current producers (kinematic, dynamic)."""
    keys = set(suite.keys())
    rows = [r for r in store.rows() if producers.get((r.env, r.policy)) == r.producer and (r.seed, r.episode) in keys]
    wanted = set(suite.dynamic)
    made = {(*key, engine): dynamic_producer(chosen[key[0]][key[1]], engine) for key in producers
            for engine in dynamic_engines(key[0])}
    dynamic = [r for r in store.dynamic_rows()
               if made.get((r.env, r.policy, r.engine)) == r.producer and (r.scenario, r.seed) in wanted]
    return rows, dynamic


def _summaries(store: ResultStore, chosen: dict[str, dict[str, PolicySpec]], suite: EvalSuite,
               rows: list[EpisodeRow], dynamic_rows: list[DynamicRow]) -> dict[str, list[Summary]]:
    """The table of each env from the selected rows (:func:`_selected`), with each policy's description."""
    all_summaries = summarise(rows, store)
    dynamic: dict[tuple[str, str, str], list[DynamicRow]] = {}
    for r in dynamic_rows:
        dynamic.setdefault((r.env, r.policy, r.engine), []).append(r)
    for env, ss in all_summaries.items():
        for s in ss:
            s.dynamic = dynamic_summary(dynamic.get((env, s.policy, "pybullet"), []), suite)
            s.dynamic_mujoco = dynamic_summary(dynamic.get((env, s.policy, "mujoco"), []), suite)
    for env, ss in all_summaries.items():
        for s in ss:
            s.description = chosen[env][s.policy].description
    return all_summaries


def _say_what_is_rerun(jobs: list[Job], done: set[tuple], version: str, producers: dict[tuple[str, str], str],
                       echo: Callable[[str], None]) -> None:
    """One line per (env, policy) whose stored episodes came from another producer."""
    stored: dict[tuple, list[str]] = {}
    for key in done:
        stored.setdefault(key[:5], []).append(key[5])
    stale: dict[tuple[str, str], set[str]] = {}
    for _, spec, s, k, _ in jobs:
        for old in stored.get((spec.env_id, spec.name, s, k, version), ()):
            stale.setdefault((spec.env_id, spec.name), set()).add(old)
    for (env, name), old in stale.items():
        n = sum(1 for _, spec, *_ in jobs if (spec.env_id, spec.name) == (env, name))
        echo(f"{env_name(env)} {name}: the stored episodes were made by another producer "
             f"({_short(next(iter(old)))} -> {_short(producers[env, name])}); re-running {n} of them")


def _short(producer: str) -> str:
    """A producer in a few characters: the model's hash, the agent's source hash (and its parameters' where they
    are not all of it), or a hash of the parameters."""
    import hashlib

    try:
        made = json.loads(producer)
    except ValueError:
        made = {}
    params = made.get("params", {}) if isinstance(made, dict) else {}
    if "model_sha256" in params:
        return f"model sha256 {params['model_sha256'][:12]}"
    said = f"parameters {hashlib.sha256(json.dumps(params, sort_keys=True).encode()).hexdigest()[:12]}"
    if made.get("source_sha256"):
        return f"{made.get('policy')}, source sha256 {made['source_sha256'][:12]}, {said}"
    return f"{made.get('policy', '?')}, {said}"


def _partial_label(env_ids: list[str] | None, policies: list[str] | None) -> str:
    """'' for the full table; else a folder-safe name of the filter (and a short hash of it)."""
    import hashlib
    import re

    if not env_ids and not policies:
        return ""
    parts = [env_name(e) for e in env_ids or []] + list(policies or [])
    text = re.sub(r"[^\w.+-]+", "_", "_".join(parts))[:60]
    return f"{text}-{hashlib.sha256('|'.join(parts).encode()).hexdigest()[:6]}"


def _check_writable(folder: Path) -> None:
    """Make ``folder`` and write a probe file in it now, so that a bad ``--out``
    fails before any episode runs (a ValueError naming it)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".paragym-write-check"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise ValueError(f"cannot write the reports to {folder}: {exc.strerror or exc} (choose another --out)") from exc

