"""Several training runs at once (``paragym train --seeds N``, ``--sweep FILE``), on this machine or as Ray Tune
trials on a local Ray or a cluster (``--ray ADDRESS``).

A run is :func:`paragym.baselines.training.train` with one seed and one point's hyper-parameters. A sweep file is
YAML: a mapping of the algorithm's hyper-parameter names (the keys of ``hyperparams/<algo>.yml``) to lists of
values; the sweep is their grid, each combination once, each played with every seed. A sweep's point has a name,
its settings as ``name=value`` joined by commas (``learning_rate=0.001,n_steps=64``), and its runs are written
under ``<models>/<point>/``; runs without a sweep are written under ``<models>/`` as one ``paragym train`` writes
them. A run whose model is there already is skipped, and one trained for other timesteps refused, unless ``force``
(as ``paragym train``).

On Ray each run is a Ray Tune trial (one per run, ``threads`` CPUs each): it trains into a folder of its own on
whichever node runs it, and its files (the model, its JSON with the curve, the curve's picture) travel back as
the trial's checkpoint, through Ray Tune's storage (``storage``: a folder every node reaches, or a URI Ray Tune
takes, such as ``s3://...``; by default a temporary folder of this machine, which serves a local Ray), to where
the same run on this machine writes them. A trial is the local run: the same seed and hyper-parameters train the
same model, weight for weight (a test), since each run seeds its own generators and torch runs on the CPU with
``threads`` threads.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from paragym import check_env_id
from paragym.baselines.config import ALGOS, PARAGYM_KEYS, _read_config, check_algo
from paragym.baselines.run_files import RunFiles, _finished_run, fidelity_dir, run_files, writable_models_dir

__all__ = ["Run", "RunOutcome", "plan_runs", "read_sweep", "run_all"]


@dataclass(frozen=True)
class Run:
    """One training run: its seed, its sweep point's name ("" without a sweep) and hyper-parameters, and the
    folder its files go to (the run's ``models_dir``)."""

    seed: int
    point: str
    hyperparams: dict[str, Any]
    models_dir: Path


@dataclass
class RunOutcome:
    """What a run left: its files, its JSON, and whether it was skipped as trained before."""

    run: Run
    files: RunFiles
    meta: dict[str, Any] = field(repr=False)
    skipped: bool = False


def read_sweep(path: str | Path) -> list[tuple[str, dict[str, Any]]]:
    """The points of the sweep file ``path`` (module docstring): (name, hyper-parameters), in the grid's order. A
    ValueError naming the file for anything but a mapping of names to non-empty lists of numbers, strings or
    booleans."""
    import yaml

    path = Path(path)
    try:
        spec = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"--sweep {path}: cannot read it as YAML: {exc}") from None
    if not isinstance(spec, dict) or not spec:
        raise ValueError(f"--sweep {path}: expected a mapping of hyper-parameter names to lists of values")
    for name, values in spec.items():
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"--sweep {path}: {name!r} is not a hyper-parameter name")
        if not isinstance(values, list) or not values:
            raise ValueError(f"--sweep {path}: {name} must list its values (a YAML list); got {values!r}")
        for v in values:
            if not isinstance(v, int | float | str | bool) or (isinstance(v, float) and not math.isfinite(v)):
                raise ValueError(f"--sweep {path}: {name}'s values must be finite numbers, strings or booleans; "
                                 f"got {v!r}")
            if isinstance(v, str) and ("/" in v or "," in v or not v):
                raise ValueError(f"--sweep {path}: {name}'s value {v!r} cannot name a folder (no '/', ',' or empty)")
    names = list(spec)
    return [(",".join(f"{n}={v}" for n, v in zip(names, combo, strict=True)), dict(zip(names, combo, strict=True)))
            for combo in itertools.product(*(spec[n] for n in names))]


def plan_runs(seed: int, seeds: int, models_dir: str | Path,
              points: list[tuple[str, dict[str, Any]]] | None = None) -> list[Run]:
    """The runs of seeds ``seed`` .. ``seed + seeds - 1`` at every point of a sweep (None: none), each with its
    folder under ``models_dir`` (module docstring)."""
    if not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer; got {seed!r}")
    if not isinstance(seeds, int) or seeds < 1:
        raise ValueError(f"--seeds must be a positive integer; got {seeds!r}")
    root = Path(writable_models_dir(models_dir))
    return [Run(s, name, hp, root / name if name else root) for name, hp in (points or [("", {})])
            for s in range(seed, seed + seeds)]


