"""The floors of every leaderboard: uniformly random, zero and constant actions."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from paragym.rollout import first_episodes

__all__ = ["ConstantPolicy", "RandomPolicy", "ZeroPolicy", "best_constant"]


def _box(action_space: gym.spaces.Space) -> gym.spaces.Box:
    """``action_space``, which these policies need to be a Box (every paragym env's is)."""
    if not isinstance(action_space, gym.spaces.Box):
        raise TypeError(f"action_space must be a gymnasium Box; got {type(action_space).__name__}")
    return action_space


class RandomPolicy:
    """Uniform samples of the action space, seeded (``seed``) for repeatability."""

    def __init__(self, action_space: gym.spaces.Space, seed: int | None = None) -> None:
        self.action_space = _box(action_space)
        self.rng = np.random.default_rng(seed)

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        space = self.action_space
        return self.rng.uniform(space.low, space.high).astype(space.dtype)


class ZeroPolicy:
    """Always the zero action (stand still, for joint-increment actions)."""

    def __init__(self, action_space: gym.spaces.Space) -> None:
        self.action_space = _box(action_space)

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
    return. How a task's best-constant floor was chosen (its bench names the result).

    Where the id's native vector env has the single env's parameters, its episodes are the single env's, bit
    for bit, and each action's episodes run there together (one robot per seed); else (the CaPaMan's released
    ids, whose native env checks collisions on the grid) one after the other in the single env."""
    import itertools

    single = gym.make(env_id)
    native = gym.make_vec(env_id, num_envs=len(seeds), vectorization_mode="vector_entry_point")
    together = native.unwrapped.params == single.unwrapped.params
    space = single.action_space
    best: tuple[int, float, tuple[float, ...]] | None = None
    for action in itertools.product(levels, repeat=int(np.prod(space.shape))):
        constant = ConstantPolicy(space, np.reshape(action, space.shape))
        returns, wins = _constant_episodes(native, constant.action, seeds) if together else \
            _one_by_one(single, constant, seeds)
        mean = float(np.mean(returns))
        if best is None or (wins, mean) > best[:2]:
            best = (wins, mean, action)
    single.close()
    native.close()
    assert best is not None  # levels and the space are not empty
    return best[2], best[0], best[1]


def _one_by_one(env: gym.Env, policy: ConstantPolicy, seeds: range) -> tuple[list[float], int]:
    """Each seed's episode of ``env`` under ``policy``: their returns and how many succeeded."""
    from paragym.rollout import run_episode

    episodes = [run_episode(env, policy, seed=seed) for seed in seeds]
    return [e.episode_return for e in episodes], sum(bool(e.success) for e in episodes)


def _constant_episodes(envs: Any, action: np.ndarray, seeds: range) -> tuple[list[float], int]:
    """One episode per seed of the native vector env ``envs`` (a robot each) under ``action``: each episode's
    return (summed as :attr:`paragym.rollout.Episode.episode_return` sums it) and how many succeeded."""
    actions = np.repeat(action[None], len(seeds), axis=0)
    rewards, length, success = first_episodes(envs, lambda obs: actions, seeds)
    return [float(np.sum(rewards[:k, i].copy())) for i, k in enumerate(length.tolist())], int(success.sum())
