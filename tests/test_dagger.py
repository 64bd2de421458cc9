"""DAgger (``paragym train ENV --algo dagger``): the expert labels the states the learner visits."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import paragym  # noqa: E402, F401
from paragym.baselines.dagger import rollout, train_dagger  # noqa: E402
from paragym.planners import GridFieldPolicy  # noqa: E402

ENV = "paragym/CaPaManCollisionFree-v1"


def test_the_learner_drives_and_the_expert_labels_every_state_it_reaches():
    from stable_baselines3 import PPO

    env = gym.make(ENV)
    expert = GridFieldPolicy(max_joint_step=env.unwrapped.max_joint_step)
    learner = PPO("MlpPolicy", env, seed=0, device="cpu", policy_kwargs={"net_arch": [8]})
    own = rollout(env, expert, learner, 123, expert_acts=True)
    theirs = rollout(env, expert, learner, 123, expert_acts=False)
    assert own.success and not theirs.success  # the untrained learner does not complete the tour
    np.testing.assert_array_equal(own.actions, own.labels)
    assert np.abs(np.array(theirs.actions[:20]) - np.array(theirs.labels[:20])).max() > 0.1
    # replay the learner's actions: the observations are those it reached, each labelled by the expert
    obs, info = env.reset(seed=123)
    expert.reset(obs, info)
    for x, y, a in zip(theirs.observations, theirs.labels, theirs.actions, strict=True):
        np.testing.assert_array_equal(obs, x)
        np.testing.assert_array_equal(np.clip(expert.act(obs, info), -1, 1), y)
        obs, _, terminated, truncated, info = env.step(a)
    assert terminated or truncated


def test_dagger_trains_saves_and_ranks_as_a_learned_policy(tmp_path: Path):
    from paragym.baselines.policies import policies_for
    from paragym.baselines.training import load_model

    tiny = {"iterations": 2, "episodes": 2, "epochs": 2, "eval_episodes": 1, "net_arch": [16, 16]}
    res = train_dagger(ENV, models_dir=tmp_path / "m", overrides=tiny)
    assert res.files.model.name == "dagger_seed0.zip" and res.files.curve_png.is_file()
    curve = res.meta["curve"]
    assert curve["iteration"] == [0, 1] and curve["rollout_success"][0] == 1.0  # iteration 0: the expert
    assert curve["pairs"][1] > curve["pairs"][0] > 0
    assert res.meta["expert"] == "grid-field" and res.meta["episodes"] == 4
    model = load_model(res.files.model)
    assert model.predict(np.zeros(41, np.float32), deterministic=True)[0].shape == (3,)
    spec = policies_for(ENV, tmp_path / "m")["user-dagger-seed0"]
    assert "DAgger with the expert grid-field" in spec.description
    with pytest.raises(ValueError, match="--force"):
        train_dagger(ENV, models_dir=tmp_path / "m", overrides=tiny)
    with pytest.raises(ValueError, match="feedback expert"):
        train_dagger("paragym/HybridSingularityFree-v1", models_dir=tmp_path / "m", overrides=tiny)
