"""The shipped Stable-Baselines3 models: read-only package data (``paragym.models``).

``<env name>/<algo>_seed<N>.zip`` with its training config and curve (``.json``, ``.png``).
Found by name from any directory (:func:`shipped_models_dir`);
``paragym train`` never writes here (user training goes to ``runs/models``).
"""

from pathlib import Path

from paragym import registry

__all__ = ["shipped_models_dir", "shipped_models_folder", "shared_with"]


def shared_with(env_id: str) -> str | None:
    """The env id whose shipped models ``env_id`` plays (:attr:`paragym.registry.EnvRow.models_from`), or None."""
    return registry.row(env_id).models_from


def shipped_models_dir() -> Path:
    """The folder of the shipped models (this package's data), wherever
    paragym is installed and whatever the working directory."""
    return Path(__file__).resolve().parent


def shipped_models_folder(env_id: str) -> Path:
    """The folder of ``env_id``'s shipped models (those of :func:`shared_with` where it plays another's)."""
    source = shared_with(env_id) or env_id
    return shipped_models_dir() / source.split("/", 1)[-1]
