"""Run one episode of a policy in an environment and keep what happened."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["Episode", "first_episodes", "frame_of", "run_episode"]


@dataclass
class Episode:
    """Observations (T+1), actions, rewards and infos (T+1, the reset's first)
    of one episode; ``frames`` when rendering was asked for; wall times (s)."""

    observations: list[np.ndarray] = field(default_factory=list)
    actions: list[np.ndarray] = field(default_factory=list)
    rewards: list[float] = field(default_factory=list)
    infos: list[dict[str, Any]] = field(default_factory=list)
    frames: list[np.ndarray] = field(default_factory=list)
    terminated: bool = False
    truncated: bool = False
    reset_seconds: float = 0.0
    step_seconds: float = 0.0

    @property
    def episode_return(self) -> float:
        """Sum of the rewards."""
        return float(np.sum(self.rewards))

    @property
    def success(self) -> bool:
        """``info["is_success"]`` at the end."""
        return bool(self.infos[-1].get("is_success", False))


def frame_of(env: gym.Env) -> np.ndarray:
    """``env.render()``, which must be an RGB image (an env made with ``render_mode="rgb_array"``)."""
    frame = env.render()
    if not isinstance(frame, np.ndarray):
        raise ValueError(f"env must be made with render_mode='rgb_array' to record frames; its render gave "
                         f"{type(frame).__name__}")
    return frame


def run_episode(env: gym.Env, policy: Any, seed: int | None = None, frame_every: int = 0) -> Episode:
    """Reset ``env`` with ``seed``, let ``policy`` (``reset``/``act``) act until
    the episode ends. ``frame_every > 0`` keeps ``env.render()`` every that
    many steps (``render_mode="rgb_array"``)."""
    ep = Episode()
    t0 = time.perf_counter()
    obs, info = env.reset(seed=seed)
    policy.reset(obs, info)
    ep.reset_seconds = time.perf_counter() - t0
    ep.observations.append(obs)
    ep.infos.append(info)
    if frame_every:
        ep.frames.append(frame_of(env))
    t0 = time.perf_counter()
    while not (ep.terminated or ep.truncated):
        action = policy.act(obs, info)
        obs, reward, ep.terminated, ep.truncated, info = env.step(action)
        ep.observations.append(obs)
        ep.actions.append(np.asarray(action))
        ep.rewards.append(float(reward))
        ep.infos.append(info)
        if frame_every and (len(ep.actions) % frame_every == 0 or ep.terminated or ep.truncated):
            ep.frames.append(frame_of(env))
    ep.step_seconds = time.perf_counter() - t0
    return ep


def first_episodes(envs: Any, act: Callable[[np.ndarray], np.ndarray], seeds: Sequence[int]
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each robot's first episode of a native vector env ``envs`` (one robot per seed, reset with ``seeds``), robot
    r acting with row r of ``act(obs)`` (``obs``: every robot's observation): the rewards (T, R), 0 after a robot's
    episode ended, each episode's length (R,) and whether it succeeded (R,). A robot's
    :attr:`Episode.episode_return` is ``np.sum`` of its first ``length`` rewards."""
    obs, _ = envs.reset(seed=list(seeds))
    n = len(seeds)
    rows: list[np.ndarray] = []
    running, success, length = np.ones(n, bool), np.zeros(n, bool), np.zeros(n, np.int64)
    while running.any():
        obs, reward, terminated, truncated, info = envs.step(act(obs))
        rows.append(np.where(running, reward, 0.0))
        length += running
        ended = running & (terminated | truncated)
        success[ended] = np.asarray(info["is_success"], bool)[ended]
        running &= ~ended
    return np.array(rows), length, success
