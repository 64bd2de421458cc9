"""Where a training run's files go and what they hold: the model, its config and curve, its picture, the
checkpoints of a run under way (:mod:`paragym.baselines.training`). A finished run is never overwritten without
``force``."""

from __future__ import annotations

import json
import os
import platform
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym

import paragym
from paragym import check_env_id
from paragym.baselines.config import check_algo
from paragym.baselines.loading import LOADABLE, load_model
from paragym.models import shipped_models_dir

__all__ = ["USER_MODELS", "RunFiles", "TrainResult", "count_parameters", "env_name",
           "run_files", "versions", "writable_models_dir", "write_atomic"]


def env_name(env_id: str) -> str:
    """The env id without its namespace: the name of its folder under ``models/``."""
    return check_env_id(env_id).split("/", 1)[1]


@dataclass(frozen=True)
class RunFiles:
    """Where one (env, algo, seed) run keeps its files."""

    model: Path
    meta: Path
    curve_png: Path
    checkpoints: Path


#: where ``paragym train`` writes by default
USER_MODELS = Path("runs") / "models"


#: the fidelities a run trains in
FIDELITIES = ("kinematic", "dynamic")


def fidelity_dir(models_dir: str | Path, fidelity: str = "kinematic", engine: str = "pybullet") -> Path:
    """The folder of a run's ``<env name>/`` folder: ``models_dir`` for the kinematic fidelity, its
    ``dynamic-<engine>/`` for the dynamic fidelity in ``engine`` ("pybullet" or "mujoco"), so that the two never
    take each other's models; ``paragym leaderboard --models`` takes either folder."""
    from paragym.tasks.base import check_choice

    check_choice("fidelity", fidelity, FIDELITIES)
    check_choice("engine", engine, ("pybullet", "mujoco"))
    return Path(models_dir) if fidelity == "kinematic" else Path(models_dir) / f"dynamic-{engine}"


def run_files(env_id: str, algo: str, seed: int, models_dir: str | Path = USER_MODELS) -> RunFiles:
    """The files of a run under ``models_dir/<env name>/``."""
    folder = Path(models_dir) / env_name(env_id)
    stem = f"{check_algo(algo, LOADABLE)}_seed{int(seed)}"
    return RunFiles(folder / f"{stem}.zip", folder / f"{stem}.json", folder / f"{stem}.png",
                    folder / "checkpoints" / stem)


@dataclass
class TrainResult:
    """A finished run: its files, the trained model and the metadata written with it."""

    files: RunFiles
    model: Any
    meta: dict[str, Any]
    resumed_from: int = 0
    skipped: bool = False


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` whole or not at all (a file beside it, renamed over it)."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def count_parameters(model: Any) -> dict[str, int]:
    """Parameters of the whole policy and, for SAC/TD3, of the actor alone."""
    modules = {"policy": model.policy, "actor": getattr(model, "actor", None)}
    return {name: int(sum(p.numel() for p in m.parameters())) for name, m in modules.items() if m is not None}


def writable_models_dir(models_dir: str | Path) -> str | Path:
    """``models_dir``, unless it is the shipped models' folder (read-only)."""
    if Path(models_dir).resolve() == shipped_models_dir().resolve():
        raise ValueError(f"{models_dir} holds the shipped models, which are read-only: train into another folder "
                         f"(the default is {USER_MODELS})")
    return models_dir


def _finished_run(files: RunFiles, algo: str, total: int, force: bool) -> TrainResult | None:
    """A finished run of the same timesteps, as it is (``skipped``); None to
    train. A finished run of other timesteps is refused unless ``force``."""
    if not files.model.exists() or force:
        return None
    meta = json.loads(files.meta.read_text()) if files.meta.exists() else {}
    if meta.get("timesteps") == total:
        return TrainResult(files, load_model(files.model, algo), meta, skipped=True)
    raise ValueError(f"{files.model} is already trained ({meta.get('timesteps', 'an unknown number of')} steps); "
                     f"--force retrains it over that file, or choose another --models folder or --seed")


def _save_run(files: RunFiles, model: Any, meta: dict[str, Any], title: str) -> None:
    """The model, its JSON (with the model's size) and its curve's picture;
    the checkpoints go."""
    from paragym.plots import plot_training_curve

    files.model.parent.mkdir(parents=True, exist_ok=True)
    model.save(files.model)
    meta["model_bytes"] = files.model.stat().st_size
    write_atomic(files.meta, json.dumps(meta, indent=1))
    plot_training_curve(meta["curve"], files.curve_png, title)
    for name in ("latest.zip", "replay_buffer.pkl", "curve.json", "evaluations.npz", "vecnormalize.pkl",
                 "init_from.json"):
        (files.checkpoints / name).unlink(missing_ok=True)
    for folder in (files.checkpoints, files.checkpoints.parent):
        if folder.exists() and not any(folder.iterdir()):
            folder.rmdir()


def versions() -> dict[str, str]:
    """The versions of what trained the model (paragym, SB3, PyTorch, Gymnasium, Python), as a run records them."""
    import stable_baselines3
    import torch

    return {"paragym": paragym.__version__, "stable_baselines3": stable_baselines3.__version__,
            "torch": torch.__version__, "gymnasium": gym.__version__, "python": platform.python_version()}


