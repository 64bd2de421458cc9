"""The shipped Stable-Baselines3 models: read-only package data (``paragym.models``).

``<env name>/<algo>_seed<N>.zip`` with its training config and curve (``.json``, ``.png``).
Found by name from any directory (:func:`shipped_models_dir`);
``paragym train`` never writes here (user training goes to ``runs/models``).
"""

from pathlib import Path

__all__ = ["shipped_models_dir"]


def shipped_models_dir() -> Path:
    """The folder of the shipped models (this package's data), wherever
    paragym is installed and whatever the working directory."""
    return Path(__file__).resolve().parent
