"""Several training runs at once: seeds and sweeps, here and as Ray Tune trials (``paragym train --seeds/--sweep/
--ray``)."""

from __future__ import annotations

import json

import pytest

from paragym.baselines.trials import plan_runs, read_sweep, run_all
from paragym.cli import main

pytestmark = pytest.mark.slow  # every test here starts processes or runs a benchmark

ORTHO = "paragym/Orthoglide2PRRKappa-v0"
#: a run of a second: one PPO rollout of 64 steps on one robot
TINY = ["--algo", "ppo", "--timesteps", "64", "--n-envs", "1", "--no-progress"]


def _weights(path):
    from stable_baselines3 import PPO

    return {k: v.numpy().copy() for k, v in PPO.load(path, device="cpu").policy.state_dict().items()}


def _same(a, b) -> bool:
    return a.keys() == b.keys() and all((a[k] == b[k]).all() for k in a)


def test_ray_trials_train_what_the_runs_here_train_and_the_leaderboard_ranks_them(tmp_path, capsys):
    """Two seeds at a sweep's point, as Ray Tune trials on a local Ray and one after the other here: the same models
    weight for weight, in the same places, with the point's settings; the seeds' models differ; the leaderboard
    ranks the trials' models as the user's. (A sweep's grid is :func:`read_sweep`'s, tested below.)"""
    pytest.importorskip("ray.tune")
    from paragym.baselines.leaderboard import EvalSuite, run_leaderboard

    sweep = tmp_path / "sweep.yml"
    sweep.write_text("n_steps: [32]\nbatch_size: [16]\n")
    args = ["train", ORTHO, *TINY, "--seeds", "2", "--sweep", str(sweep)]
    assert main([*args, "--models", str(tmp_path / "here")]) == 0
    assert main([*args, "--models", str(tmp_path / "ray"), "--ray", "local"]) == 0
    out = capsys.readouterr().out
    assert "2 PPO runs on paragym/Orthoglide2PRRKappa-v0, as Ray Tune trials on local" in out
    models = sorted(p.relative_to(tmp_path / "here") for p in (tmp_path / "here").rglob("*.zip"))
    assert [str(m) for m in models] == [f"n_steps=32,batch_size={b}/Orthoglide2PRRKappa-v0/ppo_seed{s}.zip"
                                        for b in (16,) for s in (0, 1)]
    for m in models:
        assert _same(_weights(tmp_path / "here" / m), _weights(tmp_path / "ray" / m)), m
        meta = json.loads((tmp_path / "ray" / m).with_suffix(".json").read_text())
        assert meta["hyperparams"]["batch_size"] == int(m.parts[0].rsplit("=", 1)[1])
        assert (tmp_path / "ray" / m).with_suffix(".png").stat().st_size > 0
    assert not _same(_weights(tmp_path / "ray" / models[0]), _weights(tmp_path / "ray" / models[1]))  # the seeds
    point = tmp_path / "ray" / "n_steps=32,batch_size=16"
    run = run_leaderboard(db=tmp_path / "lb.sqlite", suite=EvalSuite("test", (0,), 1), env_ids=[ORTHO],
                          policies=["user-ppo-seed0", "user-ppo-seed1"], models_dir=point, out=None, validate=False,
                          progress=False, echo=lambda s: None)
    assert {s.policy for s in run.summaries[ORTHO]} == {"user-ppo-seed0", "user-ppo-seed1"}


def test_runs_trained_before_are_skipped_and_other_timesteps_refused(tmp_path, capsys):
    args = ["train", ORTHO, *TINY, "--seeds", "2", "--models", str(tmp_path)]
    assert main(args) == 0
    first = (tmp_path / "Orthoglide2PRRKappa-v0" / "ppo_seed1.zip").read_bytes()
    assert main(args) == 0
    assert "0 trained, 2 trained before" in capsys.readouterr().out
    assert main([*args[:5], "128", *args[6:]]) == 2  # other timesteps: refused, nothing written over
    assert "already trained (64 steps)" in capsys.readouterr().err
    assert (tmp_path / "Orthoglide2PRRKappa-v0" / "ppo_seed1.zip").read_bytes() == first


@pytest.mark.parametrize("text, match", [
    ("- 1\n- 2\n", "a mapping of hyper-parameter names"),
    ("learning_rate: 0.001\n", "must list its values"),
    ("learning_rate: []\n", "must list its values"),
    ("policy_kwargs: [{net_arch: [8]}]\n", "finite numbers, strings or booleans"),
    ("learning_rate: [.nan]\n", "finite numbers"),
    ("gamma/x: [0.9]\n", "not a hyper-parameter name"),
    ("policy: [a/b]\n", "cannot name a folder"),
    ("a: [1\n", "cannot read it as YAML"),
])
def test_a_bad_sweep_file_is_refused_naming_it(tmp_path, text, match):
    path = tmp_path / "s.yml"
    path.write_text(text)
    with pytest.raises(ValueError, match=match) as err:
        read_sweep(path)
    assert str(path) in str(err.value)


