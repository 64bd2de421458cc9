"""The dynamic fidelity in MuJoCo alone: the native dynamic vector env, its N = 1 case the single env, and no
PyBullet on the way."""

from __future__ import annotations

import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("mujoco")

from paragym.sim.mujoco_sim import MuJoCoSettings  # noqa: E402 (MuJoCo is there)

EASY = "paragym/CaPaManCollisionFree-Easy-v0"
DYNAMIC = {"fidelity": "dynamic", "engine": "mujoco"}
ALONE = {"fidelity": "dynamic", "engine": MuJoCoSettings(mirror=False)}


def _make_vec(env_id: str, n: int, mode: str, **kwargs):
    """The native vector env takes engine='mujoco' (MuJoCo alone, as it runs); its single envs are MuJoCo alone."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gym.make_vec(env_id, num_envs=n, vectorization_mode=mode,
                            **(DYNAMIC if mode == "vector_entry_point" else ALONE), **kwargs)


@pytest.mark.parametrize(("env_id", "kwargs", "steps"), [(EASY, {}, 110), ("paragym/CaPaManCollisionFree-v1", {}, 110),
                                                         ("paragym/HybridSingularityFree-Easy-v2", {}, 150),
                                                         ("paragym/Orthoglide2PRRKappa-v1", {}, 120)])
@pytest.mark.slow
def test_the_native_dynamic_vector_env_equals_single_mujoco_envs_to_the_bit(env_id, kwargs, steps):
    """N robots stepped together in MuJoCo's rollout on threads give, bit for bit, what N single envs give, one
    robot each, over episodes that end and restart (autoresets)."""
    native, sync = _make_vec(env_id, 2, "vector_entry_point"), _make_vec(env_id, 2, "sync", **kwargs)
    assert native.unwrapped.params == sync.envs[0].unwrapped.params  # one task, MuJoCo alone
    try:
        assert native.unwrapped.world._pool is not None or len(__import__("os").sched_getaffinity(0)) == 1
        obs, _ = native.reset(seed=7)
        np.testing.assert_array_equal(obs, sync.reset(seed=7)[0])
        rng, ended = np.random.default_rng(2), 0
        for k in range(steps):
            if k % 15 == 0:  # held for 15 steps: the robots travel, and some hit a post
                actions = rng.choice([-1.0, 1.0], native.action_space.shape).astype(np.float32)
            got, want = native.step(actions), sync.step(actions)
            for x, y in zip(got[:4], want[:4], strict=True):
                np.testing.assert_array_equal(x, y)
            for key, value in got[4].items():  # every number the native env reports, the single envs' too
                if not key.startswith("_"):
                    assert list(value) == list(want[4][key]), key
            ended += int(np.sum(got[2] | got[3]))
        assert ended >= 2  # autoresets on the way
    finally:
        native.close()
        sync.close()


def test_a_robot_watched_step_by_step_moves_as_one_stepped_in_the_batch():
    """A robot with a per-step observer (as KF validation records) leaves the batch and steps alone, MuJoCo step by
    step from Python; its motion is the batch's to the bit (each control period starts the solver cold)."""
    venv = _make_vec(EASY, 2, "vector_entry_point")
    try:
        obs, _ = venv.reset(seed=[5, 5])  # the same scenario for both
        np.testing.assert_array_equal(obs[0], obs[1])
        watched, seen = venv.unwrapped.world.robots[0].sim, []
        watched.after_step.append(lambda: seen.append(1))
        for k in range(12):
            obs = venv.step(np.full((2, 3), 0.6 if k < 6 else -0.4, np.float32))[0]
            np.testing.assert_array_equal(obs[0], obs[1])
        robots = venv.unwrapped.world.robots
        np.testing.assert_array_equal(robots[0].sim.data.qpos, robots[1].sim.data.qpos)
        assert len(seen) == 12 * 20  # the watched robot stepped alone, every physics step seen
    finally:
        venv.close()


