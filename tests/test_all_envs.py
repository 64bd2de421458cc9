"""Shared contract of every registered paragym environment (later envs are covered automatically)."""

import gymnasium as gym
import numpy as np
import pytest
from env_ids import KINEMATIC_IDS, STEP_IDS

IDS = KINEMATIC_IDS  # one id per kinematic fidelity (tests/env_ids.py)


def _episode(env_id: str, seed: int, steps: int = 30) -> np.ndarray:
    env = gym.make(env_id)
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    out = [obs]
    for _ in range(steps):
        obs, r, term, trunc, _ = env.step(env.action_space.sample())
        out.append(np.append(obs, [r, term, trunc]))
        if term or trunc:
            obs, _ = env.reset()
            out.append(obs)
    env.close()
    return np.concatenate(out)


@pytest.mark.parametrize("env_id", IDS)
def test_same_seed_same_episode(env_id):
    np.testing.assert_array_equal(_episode(env_id, 5), _episode(env_id, 5))
    env = gym.make(env_id)
    env.reset(seed=1)
    for _ in range(10):  # random actions may end an episode early (a rung that tracks through the joints)
        if any(env.step(env.action_space.sample())[2:4]):
            break
    obs_after, _ = env.reset(seed=9)
    obs_fresh, _ = gym.make(env_id).reset(seed=9)
    np.testing.assert_array_equal(obs_after, obs_fresh)


@pytest.mark.parametrize("env_id", STEP_IDS)
def test_bad_actions_are_refused(env_id):
    env = gym.make(env_id, disable_env_checker=True)
    env.reset(seed=0)
    shape = env.action_space.shape
    with pytest.raises(ValueError, match="finite"):
        env.step(np.full(shape, np.nan, np.float32))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((shape[0] + 1,), np.float32))


@pytest.mark.parametrize("env_id", IDS)
def test_rgb_render_and_close(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8 and frame.std() > 5
    env.close()