def test_a_sweep_is_its_grid_and_bad_requests_are_refused(tmp_path):
    path = tmp_path / "s.yml"
    path.write_text("learning_rate: [0.001, 0.0003]\nn_epochs: [5, 10, 20]\n")
    points = read_sweep(path)
    assert [name for name, _ in points][:2] == ["learning_rate=0.001,n_epochs=5", "learning_rate=0.001,n_epochs=10"]
    assert len(points) == 6 and points[-1][1] == {"learning_rate": 0.0003, "n_epochs": 20}
    runs = plan_runs(3, 2, tmp_path, points)
    assert [(r.seed, r.models_dir.name) for r in runs[:3]] == [(3, points[0][0]), (4, points[0][0]),
                                                                 (3, points[1][0])]
    with pytest.raises(ValueError, match="--seeds must be a positive integer"):
        plan_runs(0, 0, tmp_path)
    with pytest.raises(ValueError, match="train ppo, sac, td3, tqc; got 'bc'"):
        run_all(ORTHO, "bc", plan_runs(0, 2, tmp_path))
    assert main(["train", ORTHO, "--ray-storage", str(tmp_path)]) == 2
    with pytest.raises(ValueError, match="PPO takes no hyper-parameter learnin_rate"):
        run_all(ORTHO, "ppo", plan_runs(0, 1, tmp_path, [("learnin_rate=0.1", {"learnin_rate": 0.1})]))
    assert not list(tmp_path.rglob("*.zip"))  # refused before any run


def test_the_dynamic_fidelity_trains_under_physics_in_its_own_folder(tmp_path):
    """PPO for one rollout under MuJoCo's dynamics: the training robots and the evaluation env's simulate the
    mechanism in MuJoCo alone (the native dynamic vector env, every robot stepped at once), the run goes under
    ``dynamic-mujoco/`` and says so, and a kinematic run of the same seed beside it is another model, not
    "already trained"."""
    pytest.importorskip("mujoco")
    from stable_baselines3.common.callbacks import BaseCallback

    from paragym.baselines.training import train
    from paragym.sim.mujoco_sim import MuJoCoSettings

    seen = []

    class Look(BaseCallback):
        def _on_training_start(self) -> None:
            params = self.training_env.get_attr("params")[0]
            seen.append((params.fidelity, params.engine, type(self.training_env.get_attr("world")[0]).__name__,
                         self.training_env.num_envs))

        def _on_step(self) -> bool:
            return True

    easy = "paragym/CaPaManCollisionFree-Easy-v0"
    res = train(easy, "ppo", seed=0, timesteps=32, models_dir=tmp_path, progress_bar=False, n_envs=2,
                hyperparams={"n_steps": 16, "batch_size": 16}, callbacks=[Look()], fidelity="dynamic",
                engine="mujoco")
    assert seen == [("dynamic", MuJoCoSettings(mirror=False), "MuJoCoWorld", 2)]  # MuJoCo's 1 ms step
    assert res.files.model == tmp_path / "dynamic-mujoco" / "CaPaManCollisionFree-Easy-v0" / "ppo_seed0.zip"
    assert (res.meta["fidelity"], res.meta["engine"]) == ("dynamic", "mujoco")
    kinematic = train(easy, "ppo", seed=0, timesteps=32, models_dir=tmp_path, progress_bar=False, n_envs=1,
                      hyperparams={"n_steps": 32, "batch_size": 16})
    assert not kinematic.skipped
    assert kinematic.files.model == tmp_path / "CaPaManCollisionFree-Easy-v0" / "ppo_seed0.zip"
    assert kinematic.meta["fidelity"] == "kinematic"
    from paragym.baselines.leaderboard import EvalSuite, run_leaderboard

    names = ["user-ppo-seed0", "user-dynamic-mujoco-ppo-seed0"]  # the leaderboard ranks both, apart
    run = run_leaderboard(db=tmp_path / "lb.sqlite", suite=EvalSuite("test", (0,), 1), env_ids=[easy], policies=names,
                          models_dir=tmp_path, out=None, validate=False, progress=False, echo=lambda s: None)
    assert {s.policy for s in run.summaries[easy]} == set(names)
    assert main(["train", easy, "--engine", "mujoco", "--models", str(tmp_path)]) == 2  # needs --fidelity dynamic
    assert main(["train", easy, "--algo", "cem", "--fidelity", "dynamic", "--models", str(tmp_path)]) == 2
