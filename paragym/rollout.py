"""Run one episode of a policy in an environment and keep what happened."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["Episode", "frame_of", "run_episode"]


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
