"""rl-baselines3-zoo as a client: the shipped hyper-parameter files load in
``rl_zoo3.train`` unchanged, and what it trains is a model paragym loads."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # every test here starts processes or runs a benchmark

# not imported here: importing rl_zoo3 replaces Gymnasium's TimeLimit process-wide (rl_zoo3.gym_patches),
# which would change how the released envs truncate for every later test of this process
if importlib.util.find_spec("rl_zoo3") is None:
    pytest.skip("rl_zoo3 is not installed (the zoo extra)", allow_module_level=True)

from paragym.baselines.policies import policies_for  # noqa: E402
from paragym.baselines.training import load_model  # noqa: E402

CASES = [  # (algo, env id, overrides that keep it to a few hundred steps)
    ("ppo", "paragym/Orthoglide2PRRKappa-v0", ["n_envs:2", "n_steps:64", "batch_size:64", "n_epochs:1"]),
    ("ppo", "paragym/CaPaManCollisionFree-v1", ["n_envs:2", "n_steps:64", "batch_size:64", "n_epochs:1"]),
    ("sac", "paragym/MobileTripodOdometry-v0", ["learning_starts:100", "batch_size:32"]),
    ("td3", "paragym/HybridSingularityFree-v0", ["learning_starts:100", "batch_size:32"]),
]


#: one Python process trains every case, ``rl_zoo3.train`` called once per case's command line: importing rl-zoo
#: and its dependencies takes seconds, paid once
_DRIVER = """
import json, sys
import rl_zoo3.train

for argv in json.loads(sys.argv[1]):
    sys.argv = ["rl_zoo3.train", *argv]
    rl_zoo3.train.train()
"""


@pytest.fixture(scope="module")
def zoo_runs(shared_folder) -> Path:
    """Every case trained by ``rl_zoo3.train`` from the shipped files, each in ``<folder>/<algo>-<env name>``
    (by one xdist worker; the others find the runs there)."""
    import json

    conf = {algo: str(resources.files("paragym.baselines").joinpath("hyperparams", f"{algo}.yml"))
            for algo, _, _ in CASES}
    with shared_folder("zoo") as folder:
        if not (folder / "done").is_file():
            commands = [["--algo", algo, "--env", env_id, "--gym-packages", "paragym", "-conf", conf[algo], "-n", "300",
                         "--eval-freq", "-1", "-f", str(folder / f"{algo}-{env_id.split('/')[1]}"), "--seed", "0",
                         "-params", *overrides] for algo, env_id, overrides in CASES]
            folder.mkdir(exist_ok=True)
            done = subprocess.run([sys.executable, "-c", _DRIVER, json.dumps(commands)], capture_output=True,
                                  text=True, timeout=600, cwd=folder)
            assert done.returncode == 0, done.stderr[-3000:]
            (folder / "done").write_text(done.stdout[-2000:])
        return folder


@pytest.mark.parametrize(("algo", "env_id", "overrides"), CASES, ids=[f"{a}-{e.split('/')[1]}" for a, e, _ in CASES])
def test_rl_zoo_trains_from_the_shipped_file(zoo_runs: Path, tmp_path: Path, algo: str, env_id: str,
                                             overrides: list[str]) -> None:
    logs = zoo_runs / f"{algo}-{env_id.split('/')[1]}"
    name = env_id.replace("/", "-")
    model = logs / algo / f"{name}_1" / f"{name}.zip"
    assert model.is_file(), (zoo_runs / "done").read_text()
    loaded = load_model(model)  # paragym reads what rl-zoo wrote, without unpickling and without algo=
    assert loaded.num_timesteps >= 300 and type(loaded).__name__.lower() == algo
    spec = policies_for(env_id, logs)[f"user-{algo}-zoo1"]  # --models takes rl-zoo's log folder
    assert spec.kind == "learned" and "rl-baselines3-zoo" in spec.description
    if env_id.endswith("Orthoglide2PRRKappa-v0"):  # and the leaderboard ranks it from the command line
        from paragym.cli import main

        assert main(["leaderboard", "--quick", "--env", env_id, "--models", str(logs), "--policy",
                     "user-ppo-zoo1", "--no-validation", "--no-progress", "--workers", "1", "--db",
                     str(tmp_path / "db.sqlite"), "--out", str(tmp_path / "out")]) == 0
        assert "user-ppo-zoo1" in next((tmp_path / "out").rglob("LEADERBOARD.md")).read_text()


def test_zoo_normalised_observations_are_refused(tmp_path: Path) -> None:
    name = "paragym-Orthoglide2PRRKappa-v0"
    run = tmp_path / "ppo" / f"{name}_3"
    (run / name).mkdir(parents=True)
    (run / f"{name}.zip").write_bytes(b"not read")
    (run / name / "config.yml").write_text("!!python/object/apply:collections.OrderedDict\n- - - normalize\n"
                                          "    - \"{'norm_obs': True, 'norm_reward': True}\"\n")
    with pytest.raises(ValueError, match="vecnormalize.pkl"):
        policies_for("paragym/Orthoglide2PRRKappa-v0", tmp_path)
