"""The shipped Stable-Baselines3 models: read-only package data (``paragym.models``).

``<env name>/<algo>_seed<N>.zip`` with its training config and curve (``.json``, ``.png``).
Found by name from any directory (:func:`shipped_models_dir`);
``paragym train`` never writes here (user training goes to ``runs/models``).
"""

from pathlib import Path

from paragym.registry import ROWS

__all__ = ["SHARED_WITH", "shipped_models_dir", "shipped_models_folder"]

#: env id -> the env id whose shipped models it plays (:attr:`paragym.registry.EnvRow.models_from`)
SHARED_WITH = {r.id: r.models_from for r in ROWS if r.models_from}


def shipped_models_dir() -> Path:
    """The folder of the shipped models (this package's data), wherever
    paragym is installed and whatever the working directory."""
    return Path(__file__).resolve().parent


def shipped_models_folder(env_id: str) -> Path:
    """The folder of ``env_id``'s shipped models (:data:`SHARED_WITH` read first)."""
    source = SHARED_WITH.get(env_id, env_id)
    return shipped_models_dir() / source.split("/", 1)[-1]
