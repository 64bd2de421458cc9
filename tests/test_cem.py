"""The cross-entropy search of linear policies (paragym.baselines.cem): a learner the leaderboard ranks."""

import json
import math

import gymnasium as gym
import numpy as np
import pytest

import paragym  # noqa: F401
from paragym.baselines.cem import CemSettings, read_linear, train_cem
from paragym.baselines.policies import policies_for
from paragym.cli import main

ENV = "paragym/Orthoglide2PRRKappa-Hard-v0"  # its random episodes end within a few steps: a cheap search
TINY = CemSettings(population=4, episodes=2, elite=0.5, budget_seconds=math.inf, generations=2)


def test_a_search_is_its_seed_and_its_generations_whatever_the_machine(tmp_path):
    a = train_cem(ENV, seed=3, settings=TINY, models_dir=tmp_path / "a")
    b = train_cem(ENV, seed=3, settings=TINY, models_dir=tmp_path / "b")
    c = train_cem(ENV, seed=4, settings=TINY)
    np.testing.assert_array_equal(a.W, b.W)
    np.testing.assert_array_equal(a.b, b.b)
    assert not np.array_equal(a.W, c.W) and c.model is None
    meta = json.loads(a.model.with_suffix(".json").read_text())
    assert meta["generations"] == 2 and meta["episodes_played"] == 2 * 4 * 2 and meta["algo"] == "cem"
    assert len(meta["curve"]["mean_success"]) == 2 and meta["first_reset_seed"] >= 1_000_000  # not the board's
    with pytest.raises(FileExistsError, match="force"):
        train_cem(ENV, seed=3, settings=TINY, models_dir=tmp_path / "a")


def test_the_policy_acts_as_its_arrays_say_and_the_leaderboard_finds_it(tmp_path):
    res = train_cem(ENV, seed=0, settings=TINY, models_dir=tmp_path)
    spec = policies_for(ENV, tmp_path)["user-cem-seed0"]
    assert spec.kind == "learned" and "cross-entropy" in spec.description
    assert json.loads(spec.producer())["params"]["model_sha256"]  # the file's hash keys its rows
    env = gym.make(ENV)
    policy = spec.factory(env, 0)
    rng = np.random.default_rng(0)
    for _ in range(20):
        obs = rng.uniform(-3, 3, env.observation_space.shape).astype(np.float32)
        want = np.clip(res.W.astype(np.float64) @ obs.astype(np.float64) + res.b, env.action_space.low,
                       env.action_space.high)
        np.testing.assert_allclose(policy.act(obs, {}), want, rtol=1e-5, atol=1e-5)
    with pytest.raises(ValueError, match="expects observations"):
        spec.factory(gym.make("paragym/Orthoglide2PRRKappa-v2"), 0)
    env.close()


def test_a_model_file_is_arrays_only(tmp_path):
    path = tmp_path / "cem_seed0.npz"
    np.savez(path, W=np.array([object()], dtype=object), b=np.zeros(1), low=np.zeros(1), high=np.ones(1))
    with pytest.raises(ValueError, match="allow_pickle"):
        read_linear(path)
    np.savez(path, W=np.zeros((2, 3)), b=np.zeros(2))
    with pytest.raises(ValueError, match="lacks high, low"):
        read_linear(path)


@pytest.mark.parametrize("field, value, message", [("population", 3, "population"), ("elite", 0.01, "elite"),
                                                    ("episodes", 0, "episodes"), ("init_std", -1.0, "init_std"),
                                                    ("budget_seconds", math.nan, "budget_seconds")])
def test_settings_are_checked_by_name(field, value, message):
    with pytest.raises(ValueError, match=message):
        CemSettings(**{field: value})


def test_paragym_train_runs_the_search(tmp_path, capsys):
    code = main(["train", "Orthoglide2PRRKappa-Hard-v0", "--algo", "cem", "--budget", "inf", "--generations", "1",
                 "--models", str(tmp_path), "--no-progress"])
    out = capsys.readouterr().out
    assert code == 0 and "1 generations" in out
    assert (tmp_path / "Orthoglide2PRRKappa-Hard-v0" / "cem_seed0.npz").is_file()
    assert main(["train", "Orthoglide2PRRKappa-Hard-v0", "--algo", "cem", "--timesteps", "5"]) == 2


def test_the_shipped_models_are_read_only_to_the_search():
    from paragym.models import shipped_models_dir

    with pytest.raises(ValueError, match="read-only"):
        train_cem(ENV, settings=TINY, models_dir=shipped_models_dir())


def test_a_stop_ends_the_search_and_its_time_is_not_search_time():
    import time

    calls = []

    def stop(actor, seconds, steps):
        calls.append((seconds, steps))
        time.sleep(0.3)
        return len(calls) == 2

    res = train_cem(ENV, settings=CemSettings(population=4, episodes=1, elite=0.5, budget_seconds=math.inf,
                                              generations=10), stop=stop)
    assert res.meta["generations"] == 2 and res.meta["stopped"] and len(calls) == 2
    assert calls[1][1] > calls[0][1] > 0 and res.meta["steps_played"] == calls[1][1]
    assert res.meta["train_seconds"] < 0.3  # the two 0.3 s sleeps are the stop's, not the search's
