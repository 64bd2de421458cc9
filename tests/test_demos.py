"""``paragym demos`` (Minari datasets of the reference) and behaviour cloning from them (issue 17)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")
pytest.importorskip("jax")  # Minari's DataCollector needs it (the 'demos' extra)

from paragym import registry  # noqa: E402
from paragym.baselines.demos import AUTHOR, dataset_id_for, demo_seed, record_demos  # noqa: E402

ENV = "paragym/MobileTripodOdometry-v1"


@pytest.fixture
def datasets(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    root = tmp_path / "minari"
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return root


def test_demos_make_a_minari_dataset_that_reloads(datasets: Path):
    data = record_demos(ENV, 2)
    again = minari.load_dataset(dataset_id_for(ENV, "encoder-correction"))
    assert again.total_episodes == 2 and again.spec.env_spec.id == ENV
    meta = again.storage.metadata
    assert meta["author"] in (AUTHOR, {AUTHOR}, [AUTHOR])
    assert meta["ref_max_score"] > meta["ref_min_score"]  # the reference beats the random floor
    assert meta["num_episodes_average_score"] == 2  # the episodes the scores were measured on, not Minari's 100
    assert not meta.get("code_permalink")  # no address that does not exist
    episode = next(again.iterate_episodes())
    assert episode.observations.shape == (607, 16) and episode.actions.shape == (606, 3)
    # the recorded episode is the env's, step for step: replay its actions from the same seed
    import gymnasium as gym

    env = gym.make(ENV)
    obs, _ = env.reset(seed=demo_seed(0))
    np.testing.assert_allclose(obs, episode.observations[0], rtol=0, atol=0)
    total = 0.0
    for k, action in enumerate(episode.actions):
        obs, reward, *_ = env.step(action)
        total += reward
        np.testing.assert_allclose(obs, episode.observations[k + 1], rtol=0, atol=0)
    assert total == pytest.approx(float(episode.rewards.sum()))
    assert data.total_steps == again.total_steps


def test_demos_never_overwrite_without_force_nor_a_foreign_dataset(datasets: Path):
    record_demos(ENV, 1)
    with pytest.raises(ValueError, match="exists; --force"):
        record_demos(ENV, 1)
    assert record_demos(ENV, 2, force=True).total_episodes == 2
    # a dataset written by someone else under paragym's id is not replaced
    path = datasets / "paragym" / "MobileTripodOdometry-v1" / "encoder-correction-v0" / "data" / "metadata.json"
    meta = json.loads(path.read_text())
    meta["author"] = ["someone else"]
    path.write_text(json.dumps(meta))
    before = path.read_bytes()
    with pytest.raises(ValueError, match="not written by paragym"):
        record_demos(ENV, 1, force=True)
    assert path.read_bytes() == before


def test_bc_clones_the_dataset_and_ranks_as_a_learned_policy(datasets: Path, tmp_path: Path):
    pytest.importorskip("stable_baselines3")
    from paragym.baselines.bc import train_bc
    from paragym.baselines.policies import policies_for
    from paragym.baselines.training import load_model, train

    with pytest.raises(ValueError, match="paragym demos"):
        train_bc(ENV, models_dir=tmp_path / "m")
    with pytest.raises(ValueError, match="demonstrations"):
        train(ENV, "bc", models_dir=tmp_path / "m")
    record_demos(ENV, 3)
    res = train_bc(ENV, models_dir=tmp_path / "m", overrides={"epochs": 3})
    assert res.files.model.name == "bc_seed0.zip" and res.files.curve_png.is_file()
    assert res.meta["dataset_episodes"] == 3 and len(res.meta["curve"]["holdout_loss"]) == 3
    model = load_model(res.files.model)
    obs = np.zeros(16, np.float32)
    assert model.predict(obs, deterministic=True)[0].shape == (3,)
    assert "user-bc-seed0" in policies_for(ENV, tmp_path / "m")
    with pytest.raises(ValueError, match="--force"):
        train_bc(ENV, models_dir=tmp_path / "m")
    # PPO with init_from: bc starts from the clone (learning rate 0: nothing moves it)
    tiny = {"n_envs": 4, "n_steps": 16, "batch_size": 64, "n_epochs": 1, "learning_rate": 0.0, "eval_freq": 10 ** 9,
            "n_eval_episodes": 1, "init_from": "bc"}
    ppo = train(ENV, "ppo", models_dir=tmp_path / "m", timesteps=64, progress_bar=False, hyperparams=tiny).model
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(20, 16)).astype(np.float32)
    np.testing.assert_allclose(ppo.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0],
                               rtol=0, atol=1e-6)
    fresh = train(ENV, "ppo", models_dir=tmp_path / "n", timesteps=64, progress_bar=False,
                  hyperparams={**tiny, "init_from": None}).model
    assert np.abs(fresh.predict(obs, deterministic=True)[0] - model.predict(obs, deterministic=True)[0]).max() > 1e-3


def test_demos_skip_a_scenario_the_planner_cannot_solve(datasets: Path, monkeypatch: pytest.MonkeyPatch):
    """RRT + GA finds no plan for the CaPaMan scenario of reset seed 100002
    (one of the leaderboard's): starting the demonstrations there records
    the next seed instead, and the description names the skipped one."""
    import paragym.baselines.demos as demos

    monkeypatch.setattr(demos, "DEMO_SEED", 100_002)
    data = record_demos("paragym/CaPaManCollisionFree-v1", 1)
    assert data.total_episodes == 1
    assert "but [100002] (no plan found)" in data.storage.metadata["description"]


@pytest.mark.parametrize("env_id", [r.id for r in registry.ROWS])
def test_the_demos_command_records_every_registered_id(env_id: str, datasets: Path, capsys: pytest.CaptureFixture):
    """``paragym demos`` dispatches the same way for every id, v1 and v2 included (one zero-policy episode)."""
    from paragym.cli import main

    assert main(["demos", env_id.split("/")[1], "--episodes", "1", "--policy", "zero", "--no-progress"]) == 0
    assert "1 episodes" in capsys.readouterr().out
    assert minari.load_dataset(dataset_id_for(env_id, "zero")).total_episodes == 1


def test_bc_without_its_dataset_names_the_command_that_records_it(datasets: Path, tmp_path: Path):
    """CaPaMan v1's clone learns from grid-dijkstra's episodes, not the reference's: the hint records those."""
    from paragym.baselines.bc import train_bc

    with pytest.raises(ValueError, match="paragym demos paragym/CaPaManCollisionFree-v1 --episodes 200 --policy "
                                         "grid-dijkstra"):
        train_bc("paragym/CaPaManCollisionFree-v1", models_dir=tmp_path)
