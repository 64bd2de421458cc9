"""Models: shipped ones are read-only package data, loading runs no code, rows name their producer
(issue 15, items 2-4)."""

from __future__ import annotations

import base64
import contextlib
import json
import subprocess
import sys
import zipfile

import cloudpickle
import pytest

pytest.importorskip("stable_baselines3")

from paragym.baselines.leaderboard import EvalSuite, evaluate_episode, run_leaderboard  # noqa: E402
from paragym.baselines.policies import policies_for, shipped_models_dir  # noqa: E402
from paragym.baselines.store import ResultStore  # noqa: E402
from paragym.baselines.training import load_model, train  # noqa: E402
from paragym.cli import main  # noqa: E402

HYBRID = "paragym/HybridSingularityFree-v0"
TINY = {"n_envs": 2, "n_steps": 64, "batch_size": 64, "n_epochs": 1, "eval_freq": 10_000, "n_eval_episodes": 1}


class _Touch:
    """A payload: unpickling it creates a file."""

    def __init__(self, path: str) -> None:
        self.path = path

    def __reduce__(self):
        return (open, (self.path, "w"))


def _poisoned(src, dst, marker) -> None:
    """A copy of the model ``src`` whose data carries cloudpickle payloads that create ``marker``."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            payload = zin.read(item.filename)
            if item.filename == "data":
                data = json.loads(payload)
                evil = base64.b64encode(cloudpickle.dumps(_Touch(str(marker)))).decode()
                data["observation_space"][":serialized:"] = evil  # the readable fields stay as they were
                data["lr_schedule"][":serialized:"] = evil
                data["extra"] = {":type:": "<class 'object'>", ":serialized:": evil}
                payload = json.dumps(data).encode()
            zout.writestr(item, payload)


def test_loading_a_model_runs_no_code_embedded_in_it(tmp_path):
    from stable_baselines3 import PPO

    shipped = shipped_models_dir() / "HybridSingularityFree-v0" / "ppo_seed0.zip"
    folder = tmp_path / "mine" / "HybridSingularityFree-v0"
    folder.mkdir(parents=True)
    evil, marker = folder / "ppo_seed0.zip", tmp_path / "ran"
    _poisoned(shipped, evil, marker)
    with contextlib.suppress(Exception):
        PPO.load(evil, device="cpu")  # SB3's own load runs the payload: the test's payload is real
    assert marker.exists()
    marker.unlink()

    model = load_model(evil)
    assert not marker.exists()
    reference = load_model(shipped)
    obs = reference.observation_space.sample()
    assert (model.predict(obs, deterministic=True)[0] == reference.predict(obs, deterministic=True)[0]).all()
    spec = policies_for(HYBRID, tmp_path / "mine")["user-ppo-seed0"]  # and the leaderboard's path to it
    row = evaluate_episode(spec, 0, 0)
    assert not marker.exists() and row.length > 0


def test_every_shipped_model_loads_without_unpickling_and_acts_as_sb3_does():
    import numpy as np
    from stable_baselines3 import PPO, SAC

    files = sorted(shipped_models_dir().glob("*/*_seed*.zip"))
    # v0: PPO and SAC x 3 seeds; CaPaMan v1: bc, PPO, SAC, DAgger x 3; tripod v1: bc, PPO, SAC x 3; hybrid v1: PPO, SAC;
    # the twelve rungs of the ladders v0: bc and SAC seed 0, and PPO seed 0 on ten (not the tripod's nor the
    # CaPaMan's medium rung); the hybrid's ladder v1: PPO and SAC seed 0 on each rung
    assert len(files) == 24 + 12 + 9 + 6 + 12 + 12 + 10 + 6
    from paragym import registry

    first = [r.name for r in registry.rows() if r.rung is not None and r.version == 0]
    assert all((shipped_models_dir() / name / f"{algo}_seed0.zip").is_file()
               for name in first for algo in ("bc", "sac"))
    assert all((shipped_models_dir() / r.name / f"{algo}_seed0.zip").is_file()
               for r in registry.ladders("hybrid")[1] for algo in ("ppo", "sac"))
    for path in files[::4]:
        ours = load_model(path)
        theirs = (SAC if path.stem.startswith("sac") else PPO).load(path, device="cpu")  # a clone is a PPO policy
        obs = np.random.default_rng(0).uniform(-1, 1, (20, *theirs.observation_space.shape)).astype(np.float32)
        assert ours.observation_space == theirs.observation_space and ours.action_space == theirs.action_space
        np.testing.assert_array_equal(ours.predict(obs, deterministic=True)[0],
                                      theirs.predict(obs, deterministic=True)[0])


@pytest.mark.slow
def test_the_shipped_models_are_found_by_name_from_any_directory_and_a_local_models_folder_changes_nothing(tmp_path):
    (tmp_path / "models" / "HybridSingularityFree-v0").mkdir(parents=True)
    (tmp_path / "models" / "HybridSingularityFree-v0" / "ppo_seed0.zip").write_bytes(b"not this one")
    code = ("from paragym.baselines.policies import policies_for, shipped_models_dir\n"
            "from paragym.baselines.training import load_model\n"
            "specs = policies_for('HybridSingularityFree-v0')\n"
            "print(sorted(n for n, s in specs.items() if s.kind == 'learned'))\n"
            "print(specs['ppo-seed0'].factory.path)\n"
            "load_model(shipped_models_dir() / 'HybridSingularityFree-v0' / 'ppo_seed0.zip')\n")
    res = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    names, path = res.stdout.splitlines()[:2]
    assert names == str(sorted(f"{a}-seed{k}" for a in ("ppo", "sac") for k in range(3)))
    assert not path.startswith(str(tmp_path)) and path.startswith(str(shipped_models_dir()))


def test_training_never_writes_over_the_shipped_or_a_finished_model(tmp_path, monkeypatch, capsys):
    before = {p: p.read_bytes() for p in shipped_models_dir().glob("HybridSingularityFree-v0/*")}
    with pytest.raises(ValueError, match="read-only"):
        train(HYBRID, "ppo", timesteps=128, models_dir=shipped_models_dir(), progress_bar=False, hyperparams=TINY)
    monkeypatch.chdir(tmp_path)
    assert main(["train", HYBRID, "--timesteps", "128", "--no-progress"]) == 0  # the CLI's default folder
    assert (tmp_path / "runs" / "models" / "HybridSingularityFree-v0" / "ppo_seed0.zip").is_file()
    with pytest.raises(ValueError, match="already trained"):
        train(HYBRID, "ppo", timesteps=256, progress_bar=False, hyperparams=TINY)
    assert main(["train", HYBRID, "--timesteps", "256", "--no-progress"]) == 2
    assert "--force" in capsys.readouterr().err
    assert {p: p.read_bytes() for p in shipped_models_dir().glob("HybridSingularityFree-v0/*")} == before


def test_a_retrained_model_gets_its_episodes_run_again_never_mixed(tmp_path):
    models = tmp_path / "models"
    train(HYBRID, "ppo", seed=0, timesteps=128, models_dir=models, progress_bar=False, hyperparams=TINY)
    said: list[str] = []
    kw = dict(db=tmp_path / "r.sqlite", suite=EvalSuite("test", (0,), 3), env_ids=[HYBRID],
              policies=["user-ppo-seed0"], models_dir=models, out=None, validate=False, progress=False,
              echo=said.append)
    first = run_leaderboard(**kw)
    assert first.new_episodes == 3
    with ResultStore(tmp_path / "r.sqlite") as store:
        old = {r.producer for r in store.rows()}
    assert len(old) == 1 and "model_sha256" in next(iter(old))

    train(HYBRID, "ppo", seed=0, timesteps=256, models_dir=models, progress_bar=False, hyperparams=TINY, force=True)
    said.clear()
    second = run_leaderboard(**kw)
    assert second.new_episodes == 3 and second.skipped_episodes == 0
    assert any("another producer" in line and "re-running 3" in line for line in said)
    summary = second.summaries[HYBRID][0]
    assert summary.episodes == 3 and summary.producer not in old
    with ResultStore(tmp_path / "r.sqlite") as store:
        assert len({r.producer for r in store.rows()}) == 2  # the old rows stay, apart
    assert run_leaderboard(**kw).new_episodes == 0


def test_a_changed_planner_parameter_is_a_new_producer():
    from dataclasses import replace

    from paragym.planners.rrt_ga import RrtGaSettings

    spec = policies_for("paragym/CaPaManCollisionFree-v0")["rrt-ga"]
    assert "generations" in spec.producer()
    changed = replace(spec, params=lambda: {"planner": {"settings": {**RrtGaSettings().__dict__, "generations": 5}}})
    assert changed.producer() != spec.producer()


def test_a_models_folder_that_does_not_exist_is_an_error(tmp_path, capsys):
    with pytest.raises(ValueError, match="does not exist"):
        policies_for(HYBRID, tmp_path / "nope")
    assert main(["leaderboard", "--quick", "--db", str(tmp_path / "a.sqlite"), "--models", str(tmp_path / "nope"),
                 "--no-progress", "--out", str(tmp_path / "out")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert not (tmp_path / "a.sqlite").exists()




def test_a_shipped_model_is_described_by_its_path_in_the_package():
    """Descriptions end up in committed tables: a shipped model is named ``models/<env>/<file>``, the same on
    every machine, never by this machine's absolute path."""
    from paragym import registry

    for row in registry.ROWS:
        for spec in policies_for(row.id).values():
            if spec.kind == "learned":
                path = spec.description.rsplit(": ", 1)[1]
                assert path.startswith("models/") and not path.startswith("/"), spec.description


