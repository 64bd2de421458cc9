"""paragym train: hyper-parameters, files, resume, loading, numpy inference."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402

from paragym.baselines.policies import LearnedPolicy  # noqa: E402
from paragym.baselines.training import ALGOS, load_hyperparams, load_model, run_files, train  # noqa: E402
from paragym.cli import main  # noqa: E402

HYBRID = "paragym/HybridSingularityFree-v0"
TINY = {"ppo": {"n_envs": 2, "n_steps": 64, "batch_size": 64, "n_epochs": 2, "eval_freq": 128, "n_eval_episodes": 1,
                "checkpoint_freq": 128},
        "sac": {"learning_starts": 50, "batch_size": 32, "eval_freq": 200, "n_eval_episodes": 1},
        "td3": {"learning_starts": 50, "batch_size": 32, "eval_freq": 200, "n_eval_episodes": 1},
        "tqc": {"learning_starts": 50, "batch_size": 32, "eval_freq": 200, "n_eval_episodes": 1}}


@pytest.mark.parametrize("algo", ALGOS)
def test_every_env_has_hyperparameters(algo):
    import paragym

    for env_id in paragym.ENVIRONMENTS:
        hp = load_hyperparams(algo, env_id)
        assert hp["n_timesteps"] > 0 and hp["policy"] == "MlpPolicy" and hp["eval_freq"] > 0


@pytest.mark.parametrize("algo", ALGOS)
def test_a_short_run_writes_its_files_and_is_not_repeated(tmp_path, algo):
    res = train(HYBRID, algo, seed=1, timesteps=400, models_dir=tmp_path, progress_bar=False, hyperparams=TINY[algo])
    files = run_files(HYBRID, algo, 1, tmp_path)
    assert files.model.is_file() and files.curve_png.is_file() and not files.checkpoints.exists()
    meta = json.loads(files.meta.read_text())
    assert meta["timesteps"] == 400 and meta["algo"] == algo and meta["parameters"]["policy"] > 0
    assert meta["curve"]["eval_timesteps"] and len(meta["curve"]["eval_mean_return"]) == len(
        meta["curve"]["eval_timesteps"])
    assert res.model.num_timesteps >= 400
    again = train(HYBRID, algo, seed=1, timesteps=400, models_dir=tmp_path, progress_bar=False)
    assert again.skipped


def test_training_leaves_no_folder_in_the_temp_dir(tmp_path, monkeypatch):
    """SB3's default logger makes an empty ``SB3-<date>`` folder in the temp dir at every learn: paragym's
    training gives the model a logger without a folder, so a run writes only its own files."""
    import tempfile

    temp = tmp_path / "temp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    train(HYBRID, "ppo", seed=3, timesteps=128, models_dir=tmp_path / "models", progress_bar=False,
          hyperparams=TINY["ppo"])
    assert list(temp.glob("SB3-*")) == []  # (torch may keep its own cache there, torchinductor_<user>)


@pytest.mark.parametrize("algo", ALGOS)
def test_numpy_inference_equals_predict(tmp_path, algo):
    res = train(HYBRID, algo, seed=0, timesteps=200, models_dir=tmp_path, progress_bar=False, hyperparams=TINY[algo])
    model = load_model(res.files.model)
    policy = LearnedPolicy(model)
    assert policy.layers is not None
    obs = np.random.default_rng(0).uniform(-3, 3, (100, *model.observation_space.shape)).astype(np.float32)
    ours = np.array([policy.act(o, {}) for o in obs])
    theirs = np.array([model.predict(o, deterministic=True)[0] for o in obs])
    assert np.abs(ours - theirs).max() < 1e-5
    from paragym.baselines.actor import actor_from_file  # the leaderboard's way, without PyTorch: the same actor

    actor, observation = actor_from_file(res.files.model)
    assert observation == model.observation_space and actor.squash == policy.actor.squash
    for (w, b, f), (w2, b2, f2) in zip(actor.layers, policy.layers, strict=True):
        assert np.array_equal(w, w2) and np.array_equal(b, b2) and f == f2


class _Interrupt(BaseCallback):
    def __init__(self, after: int) -> None:
        super().__init__()
        self.after = after

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.after:
            raise KeyboardInterrupt
        return True


def test_an_interrupted_run_resumes_from_its_checkpoint(tmp_path):
    hp = {**TINY["ppo"], "normalize": "{'norm_obs': False, 'norm_reward': True}"}  # its statistics are checkpointed too
    with pytest.raises(KeyboardInterrupt):
        train(HYBRID, "ppo", seed=2, timesteps=768, models_dir=tmp_path, progress_bar=False, hyperparams=hp,
              callbacks=[_Interrupt(400)])
    files = run_files(HYBRID, "ppo", 2, tmp_path)
    assert (files.checkpoints / "latest.zip").is_file() and not files.model.exists()
    assert (files.checkpoints / "vecnormalize.pkl").is_file()
    res = train(HYBRID, "ppo", seed=2, timesteps=768, models_dir=tmp_path, progress_bar=False, hyperparams=hp)
    assert 256 <= res.resumed_from < 768
    assert res.model.num_timesteps >= 768
    curve = res.meta["curve"]["eval_timesteps"]
    assert curve == sorted(curve) and curve[0] < res.resumed_from < curve[-1]  # the curve continues
    assert not files.checkpoints.exists()


def test_bad_names_and_corrupt_files_are_clear_errors(tmp_path, capsys):
    with pytest.raises(ValueError, match="unknown env"):
        train("NoSuchEnv-v0", "ppo")
    with pytest.raises(ValueError, match="unknown algorithm"):
        train(HYBRID, "dqn")
    bad = tmp_path / "ppo_seed0.zip"
    bad.write_bytes(b"not a zip file")
    with pytest.raises(ValueError, match="cannot load PPO model"):
        load_model(bad)
    assert bad.read_bytes() == b"not a zip file"
    assert main(["train", "NoSuchEnv-v0"]) == 2
    assert main(["train", HYBRID, "--algo", "dqn"]) == 2
    err = capsys.readouterr().err
    assert "unknown env" in err and "unknown algorithm" in err


@pytest.mark.parametrize("env_id", sorted(__import__("paragym").ENVIRONMENTS))
@pytest.mark.slow
def test_vectorized_training_runs_for_every_env_with_its_yml(tmp_path, env_id, recwarn):
    """--vectorized with the yml's own settings (reward normalisation among them) evaluates,
    counts its steps truthfully and draws a curve, for every env id (issue 15, item 5)."""
    import warnings

    # one rollout of 4 x 32 steps, evaluated once at its end (an evaluation is a whole episode)
    small = {"n_steps": 32, "batch_size": 64, "n_epochs": 1, "eval_freq": 128, "n_eval_episodes": 1}
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        res = train(env_id, "ppo", seed=0, timesteps=100, models_dir=tmp_path, progress_bar=False,
                    hyperparams=small, vectorized=True, n_envs=4)
    assert res.meta["hyperparams"].get("normalize") == load_hyperparams("ppo", env_id).get("normalize")
    assert res.meta["num_timesteps"] == res.model.num_timesteps == 128  # whole rollouts of 4 x 32, said as such
    assert res.meta["curve"]["eval_timesteps"]
    assert res.files.curve_png.stat().st_size > 5_000


def test_a_run_too_short_for_any_episode_still_draws_an_honest_curve(tmp_path):
    import warnings

    from paragym.plots import plot_training_curve

    empty = {k: [] for k in ("eval_timesteps", "eval_mean_return", "eval_std_return", "eval_success_rate",
                             "train_timesteps", "train_return")}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        png = plot_training_curve(empty, tmp_path / "c.png", "nothing yet")
    assert png.stat().st_size > 2_000


def test_a_warm_start_is_written_down(tmp_path, capsys):
    """PPO's start from a behaviour clone is said on the console and recorded (file and SHA-256) in the model's
    JSON, and the leaderboard's description of the model names it."""
    import hashlib

    from paragym.baselines.policies import policies_for
    from paragym.models import shipped_models_folder

    env_id = "paragym/MobileTripodOdometry-v1"
    small = {"n_steps": 32, "batch_size": 64, "n_epochs": 1, "eval_freq": 64, "n_eval_episodes": 1}
    res = train(env_id, "ppo", seed=1, timesteps=64, models_dir=tmp_path, progress_bar=False, hyperparams=small,
                vectorized=True, n_envs=2)
    start = res.meta["hyperparams"]["init_from"]
    clone = shipped_models_folder(env_id) / "bc_seed0.zip"
    assert start["sha256"] == hashlib.sha256(clone.read_bytes()).hexdigest()
    assert start["file"] == "shipped: models/MobileTripodOdometry-v1/bc_seed0.zip"
    assert "starts from the behaviour clone shipped: models/MobileTripodOdometry-v1/bc_seed0.zip" in \
        capsys.readouterr().out
    described = policies_for(env_id, tmp_path)["user-ppo-seed1"].description
    assert f"sha256 {start['sha256'][:12]}" in described


def test_train_options_that_do_not_apply_are_refused(capsys):
    assert main(["train", HYBRID, "--algo", "dagger", "--timesteps", "500"]) == 2
    assert main(["train", HYBRID, "--algo", "ppp"]) == 2
    err = capsys.readouterr().err
    assert "--timesteps does not apply to dagger" in err
    assert "known: ppo, sac, td3, tqc, bc, dagger" in err
