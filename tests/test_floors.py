"""The naive floors (issue 40): each task's one-line controller and best constant action, ranked beside zero and
random, doing what their rows say."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import paragym  # noqa: F401
from paragym.baselines.policies import get_policy, policies_for
from paragym.baselines.simple import best_constant
from paragym.baselines.tasks.tripod import BEST_CONSTANT
from paragym.units import DEG

NEWEST_FLOORS = {"paragym/CaPaManCollisionFree-v1": "straight-line", "paragym/HybridSingularityFree-v2": "greedy-split",
                 "paragym/MobileTripodOdometry-v2": "best-constant"}


@pytest.mark.parametrize("env_id, name", sorted(NEWEST_FLOORS.items()))
def test_the_newest_ids_rank_a_naive_floor_beside_zero_and_random(env_id, name):
    floors = {n for n, spec in policies_for(env_id).items() if spec.kind == "floor"}
    assert {"zero", "random", name} <= floors


@pytest.mark.parametrize("env_id", ["paragym/CaPaManCollisionFree-v0", "paragym/CaPaManCollisionFree-v1"])
def test_the_straight_line_steers_each_crank_at_the_target(env_id):
    env = gym.make(env_id)
    obs, info = env.reset(seed=11)
    s = env.unwrapped.state
    policy = get_policy(env_id, "straight-line").factory(env, 0)
    for _ in range(80):
        want = (s.tp[0, s.target_index[0]] - s.alpha[0]) / (2 * DEG)
        action = policy.act(obs, info)
        np.testing.assert_allclose(action, np.clip(want, -1, 1), atol=2e-5)  # the obs is float32
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    assert info["reached"] >= 1 or info["collision"]  # straight at the target: it gets there or hits something


def test_greedy_split_steps_toward_the_lower_end_excess():
    env = gym.make("paragym/HybridSingularityFree-v2")
    policy = get_policy("paragym/HybridSingularityFree-v2", "greedy-split").factory(env, 0)
    obs = np.zeros(48, np.float32)
    cases = {(0.3, -2.0, 1.0): 1.0, (0.3, 1.0, -2.0): -1.0, (0.3, 1.0, 2.0): 0.0, (0.0, -2.0, 1.0): 0.0}
    for (excess, up, down), step in cases.items():
        obs[45:48] = excess, up, down
        np.testing.assert_array_equal(policy.act(obs, {}), [step, 0, 0, 0])


@pytest.mark.parametrize("env_id", ["paragym/MobileTripodOdometry-v2", "paragym/CaPaManCollisionFree-Easy-v0",
                                    "paragym/HybridSingularityFree-Medium-v2"])
def test_the_searchs_episodes_together_are_the_single_envs(env_id):
    """The search plays an action's episodes together in the native vector env: each return and success is the
    single env's on the same seed."""
    from paragym.baselines.simple import ConstantPolicy, _constant_episodes, _one_by_one

    single = gym.make(env_id)
    native = gym.make_vec(env_id, num_envs=4, vectorization_mode="vector_entry_point")
    assert native.unwrapped.params == single.unwrapped.params
    constant = ConstantPolicy(single.action_space, np.full(single.action_space.shape, 0.5))
    assert _constant_episodes(native, constant.action, range(7, 11)) == _one_by_one(single, constant, range(7, 11))
    single.close()
    native.close()


@pytest.mark.slow
def test_the_best_constant_is_what_its_search_finds():
    """The shipped constant is re-derived, not typed: the search over {0, 0.5, 1}^3 on reset seeds 0-29."""
    action, wins, _ = best_constant("paragym/MobileTripodOdometry-v2")
    assert action == BEST_CONSTANT["paragym/MobileTripodOdometry-v2"] and wins == 13
    env = gym.make("paragym/MobileTripodOdometry-v2")
    policy = get_policy("paragym/MobileTripodOdometry-v2", "best-constant").factory(env, 0)
    np.testing.assert_array_equal(policy.act(np.zeros(16, np.float32), {}),
                                  BEST_CONSTANT["paragym/MobileTripodOdometry-v2"])