def test_the_mujoco_world_runs_with_pybullet_absent():
    """``import paragym`` and the MuJoCo worlds (the CaPaMan's single and vector, the hybrid's and the 2PRR's
    vector), with PyBullet not importable: any call into PyBullet on the way fails the run."""
    script = """
import sys
sys.modules["pybullet"] = None  # importing PyBullet raises ImportError
import warnings
import gymnasium as gym
import numpy as np
import paragym
warnings.simplefilter("ignore")
from paragym.sim.mujoco_sim import MuJoCoSettings
env = gym.make("paragym/CaPaManCollisionFree-Easy-v0", fidelity="dynamic", engine=MuJoCoSettings(mirror=False))
env.reset(seed=1)
ends = 0
for _ in range(60):
    ends += sum(env.step(env.action_space.sample())[2:4])
    if ends:
        env.reset()
venv = gym.make_vec("paragym/CaPaManCollisionFree-Easy-v0", num_envs=3, vectorization_mode="vector_entry_point",
                    fidelity="dynamic", engine="mujoco")
venv.reset(seed=2)
for _ in range(60):
    venv.step(venv.action_space.sample())
hybrid = gym.make_vec("paragym/HybridSingularityFree-Easy-v2", num_envs=2, vectorization_mode="vector_entry_point",
                      fidelity="dynamic", engine="mujoco")
hybrid.reset(seed=3)
for _ in range(30):
    hybrid.step(hybrid.action_space.sample())
orthoglide = gym.make_vec("paragym/Orthoglide2PRRKappa-v1", num_envs=2, vectorization_mode="vector_entry_point",
                          fidelity="dynamic", engine="mujoco")
orthoglide.reset(seed=4)
for _ in range(30):
    orthoglide.step(orthoglide.action_space.sample())
for made in (env, venv, hybrid, orthoglide):
    made.close()
assert "pybullet" not in sys.modules or sys.modules["pybullet"] is None
print("ran without PyBullet")
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "ran without PyBullet" in done.stdout


def test_a_described_scene_is_the_scene_built_in_pybullet():
    """The CaPaMan described as data exports the MJCF its PyBullet build exports, character for character, and
    moves as it does in MuJoCo."""
    from paragym.sim.capaman_dynamic import CaPaManDynamicScene

    built = CaPaManDynamicScene(engine=MuJoCoSettings())
    described = CaPaManDynamicScene(engine=MuJoCoSettings(mirror=False))
    try:
        assert described.sim.robot_mjcf == built.sim.robot_mjcf
        for scene in (built, described):
            scene.set_configuration(np.radians([80.0, 90, 100]))
            scene.drive(np.radians([85.0, 95, 100]), 0.02)
        np.testing.assert_allclose(described.tip, built.tip, rtol=0, atol=1e-12)
        np.testing.assert_allclose(described.alpha, built.alpha, rtol=0, atol=1e-12)
        assert described.render(32, 24).shape == (24, 32, 3)  # drawn in a PyBullet world built on demand
    finally:
        built.close()
        described.close()


def test_each_engine_takes_its_own_collision_test_and_says_so():
    """PyBullet's dynamic scene measures clearance with PyBullet; MuJoCo alone with the task's kernel; the native
    vector env runs MuJoCo alone; and the repr of the settings of 0.9's MuJoCo fidelity (a result row's record)
    stays what it was."""
    with pytest.raises(ValueError, match="engine='mujoco'"):
        gym.make_vec(EASY, num_envs=2, vectorization_mode="vector_entry_point", fidelity="dynamic")
    for engine, collision in (("pybullet", "posts"), ("mujoco", "posts"), (ALONE["engine"], "pybullet")):
        with pytest.raises(ValueError, match="collision="):
            gym.make(EASY, fidelity="dynamic", engine=engine, collision=collision)
    with pytest.raises(ValueError, match="mirror=False"):
        gym.make("paragym/MobileTripodOdometry-v0", fidelity="dynamic", engine=ALONE["engine"])
    assert repr(MuJoCoSettings()) == "MuJoCoSettings(time_step=0.001, servo_bandwidth=None, iterations=None)"
    assert repr(ALONE["engine"]).endswith(", mirror=False)")


def test_a_mujoco_world_is_not_copied():
    """Its robots' MuJoCo states and the threads that step them are its own: a copy is refused, as a PyBullet
    client's is."""
    import copy

    venv = _make_vec(EASY, 2, "vector_entry_point")
    try:
        with pytest.raises(TypeError, match="cannot be copied"):
            copy.deepcopy(venv)
    finally:
        venv.close()
