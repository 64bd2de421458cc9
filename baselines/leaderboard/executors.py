"""The executors: each runs jobs and yields the finished rows as they come.

``local`` runs them in this process, ``workers`` in a fork-started process
pool on this machine, ``ray`` as Ray tasks, local or on a cluster. Workers
die with their parent (:func:`die_with_parent`); a local Ray is reaped
if its driver dies (:mod:`paragym.baselines.ray_session`).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

from paragym.baselines.leaderboard.evaluate import evaluate_job
from paragym.baselines.policies import PolicySpec
from paragym.baselines.ray_session import ray_session
from paragym.baselines.store import DynamicRow, EpisodeRow, ValidationRow

__all__ = ["EXECUTORS", "RUNNERS", "Job", "Row", "die_with_parent"]

#: a job: its kind ("episode", "dynamic", "dynamic@mujoco" or "validation"), the spec, the kind's two arguments
#: (the evaluation seed and the episode; the scenario and the reset seed; the seed and None:
#: :func:`~paragym.baselines.leaderboard.evaluate.evaluate_job`), and the producer its row records (computed
#: once, by the run that planned the job: a worker never recomputes what identifies the policy)
Job = tuple[str, PolicySpec, Any, Any, str]
#: what a job gives back
Row = EpisodeRow | DynamicRow | ValidationRow


def _run_local(jobs: list[Job], workers: int, ray_address: str | None, models_dir: str | None) -> Iterator[Row]:
    for kind, spec, a, b, made in jobs:
        yield evaluate_job(kind, spec, a, b, made)


def die_with_parent(parent: int) -> None:
    """Make this process end when ``parent`` does, however it ends (SIGKILL
    included): Linux's parent-death signal where there is one, and a watchdog
    thread that polls the parent's pid everywhere (it also covers a parent
    that died before the signal was armed)."""
    import ctypes
    import os
    import signal
    import sys
    import threading

    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass

    def watch() -> None:
        while True:
            if os.getppid() != parent:
                os._exit(1)
            time.sleep(0.5)

    if os.getppid() != parent:
        os._exit(1)
    threading.Thread(target=watch, name="paragym-parent-watchdog", daemon=True).start()


def _init_worker(parent: int) -> None:
    """A pool worker: it ends with its parent, takes SIGTERM's default action and ignores SIGINT. A forked worker
    inherits the parent's Python handlers (the CLI's turn both into KeyboardInterrupt), and a worker that catches
    one as its job's error goes on with the next queued episode instead of stopping."""
    import signal
    import sys

    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C reaches the whole process group: the parent stops us
    die_with_parent(parent)
    torch = sys.modules.get("torch")  # not imported for it: shipped (MLP) models act in numpy without PyTorch
    if torch is not None:
        torch.set_num_threads(1)


def _evaluate_by_name(kind: str, env_id: str, name: str, models_dir: str | None, a: Any, b: Any, made: str) -> Row:
    from paragym.baselines.policies import get_policy

    return evaluate_job(kind, get_policy(env_id, name, models_dir), a, b, made)


def _run_pool(jobs: list[Job], workers: int, ray_address: str | None, models_dir: str | None) -> Iterator[Row]:
    """A fork-started process pool: workers inherit the policy registry, so
    policies registered in the calling script work too. The workers die with
    this process (:func:`die_with_parent`), and an interrupted run stops them
    at once instead of waiting for their episodes."""
    import multiprocessing as mp
    import os
    from concurrent.futures import ProcessPoolExecutor, as_completed

    pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("fork"), initializer=_init_worker,
                               initargs=(os.getpid(),))
    finished = False
    try:
        futures = [pool.submit(_evaluate_by_name, kind, spec.env_id, spec.name, models_dir, a, b, made)
                   for kind, spec, a, b, made in jobs]
        for fut in as_completed(futures):
            yield fut.result()
        finished = True
    finally:
        if not finished:
            for proc in list(getattr(pool, "_processes", {}).values()):
                proc.terminate()
        pool.shutdown(wait=finished, cancel_futures=True)


def _run_ray(jobs: list[Job], workers: int, ray_address: str | None, models_dir: str | None) -> Iterator[Row]:
    """Ray tasks (one per episode; the policy spec travels with the task,
    pickled by Ray) on a local instance, or on the cluster at ``ray_address``
    (:func:`~paragym.baselines.ray_session.ray_session`)."""
    pending: list[Any] = []
    with ray_session(ray_address, workers, what="--executor ray") as ray:
        try:
            remote = ray.remote(num_cpus=1)(evaluate_job)
            pending = [remote.remote(kind, spec, a, b, made) for kind, spec, a, b, made in jobs]
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                try:
                    yield ray.get(done[0])
                except ray.exceptions.RayTaskError as exc:  # the task's own error, without Ray's coloured traceback
                    cause = getattr(exc, "cause", None)
                    if isinstance(cause, ValueError):
                        raise ValueError(str(cause)) from None
                    raise RuntimeError(f"a Ray task failed: {type(cause).__name__}: {cause}") from None
        finally:
            for ref in pending:
                ray.cancel(ref)


EXECUTORS = ("local", "workers", "ray")

#: executor -> ``run(jobs, workers, ray_address, models_dir)``: the rows as their jobs finish
RUNNERS = {"local": _run_local, "workers": _run_pool, "ray": _run_ray}
