"""Loading a trained model to evaluate it: which algorithm a file holds, and its weights without unpickling
anything (:mod:`paragym.baselines.training`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from paragym.baselines.config import ALGOS, check_algo

__all__ = ["LOADABLE", "load_model", "model_algorithm"]

#: what :func:`load_model` loads: the RL algorithms, bc (behaviour cloning; bc.py) and dagger (dagger.py),
#: both PPO policies
LOADABLE = (*ALGOS, "bc", "dagger")


def _algorithm(algo: str) -> type:
    from stable_baselines3 import PPO, SAC, TD3

    if algo == "tqc":
        from sb3_contrib import TQC

        return TQC
    return {"ppo": PPO, "sac": SAC, "td3": TD3, "bc": PPO, "dagger": PPO}[algo]  # imitation: a PPO policy


def model_algorithm(path: str | Path) -> str | None:
    """The algorithm that saved the SB3 model file ``path``, read from the
    attributes only it has in the file's ``data`` JSON (PPO's ``clip_range``,
    TD3's ``policy_delay``, TQC's ``top_quantiles_to_drop_per_net``, SAC's
    ``target_entropy``); None when the file does not say. Nothing is
    unpickled."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as z:
            data = json.loads(z.read("data"))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return None
    marks = (("top_quantiles_to_drop_per_net", "tqc"), ("policy_delay", "td3"), ("target_entropy", "sac"),
             ("clip_range", "ppo"))
    return next((algo for key, algo in marks if key in data), None)


def load_model(path: str | Path, algo: str | None = None) -> Any:
    """Load a saved SB3 model on the CPU without unpickling anything from it
    (:mod:`paragym.baselines.safe_load`: every cloudpickled entry is rebuilt
    from its readable form, the weights are read as tensors only). The
    algorithm comes from ``algo``, else the file name (``ppo_seed0.zip``),
    else the file itself (:func:`model_algorithm`: rl-baselines3-zoo's
    ``<env>.zip``). A missing, damaged or unsafe file raises a ValueError
    naming it."""
    from paragym.baselines.safe_load import safe_custom_objects

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"no model file at {path}")
    if algo is None:
        algo = path.stem.split("_", 1)[0]
        if algo.lower() not in LOADABLE:  # rl-zoo names its files after the env: ask the file
            algo = model_algorithm(path) or algo
    algo = check_algo(algo, LOADABLE)
    cls = _algorithm(algo)
    try:
        custom = safe_custom_objects(path, cls)
        return cls.load(path, device="cpu", custom_objects=custom)
    except Exception as exc:  # zipfile, JSON, torch or key errors for a damaged file; ours for an unsafe one
        raise ValueError(f"cannot load {algo.upper()} model {path}: {type(exc).__name__}: {exc}") from exc


