"""``train_scenarios=K`` (issue 40): a finite training set of scenarios, as Procgen's ``num_levels``, the same in the
single env and the native vector env, unseen by the leaderboard's evaluation seeds."""

from __future__ import annotations

import inspect
import pickle

import gymnasium as gym
import pytest
from env_ids import KINEMATIC_IDS

import paragym


def _key(scenario) -> str:
    return pickle.dumps(scenario).hex()


@pytest.mark.parametrize("env_id", KINEMATIC_IDS)  # one id per kinematic fidelity (tests/env_ids.py)
@pytest.mark.slow
def test_k_levels_are_the_scenarios_of_seeds_0_to_k_minus_1(env_id):
    plain = gym.make(env_id)
    levels = {_key(plain.reset(seed=level)[1]["scenario"]) for level in range(3)}
    env = gym.make(env_id, train_scenarios=3)
    drawn = [_key(env.reset(seed=100_000 + k)[1]["scenario"]) for k in range(12)]
    assert set(drawn) <= levels and len(set(drawn)) >= 2, (len(set(drawn)), len(levels))
    unseen = {_key(plain.reset(seed=100_000 + k)[1]["scenario"]) for k in range(12)}
    assert not unseen & levels  # the leaderboard's seeds draw none of them
    plain.close()
    env.close()


def test_the_vector_env_draws_the_same_levels_as_the_single_env():
    env_id = "paragym/HybridSingularityFree-v2"
    single = gym.make(env_id, train_scenarios=4)
    vec = gym.make_vec(env_id, num_envs=6, vectorization_mode="vector_entry_point", train_scenarios=4)
    vec.reset(seed=7)
    drawn = vec.unwrapped.state.scenarios
    for i in range(6):
        _, info = single.reset(seed=7 + i)
        assert _key(info["scenario"]) == _key(drawn[i])
    assert len({_key(s) for s in drawn}) <= 4
    single.close()
    vec.close()


def test_train_scenarios_is_an_argument_checked_by_name():
    env_id = "paragym/Orthoglide2PRRKappa-v1"
    assert "train_scenarios" in inspect.signature(type(gym.make(env_id).unwrapped)).parameters
    for bad, kind in ((0, ValueError), (100_001, ValueError), (True, TypeError), (2.0, TypeError)):
        with pytest.raises(kind, match="train_scenarios"):
            gym.make(env_id, train_scenarios=bad)
    assert paragym  # the ids are registered by importing paragym