# a Python that cannot import PyTorch or Stable-Baselines3 (the main job's install has neither)
_WITHOUT_TORCH = """
import sys

class _Refuse:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("torch", "stable_baselines3", "sb3_contrib"):
            raise ImportError(f"no {name} here")

sys.meta_path.insert(0, _Refuse())
"""


def test_the_leaderboard_plays_the_shipped_models_without_pytorch_as_sb3_would():
    """The leaderboard's learned policies read their actor from the model file (weights as tensors only, no
    PyTorch): the main job needs no deep-learning install, and every action is SB3's to float32 rounding."""
    import numpy as np

    from paragym.baselines.actor import actor_from_file
    from paragym.baselines.leaderboard.suite import episode_seed
    from paragym.baselines.policies import LearnedPolicy
    from paragym.rollout import run_episode

    code = _WITHOUT_TORCH + (
        "from paragym.baselines.leaderboard import evaluate_episode\n"
        "from paragym.baselines.policies import policies_for\n"
        f"for name in ('ppo-seed0', 'sac-seed1'):\n"
        f"    print(repr(evaluate_episode(policies_for({HYBRID!r})[name], 0, 0).episode_return))\n"
        "print('torch' in sys.modules, 'stable_baselines3' in sys.modules)\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    *returns, imported = res.stdout.split("\n")[-4:-1]
    assert imported == "False False"
    import gymnasium as gym

    env = gym.make(HYBRID)
    for name, got in zip(("ppo", "sac"), returns, strict=True):  # the same episodes through SB3's model
        path = shipped_models_dir() / "HybridSingularityFree-v0" / f"{name}_seed{0 if name == 'ppo' else 1}.zip"
        ep = run_episode(env, LearnedPolicy(load_model(path)), seed=episode_seed(0, 0))
        assert float(got) == ep.episode_return
    for path in sorted(shipped_models_dir().glob("*/*_seed*.zip"))[1::4]:
        actor, observation = actor_from_file(path)
        model = load_model(path)
        obs = np.random.default_rng(0).uniform(-1, 1, (20, *observation.shape)).astype(np.float32)
        assert observation == model.observation_space
        assert np.abs(np.array([actor.act(o) for o in obs]) - model.predict(obs, deterministic=True)[0]).max() < 1e-5


def test_weights_that_name_anything_but_tensors_are_refused_unrun(tmp_path):
    """A model's policy.pth is a pickle too: the torch-free reader builds tensors and nothing else."""
    import io
    import pickle

    from paragym.baselines.actor import actor_from_file

    shipped = shipped_models_dir() / "HybridSingularityFree-v0" / "ppo_seed0.zip"
    folder = tmp_path / "mine" / "HybridSingularityFree-v0"
    folder.mkdir(parents=True)
    evil, marker = folder / "ppo_seed0.zip", tmp_path / "ran"
    with zipfile.ZipFile(shipped) as zin, zipfile.ZipFile(evil, "w") as zout:
        for item in zin.infolist():
            payload = zin.read(item.filename)
            if item.filename == "policy.pth":
                buffer = io.BytesIO()
                with zipfile.ZipFile(io.BytesIO(payload)) as inner, zipfile.ZipFile(buffer, "w") as out:
                    for entry in inner.infolist():
                        body = inner.read(entry.filename)
                        if entry.filename.endswith("/data.pkl"):
                            body = pickle.dumps({"action_net.weight": _Touch(str(marker))}, protocol=2)
                        out.writestr(entry, body)
                payload = buffer.getvalue()
            zout.writestr(item, payload)
    with pytest.raises(ValueError, match="not a tensor"):
        actor_from_file(evil)
    spec = policies_for(HYBRID, tmp_path / "mine")["user-ppo-seed0"]
    with pytest.raises(ValueError, match="not a tensor"):
        evaluate_episode(spec, 0, 0)
    assert not marker.exists()
