"""The floors of every leaderboard: uniformly random, zero and constant actions."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["ConstantPolicy", "RandomPolicy", "ZeroPolicy", "best_constant"]


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


class ConstantPolicy:
    """Always one action (``action``, inside the action space): a task's best constant action is one of its
    floors."""

    def __init__(self, action_space: gym.spaces.Box, action: Any) -> None:
        self.action = np.broadcast_to(np.asarray(action, action_space.dtype), action_space.shape).copy()
        if not action_space.contains(self.action):
            raise ValueError(f"action {self.action} is outside the action space {action_space}")

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return self.action.copy()


def best_constant(env_id: str, levels: tuple[float, ...] = (0.0, 0.5, 1.0), seeds: range = range(30)
                  ) -> tuple[tuple[float, ...], int, float]:
    """The best constant action of ``env_id`` among every action whose components are ``levels``, each played
    on the episodes reset with ``seeds`` (disjoint from the leaderboard's, 100000 and up): the most successes,
    then the highest mean return, then the first in order. Returns the action, its successes and its mean
    return. How a task's best-constant floor was chosen (its bench names the result)."""
    import itertools

    env = gym.make(env_id)
    best: tuple[int, float, tuple[float, ...]] | None = None
    for action in itertools.product(levels, repeat=int(np.prod(env.action_space.shape))):
        a = np.asarray(action, env.action_space.dtype).reshape(env.action_space.shape)
        wins, total = 0, 0.0
        for seed in seeds:
            env.reset(seed=seed)
            while True:
                _, reward, terminated, truncated, info = env.step(a)
                total += reward
                if terminated or truncated:
                    break
            wins += bool(info["is_success"])
        if best is None or (wins, total / len(seeds)) > best[:2]:
            best = (wins, total / len(seeds), action)
    env.close()
    return best[2], best[0], best[1]
