"""The shipped Stable-Baselines3 models: read-only package data (``paragym.models``).

``<env name>/<algo>_seed<N>.zip`` with its training config and curve (``.json``, ``.png``).
Found by name from any directory (:func:`shipped_models_dir`);
``paragym train`` never writes here (user training goes to ``runs/models``).
"""

from pathlib import Path

__all__ = ["SHARED_WITH", "shipped_models_dir", "shipped_models_folder"]

#: env id -> the env id whose shipped models it plays: a later version whose default mode runs the earlier one's
#: episodes bit for bit where its rules do not end them sooner (tested), so that the earlier version's models are
#: its own
SHARED_WITH = {"paragym/Orthoglide2PRRKappa-v1": "paragym/Orthoglide2PRRKappa-v0",
               "paragym/HybridSingularityFree-v2": "paragym/HybridSingularityFree-v1",
               "paragym/MobileTripodOdometry-v2": "paragym/MobileTripodOdometry-v1"}


def shipped_models_dir() -> Path:
    """The folder of the shipped models (this package's data), wherever
    paragym is installed and whatever the working directory."""
    return Path(__file__).resolve().parent


def shipped_models_folder(env_id: str) -> Path:
    """The folder of ``env_id``'s shipped models (:data:`SHARED_WITH` read first)."""
    source = SHARED_WITH.get(env_id, env_id)
    return shipped_models_dir() / source.split("/", 1)[-1]
