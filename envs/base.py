"""The base class every paragym environment derives from.

As in Gymnasium-Robotics, the base owns ``reset``/``step``/``render``/``close``
and the checks every task shares (the action's shape and finiteness, the
render mode); a task fills the hooks below. All randomness comes from
``self.np_random``, so the same seed gives the same episode bit for bit.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["ParagymEnv"]


class ParagymEnv(gym.Env):
    """Shared ``reset``/``step``/``render``/``close``; tasks fill the hooks.

    Hooks: ``_reset_task(options) -> info``, ``_apply_action(action)``,
    ``_observe() -> obs``, ``_reward() -> float``, ``_terminated() -> bool``,
    ``_info() -> dict``, ``_render_rgb() -> array``, ``_close()``.
    """

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 25}

    def __init__(self, render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None; "
                             f"got {render_mode!r}")
        self.render_mode = render_mode

    # --- the loop -------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        info = self._reset_task(options or {})
        return self._observe(), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        self._apply_action(self._check_action(action))
        obs = self._observe()
        reward = self._reward()
        terminated = self._terminated()
        return obs, reward, terminated, False, self._info()

    def render(self) -> np.ndarray | None:
        if self.render_mode == "rgb_array":
            return self._render_rgb()
        if self.render_mode == "human":
            self._show()  # the PyBullet GUI window shows the scene
        return None

    def close(self) -> None:
        self._close()

    # --- shared input check ---------------------------------------------------------------
    def _check_action(self, action: np.ndarray) -> np.ndarray:
        arr = np.asarray(action, dtype=np.float64)
        space = self.action_space
        if arr.shape != space.shape:
            raise ValueError(f"action must have shape {space.shape}; got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"action must be finite; got {arr}")
        return arr

    # --- hooks ---------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any]) -> dict[str, Any]:
        raise NotImplementedError

    def _apply_action(self, action: np.ndarray) -> None:
        raise NotImplementedError

    def _observe(self) -> np.ndarray:
        raise NotImplementedError

    def _reward(self) -> float:
        raise NotImplementedError

    def _terminated(self) -> bool:
        raise NotImplementedError

    def _info(self) -> dict[str, Any]:
        raise NotImplementedError

    def _render_rgb(self) -> np.ndarray:
        raise NotImplementedError

    def _show(self) -> None:
        """Update the GUI in ``render_mode="human"``; a scene that PyBullet
        keeps up to date itself needs nothing (the default)."""

    # --- a PyBullet scene built on the first render, for envs whose step needs none ----
    _render_scene: Any = None

    def _drawn(self, build: Any, pose: Any) -> np.ndarray:
        """Build the render scene on first use (``build(gui)``), pose it
        (``pose(scene)``) and draw it."""
        if self._render_scene is None:
            self._render_scene = build(self.render_mode == "human")
        pose(self._render_scene)
        return self._render_scene.render()

    def _close_render_scene(self) -> None:
        if self._render_scene is not None:
            self._render_scene.close()
            self._render_scene = None

    def _close(self) -> None:
        raise NotImplementedError
