"""The floor of every leaderboard: uniformly random and zero actions."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["RandomPolicy", "ZeroPolicy"]


class RandomPolicy:
    """Uniform samples of the action space, seeded (``seed``) for repeatability."""

    def __init__(self, action_space: gym.spaces.Box, seed: int | None = None) -> None:
        self.action_space = action_space
        self.rng = np.random.default_rng(seed)

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        space = self.action_space
        return self.rng.uniform(space.low, space.high).astype(space.dtype)


class ZeroPolicy:
    """Always the zero action (stand still, for joint-increment actions)."""

    def __init__(self, action_space: gym.spaces.Box) -> None:
        self.action_space = action_space

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return np.zeros(self.action_space.shape, self.action_space.dtype)
