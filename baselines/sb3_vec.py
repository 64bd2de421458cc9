"""Stable-Baselines3 on a paragym native vector env: :func:`as_sb3_vecenv`.

SB3's ``VecEnv`` resets a finished sub-environment within the same step and
hands the last observation over in ``infos[i]["terminal_observation"]``
(with ``infos[i]["TimeLimit.truncated"]`` for a time limit); paragym's
native vector envs follow gymnasium 1.x's NEXT_STEP autoreset. The adapter
steps the env's SAME_STEP view (:class:`paragym.envs.vector.SameStepVectorEnv`,
which resets the robots that finished at once) and hands its ``final_obs`` on
as SB3's ``terminal_observation``, so SB3 sees exactly its own contract while
all robots still step in one numpy call.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvStepReturn

from paragym.envs.vector import ParagymVectorEnv, SameStepVectorEnv

__all__ = ["ParagymSB3VecEnv", "as_sb3_vecenv"]


class ParagymSB3VecEnv(VecEnv):
    """A :class:`ParagymVectorEnv` behind SB3's ``VecEnv`` interface."""

    def __init__(self, venv: ParagymVectorEnv) -> None:
        self.venv = venv
        self._same = SameStepVectorEnv(venv)
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions: np.ndarray | None = None
        self._first_reset = True

    def reset(self) -> np.ndarray:
        seeds = self._seeds if any(s is not None for s in self._seeds) else None
        obs, _ = self.venv.reset(seed=seeds)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        obs, rewards, terminated, truncated, info = self._same.step(self._actions)
        dones = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if dones.any():
            success = info["final_info"].get("is_success")
            for i in np.flatnonzero(dones):
                infos[i]["terminal_observation"] = info["final_obs"][i]
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
                if success is not None:  # what SB3's EvalCallback reads of a finished episode
                    infos[i]["is_success"] = bool(success[i])
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        method = getattr(self.venv, method_name)
        return [method(*method_args, **method_kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [self.venv.render()]


def as_sb3_vecenv(env_id_or_venv: str | ParagymVectorEnv, num_envs: int = 64, **kwargs: Any) -> ParagymSB3VecEnv:
    """An SB3 ``VecEnv`` over a native vector env: pass one, or an env id
    (made with ``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``,
    ``num_envs`` robots, ``kwargs`` for the env)."""
    if isinstance(env_id_or_venv, str):
        import paragym  # noqa: F401  (registers the ids)

        venv = gym.make_vec(env_id_or_venv, num_envs=num_envs, vectorization_mode="vector_entry_point", **kwargs)
    else:
        venv = env_id_or_venv
    venv = getattr(venv, "unwrapped", venv)
    if not isinstance(venv, ParagymVectorEnv):
        raise ValueError(f"as_sb3_vecenv needs a paragym native vector env; got {type(venv).__name__}")
    return ParagymSB3VecEnv(venv)
