"""Native vector envs: the same numbers as the single envs, autoreset, bad input, SB3."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from env_ids import KINEMATIC_IDS

import paragym

NATIVE = sorted(paragym.VECTOR_ENTRY_POINTS)
# (env id, env kwargs, batch steps): long enough for every robot to finish at least two episodes
CASES = [
    ("paragym/CaPaManCollisionFree-v0", {"collision": "grid"}, 600),
    ("paragym/CaPaManCollisionFree-v0", {"collision": "grid", "scenario": "paper"}, 300),
    ("paragym/Orthoglide2PRRKappa-v0", {}, 2100),
    ("paragym/Orthoglide2PRRKappa-v0", {"action_mode": "joint_velocity"}, 2100),
    ("paragym/Orthoglide2PRRKappa-v0", {"scenario": "paper"}, 2100),
    ("paragym/HybridSingularityFree-v0", {}, 230),
    ("paragym/HybridSingularityFree-v0", {"scenario": "paper"}, 230),
    ("paragym/MobileTripodOdometry-v0", {}, 1300),
    ("paragym/MobileTripodOdometry-v0", {"scenario": "rough_terrain"}, 1300),
]


def _pair(env_id: str, n: int, **kwargs):
    native = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    sync = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **kwargs)
    return native, sync


def _side_by_side(one, other, steps: int, seed: int, actions_seed: int):
    """Reset both vector envs with ``seed`` and step them with the same random actions, checking that the
    observations (first the reset's), rewards, terminations and truncations agree to 1e-9; yields each step's
    pair of results."""
    np.testing.assert_allclose(one.reset(seed=seed)[0], other.reset(seed=seed)[0], rtol=0, atol=1e-9)
    rng = np.random.default_rng(actions_seed)
    for _ in range(steps):
        actions = rng.uniform(-1, 1, one.action_space.shape).astype(np.float32)
        a, b = one.step(actions), other.step(actions)
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_allclose(np.asarray(x, float), np.asarray(y, float), rtol=0, atol=1e-9)
        yield a, b


@pytest.mark.parametrize(("env_id", "kwargs", "steps"), CASES, ids=lambda v: str(v)[-40:])
def test_native_equals_single_over_full_episodes(env_id, kwargs, steps):
    n = 2 if "CaPaMan" in env_id else 3  # the single env's grid check is slow (the reference, not the product)
    native, sync = _pair(env_id, n, **kwargs)
    ended = 0
    for a, _ in _side_by_side(native, sync, steps, seed=11, actions_seed=3):
        ended += int(np.sum(a[2] | a[3]))
    assert ended >= (2 if "CaPaMan" in env_id else 6)  # autoresets on the way
    native.close()
    sync.close()


def test_autoreset_is_next_step():
    env = gym.make_vec("paragym/HybridSingularityFree-v0", num_envs=2, vectorization_mode="vector_entry_point")
    assert env.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
    env.reset(seed=0)
    zero = np.zeros(env.action_space.shape, np.float32)
    for _ in range(99):
        obs, reward, terminated, truncated, _ = env.step(zero)
        assert not (terminated.any() or truncated.any())
    obs, reward, terminated, truncated, _ = env.step(zero)  # the 100th step
    assert terminated.all() and truncated.all()  # u reaches 1 at the time limit
    wild = np.ones(env.action_space.shape, np.float32)  # ignored: this step resets
    obs, reward, terminated, truncated, _ = env.step(wild)
    assert np.all(reward == 0) and not terminated.any() and not truncated.any()
    assert np.allclose(obs[:, 0], 0.0) and np.allclose(obs[:, 13], 0.5)  # u = 0, Delta = 0.5 again
    obs, *_ = env.step(zero)
    assert np.allclose(obs[:, 0], 0.01)


def test_the_same_step_view_equals_gymnasiums_same_step_sync_env(env_id="paragym/HybridSingularityFree-v2",
                                                                   steps=230):
    """:class:`SameStepVectorEnv` (what SB3's adapter and TorchRL step) against gymnasium's own ``SyncVectorEnv`` in
    ``SAME_STEP`` mode over single envs: the observations, rewards, ends, last observations and infos."""
    from paragym.envs.vector import SameStepVectorEnv

    same = SameStepVectorEnv(gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point"))
    sync = gym.make_vec(env_id, num_envs=3, vectorization_mode="sync",
                        vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode.SAME_STEP})
    assert same.metadata["autoreset_mode"] == sync.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    ended = 0
    for a, b in _side_by_side(same, sync, steps, seed=5, actions_seed=2):
        done = a[2] | a[3]
        assert ("final_obs" in a[4]) == ("final_obs" in b[4]) == bool(done.any())
        if done.any():
            np.testing.assert_array_equal(a[4]["_final_obs"], b[4]["_final_obs"])
            for i in np.flatnonzero(done):
                np.testing.assert_allclose(a[4]["final_obs"][i], b[4]["final_obs"][i], rtol=0, atol=1e-9)
                assert bool(a[4]["final_info"]["is_success"][i]) == bool(b[4]["final_info"]["is_success"][i])
            ended += int(done.sum())
        assert bool(a[4]["is_success"].any()) == bool(b[4]["is_success"].any())  # reset robots: their reset info
    assert ended >= 3
    same.close()
    sync.close()


@pytest.mark.parametrize("env_id", KINEMATIC_IDS)  # one id per kinematic fidelity (tests/env_ids.py)
def test_make_vec_works_for_every_id(env_id):
    for mode in ("sync", "async"):
        env = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode)
        obs, _ = env.reset(seed=0)
        obs, reward, *_ = env.step(np.zeros(env.action_space.shape, np.float32))
        assert obs.shape == (2, *env.single_observation_space.shape) and reward.shape == (2,)
        env.close()
    env = gym.make_vec(env_id, num_envs=5, vectorization_mode="vector_entry_point")
    obs, _ = env.reset(seed=0)
    assert obs.shape == (5, *env.single_observation_space.shape) and obs.dtype == np.float32
    assert env.observation_space.contains(obs)
    assert type(gym.make_vec(env_id, num_envs=2)).__name__.endswith("VectorEnv")  # the native one by default


@pytest.mark.parametrize("env_id", NATIVE)
def test_bad_batches_are_refused_naming_the_row(env_id):
    env = gym.make_vec(env_id, num_envs=4, vectorization_mode="vector_entry_point")
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(env.action_space.shape, np.float32))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((3, *env.single_action_space.shape), np.float32))
    actions = np.zeros(env.action_space.shape, np.float32)
    actions[2, 0] = np.nan
    with pytest.raises(ValueError, match="row 2"):
        env.step(actions)
    with pytest.raises(ValueError, match="num_envs"):
        gym.make_vec(env_id, num_envs=0, vectorization_mode="vector_entry_point")


def test_render_draws_the_chosen_robot():
    env = gym.make_vec("paragym/HybridSingularityFree-v0", num_envs=3, vectorization_mode="vector_entry_point",
                       render_mode="rgb_array", render_index=2)
    env.reset(seed=0)
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.std() > 0
    env.close()


def test_sb3_trains_on_a_native_vector_env(tmp_path):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    from paragym.baselines import as_sb3_vecenv  # the name the docs give
    from paragym.baselines.training import train

    venv = as_sb3_vecenv("paragym/HybridSingularityFree-v0", num_envs=4)
    venv.seed(0)
    obs = venv.reset()
    zero = np.zeros((4, 4), np.float32)
    for _ in range(100):
        obs, rewards, dones, infos = venv.step(zero)
    assert dones.all() and all("terminal_observation" in i for i in infos)
    assert np.allclose(obs[:, 0], 0.0) and np.allclose([i["terminal_observation"][0] for i in infos], 1.0)
    model = PPO("MlpPolicy", VecMonitor(venv), n_steps=32, batch_size=64, device="cpu", seed=0)
    model.learn(256)
    assert model.num_timesteps >= 256
    res = train("HybridSingularityFree-v0", "ppo", seed=0, timesteps=512, models_dir=tmp_path, progress_bar=False,
                vectorized=True, n_envs=8, hyperparams={"n_steps": 32, "batch_size": 64, "eval_freq": 256,
                                                        "n_eval_episodes": 1})
    assert res.meta["vectorized"] and res.files.model.is_file()
    with pytest.raises(ValueError, match="grid"):
        gym.make_vec("paragym/CaPaManCollisionFree-v0", num_envs=2, vectorization_mode="vector_entry_point",
                     collision="pybullet")


def test_the_grid_and_pybullet_disagree_by_at_most_two_cells():
    """CaPaMan: paper 000's grid (5 mm cells, cluster points 10 mm apart), which
    the native vector env uses, against PyBullet's exact signed distance, on
    configurations drawn uniformly and near the task points of random scenes."""
    from paragym.mechanisms import capaman
    from paragym.sim import capaman_clearance
    from paragym.tasks.capaman_worlds import _clusters

    env = gym.make("paragym/CaPaManCollisionFree-v0")
    scene, clusters = env.unwrapped.scene, _clusters(capaman.DEFAULT_GEOMETRY)
    rng = np.random.default_rng(1)
    grid, exact = [], []
    for seed in range(3):
        _, info = env.reset(seed=seed)
        sc = info["scenario"]
        grids = capaman_clearance.DistanceGrids(1)
        grids.set(0, sc.obstacles)
        alpha = np.concatenate([rng.uniform(np.pi / 4, 3 * np.pi / 4, (100, 3)),
                                sc.alpha[rng.integers(3, size=100)] + rng.normal(0, 0.15, (100, 3))])
        alpha = np.clip(alpha, np.pi / 4, 3 * np.pi / 4)
        for a in alpha:
            grid.append(capaman_clearance.grid_clearance(a[None], grids, clusters)[0][0])
            scene.set_configuration(a)
            exact.append(scene.clearance()[0])
    grid, exact = np.array(grid), np.array(exact)
    near = np.abs(exact) < 0.05
    assert near.sum() > 300 and (exact <= 0).sum() > 50
    assert np.abs(grid - exact)[near].max() <= 0.010  # two cells
    assert exact[grid <= 0].max() < 0.008  # a grid collision is within 1.6 cells of a real one
    assert np.all(grid[exact < -0.010] <= 0)  # a penetration deeper than the cluster spacing is never missed
    env.close()


def test_the_sb3_adapter_reports_success_at_an_episode_end():
    """SB3's EvalCallback reads info["is_success"] of a finished episode: the
    adapter passes the native env's on (the training curves' success rate).
    Odometry alone ends within 5 cm after the push (success) and 20 cm off
    after the initial heading error (failure)."""
    from paragym.baselines.sb3_vec import as_sb3_vecenv

    for scenario, want in (("push", [True, True]), ("initial_heading", [False, False])):
        venv = as_sb3_vecenv("paragym/MobileTripodOdometry-v1", 2, scenario=scenario)
        venv.reset()
        for _ in range(700):
            _, _, dones, infos = venv.step(np.zeros((2, 3), np.float32))
            if dones.any():
                break
        assert dones.all() and [i.get("is_success") for i in infos] == want, scenario


def test_a_native_vector_env_builds_no_pybullet_scene_until_it_needs_one():
    """The vector env builds no single env: it checks its arguments as the single env does (the task's
    ``Params.from_kwargs``), which builds no PyBullet scene in the kinematic fidelity; the CaPaMan's own checker
    scene comes at the first reset, and draws as the single env draws."""
    import warnings

    from paragym import registry

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for task in sorted({r.task for r in registry.ROWS}):
            venv = gym.make_vec(registry.rows_of(task)[-1].id, num_envs=2, vectorization_mode="vector_entry_point",
                                render_mode="rgb_array").unwrapped
            assert not hasattr(venv, "single_env"), task
            assert getattr(venv.world, "scene", None) is None and not venv._render, task
            venv.close()
        venv = gym.make_vec("paragym/CaPaManCollisionFree-v1", num_envs=2, vectorization_mode="vector_entry_point",
                            render_mode="rgb_array")
        venv.reset(seed=4)
        single = gym.make("paragym/CaPaManCollisionFree-v1", collision="grid", render_mode="rgb_array")
        single.reset(seed=4)
        np.testing.assert_array_equal(venv.render(), single.render())
        venv.close()
        single.close()
