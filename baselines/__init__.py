"""Baselines and the leaderboard (imported as ``paragym.baselines``).

* :mod:`~paragym.baselines.simple`: the floor, random and zero actions;
* :mod:`~paragym.baselines.training`: Stable-Baselines3 agents (``paragym train``),
  hyper-parameters in ``hyperparams/<algo>.yml``;
* :mod:`~paragym.baselines.policies`: every policy by env, one registration each;
* :mod:`~paragym.baselines.store` and :mod:`~paragym.baselines.leaderboard`: the
  results database and the runner behind ``paragym leaderboard``;
* :mod:`~paragym.baselines.sb3_vec`: ``as_sb3_vecenv``, SB3 on a native vector env
  (also ``paragym.baselines.as_sb3_vecenv``).

The SB3 parts import torch only when used, so the envs and planners work
without the ``rl`` extra.
"""

from typing import Any

from paragym.baselines.simple import RandomPolicy, ZeroPolicy

__all__ = ["RandomPolicy", "ZeroPolicy", "as_sb3_vecenv"]


def __getattr__(name: str) -> Any:
    """``as_sb3_vecenv`` on first use (it imports Stable-Baselines3, the ``rl`` extra)."""
    if name == "as_sb3_vecenv":
        from paragym.baselines.sb3_vec import as_sb3_vecenv

        return as_sb3_vecenv
    raise AttributeError(f"module 'paragym.baselines' has no attribute {name!r}")
