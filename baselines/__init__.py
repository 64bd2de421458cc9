"""Baselines and the leaderboard (imported as ``paragym.baselines``).

* :mod:`~paragym.baselines.simple`: the floor, random and zero actions;
* :mod:`~paragym.baselines.training`: Stable-Baselines3 agents (``paragym train``),
  hyper-parameters in ``hyperparams/<algo>.yml``;
* :mod:`~paragym.baselines.policies`: every policy by env, one registration each;
* :mod:`~paragym.baselines.store` and :mod:`~paragym.baselines.leaderboard`: the
  results database and the runner behind ``paragym leaderboard``.

The SB3 parts import torch only when used, so the envs and planners work
without the ``rl`` extra.
"""

from paragym.baselines.simple import RandomPolicy, ZeroPolicy

__all__ = ["RandomPolicy", "ZeroPolicy"]