def run_all(env_id: str, algo: str, runs: list[Run], timesteps: int | None = None, threads: int = 1,
            force: bool = False, vectorized: bool = False, n_envs: int | None = None, ray_address: str | None = None,
            storage: str | None = None, echo: Any = print, fidelity: str = "kinematic",
            engine: str = "pybullet") -> list[RunOutcome]:
    """Train ``runs`` of ``algo`` on ``env_id`` (the arguments as :func:`~paragym.baselines.training.train`'s):
    one after the other here, or as Ray Tune trials on the Ray at ``ray_address`` ("local": a local Ray of this
    machine's cores) with Ray Tune's ``storage`` (module docstring). The runs trained before are skipped first.
    Returns each run's outcome, in the order of ``runs``."""
    from paragym.baselines.training import train

    if str(algo).lower() not in ALGOS:
        raise ValueError(f"--seeds, --sweep and --ray train {', '.join(ALGOS)}; got {algo!r}")
    env_id, algo = check_env_id(env_id), check_algo(algo)
    _check_names(algo, {name for run in runs for name in run.hyperparams})
    outcomes: dict[int, RunOutcome] = {}
    todo = []
    def files_of(run: Run) -> RunFiles:  # where train() writes the run, here or in a trial's folder
        return run_files(env_id, algo, run.seed, fidelity_dir(run.models_dir, fidelity, engine))

    for i, run in enumerate(runs):
        files = files_of(run)
        _, total = _read_config(env_id, algo, timesteps, run.hyperparams, n_envs)
        done = _finished_run(files, algo, total, force)
        if done is not None:
            outcomes[i] = RunOutcome(run, files, done.meta, skipped=True)
        else:
            todo.append(i)
    settings = {"timesteps": timesteps, "threads": threads, "vectorized": vectorized, "n_envs": n_envs,
                "fidelity": fidelity, "engine": engine}
    if ray_address is None:
        for i in todo:
            res = train(env_id, algo, seed=runs[i].seed, models_dir=runs[i].models_dir, progress_bar=False,
                        force=force, hyperparams=dict(runs[i].hyperparams) or None, **settings)
            outcomes[i] = RunOutcome(runs[i], res.files, res.meta)
            echo(_line(outcomes[i]))
    elif todo:
        def deliver(j: int, folder: Path) -> None:
            i = todo[j]
            files = files_of(runs[i])
            _take(folder, files, force)
            outcomes[i] = RunOutcome(runs[i], files, json.loads(files.meta.read_text()))
            echo(_line(outcomes[i]))

        _on_ray(env_id, algo, [runs[i] for i in todo], settings, ray_address, storage, deliver)
    return [outcomes[i] for i in range(len(runs))]


def _check_names(algo: str, names: set[str]) -> None:
    """A ValueError naming the hyper-parameters in ``names`` that neither the algorithm's constructor nor paragym's
    yml takes (a sweep's typo, caught before any run starts)."""
    import inspect

    from paragym.baselines.loading import _algorithm

    known = set(inspect.signature(_algorithm(algo).__init__).parameters) | set(PARAGYM_KEYS)
    unknown = sorted(names - known - {"self", "env"})
    if unknown:
        raise ValueError(f"--sweep: {algo.upper()} takes no hyper-parameter {', '.join(unknown)}")


def _line(out: RunOutcome) -> str:
    curve = out.meta.get("curve", {})
    last = curve.get("eval_mean_return") or [float("nan")]
    point = f" at {out.run.point}" if out.run.point else ""
    return (f"seed {out.run.seed}{point}: {out.meta.get('timesteps', 0):,} steps in "
            f"{out.meta.get('train_seconds', 0):.0f} s, last evaluation {last[-1]:.3f}; {out.files.model}")


def _trial(config: dict[str, Any], env_id: str, algo: str, runs: list[Run], settings: dict[str, Any]) -> None:
    """One Ray Tune trial: run ``runs[config["index"]]`` into a folder of its own and report its files as the
    trial's checkpoint."""
    from ray import tune

    from paragym.baselines.training import train

    run = runs[config["index"]]
    with tempfile.TemporaryDirectory(prefix="paragym-trial-") as tmp:
        res = train(env_id, algo, seed=run.seed, models_dir=tmp, progress_bar=False, force=True,
                    hyperparams=dict(run.hyperparams) or None, **settings)
        curve = res.meta["curve"]
        last = curve["eval_mean_return"][-1] if curve["eval_mean_return"] else float("nan")
        tune.report({"seed": run.seed, "eval_mean_return": last, "train_seconds": res.meta["train_seconds"]},
                    checkpoint=tune.Checkpoint.from_directory(res.files.model.parent))


def _on_ray(env_id: str, algo: str, runs: list[Run], settings: dict[str, Any], ray_address: str,
            storage: str | None, deliver: Any) -> None:
    """Train ``runs`` as Ray Tune trials and call ``deliver(j, folder)`` with each run's index in ``runs`` and a
    folder holding its files (gone after the call)."""
    from paragym.baselines.ray_session import import_ray, ray_session

    # Ray Tune's console tables: off, unless the user set them (paragym prints a line per run)
    os.environ.setdefault("RAY_AIR_NEW_OUTPUT", "0")
    import_ray("--ray", tune=True)
    from ray import tune

    root = Path(tempfile.mkdtemp(prefix="paragym-tune-")) if storage is None else None
    try:
        with ray_session(ray_address, what="--ray"):
            trainable = tune.with_resources(
                tune.with_parameters(_trial, env_id=env_id, algo=algo, runs=runs, settings=settings),
                {"cpu": max(1, int(settings["threads"]))})
            tuner = tune.Tuner(trainable, param_space={"index": tune.grid_search(list(range(len(runs))))},
                               run_config=tune.RunConfig(name=f"paragym-{algo}", storage_path=str(root or storage),
                                                         verbose=0))
            results = sorted(tuner.fit(), key=lambda r: int(r.config["index"]))
        for result in results:
            if result.error is not None:
                raise RuntimeError(f"a Ray Tune trial failed: {type(result.error).__name__}: {result.error}")
        for result in results:
            with tempfile.TemporaryDirectory(prefix="paragym-trial-files-") as folder:
                deliver(int(result.config["index"]), Path(result.checkpoint.to_directory(folder)))
    finally:
        if root is not None:
            shutil.rmtree(root, ignore_errors=True)


def _take(folder: Path, files: RunFiles, force: bool) -> None:
    """Move a trial's files from ``folder`` to where ``files`` says, never over a model the run did not replace
    (``force``) or made meanwhile."""
    files.model.parent.mkdir(parents=True, exist_ok=True)
    if files.model.exists() and not force:
        raise ValueError(f"{files.model} appeared while its trial ran: the trial's model is not written over it")
    for target in (files.meta, files.curve_png, files.model):  # the model last: its presence means a whole run
        source = folder / target.name
        tmp = target.with_name(target.name + ".tmp")
        shutil.copyfile(source, tmp)
        os.replace(tmp, target)
