"""Bad input is refused at reset, naming the argument, and leaves the env as it was (issue 15, items 8-9)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from env_ids import KINEMATIC_IDS, STEP_IDS

from paragym import registry
from paragym.sim.tripod_drive import Terrain
from paragym.tasks.hybrid import HybridScenario
from paragym.tasks.orthoglide import OrthoglideScenario
from paragym.tasks.tripod import TripodScenario

IDS = KINEMATIC_IDS  # one id per kinematic fidelity (tests/env_ids.py)
HYBRID, ORTHO, TRIPOD = ("paragym/HybridSingularityFree-v0", "paragym/Orthoglide2PRRKappa-v0",
                         "paragym/MobileTripodOdometry-v0")


def _vec(env_id, n=4):
    return gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point")


@pytest.mark.parametrize("env_id", IDS)
def test_a_failed_reset_changes_nothing(env_id):
    venv = _vec(env_id)
    venv.reset(seed=3)
    state = [rng.bit_generator.state for rng in venv.unwrapped._rngs]
    with pytest.raises(ValueError, match=r"seed\[3\]"):
        venv.reset(seed=[0, 1, 2, -1])
    assert [rng.bit_generator.state for rng in venv.unwrapped._rngs] == state
    with pytest.raises(TypeError, match="seed"):
        venv.reset(seed="7")
    venv.close()


@pytest.mark.parametrize("env_id", STEP_IDS)
def test_reset_mask_resets_only_the_masked_robots(env_id):
    venv = _vec(env_id)
    obs, _ = venv.reset(seed=0)
    actions = np.zeros(venv.action_space.shape, np.float32)
    for _ in range(3):
        obs, *_ = venv.step(actions)
    mask = np.array([True, False, True, False])
    again, _ = venv.reset(seed=[10, None, 12, None], options={"reset_mask": mask})
    fresh = _vec(env_id)
    ref, _ = fresh.reset(seed=[10, 1, 12, 3])
    np.testing.assert_array_equal(again[mask], ref[mask])
    np.testing.assert_array_equal(again[~mask], obs[~mask])  # untouched robots keep their state
    with pytest.raises(TypeError, match="reset_mask"):
        venv.reset(options={"reset_mask": [True, False, True, False]})
    with pytest.raises(ValueError, match="reset_mask"):
        venv.reset(options={"reset_mask": np.zeros(4, bool)})
    venv.close()
    fresh.close()


@pytest.mark.parametrize("env_id", STEP_IDS)
@pytest.mark.parametrize("options", [[("scenario", "paper")], "paper", 5])
def test_options_must_be_a_dict(env_id, options):
    env = gym.make(env_id, disable_env_checker=True)
    with pytest.raises(TypeError, match="options"):
        env.reset(seed=0, options=options)
    env.close()
    venv = _vec(env_id, 2)
    with pytest.raises(TypeError, match="options"):
        venv.reset(seed=0, options=options)
    venv.close()


_NAN_HYBRID = HybridScenario("nan", (0.0,) * 6, (np.nan, 0, 0, 0, 0, 0))
_HIGH_HYBRID = HybridScenario("high", (0, 0, 0.3, 0, 0, 0), (0, 0, 0.3, 0, 0, 0))  # refused by the single env
BAD = {
    HYBRID: [None, 5, "moon", _NAN_HYBRID, _HIGH_HYBRID, HybridScenario("short", (0.0,) * 5, (0.0,) * 6)],
    ORTHO: [None, 5, "moon", OrthoglideScenario("nan", np.linspace(0, 1, 5), np.full((5, 2), np.nan), np.zeros((5, 2))),
            OrthoglideScenario("far", np.linspace(0, 1, 5), np.full((5, 2), 9.0), np.zeros((5, 2))),
            OrthoglideScenario("back", np.array([0.0, 1.0, 0.5]), np.full((3, 2), 0.5), np.zeros((3, 2)))],
    TRIPOD: [None, 5, "moon", TripodScenario("stop", speed=0.0), TripodScenario("nan", heading=np.nan),
             TripodScenario("unit 5", push=(5, 3.0, 0.02)), TripodScenario("late", push=(0, 1e6, 0.02)),
             TripodScenario("two", heading_error=(0.1, 0.2)), TripodScenario("slip", slip=-1.0),
             TripodScenario("flat", terrain=Terrain(((0.0, 0.0, 0.1, 0.0),))),
             TripodScenario("text", speed="fast"), TripodScenario("endless", speed=1e-9)],
    "paragym/CaPaManCollisionFree-v0": [None, 5, "moon"],
}
BAD.update({r.id: BAD[registry.first_version(r.id)] for r in registry.ROWS})  # later versions: the first's scenarios


@pytest.mark.parametrize("env_id", IDS)
def test_bad_scenarios_are_refused_at_reset_by_single_and_vector_env_alike(env_id):
    env = gym.make(env_id, disable_env_checker=True)
    venv = _vec(env_id, 2)
    venv.reset(seed=0)
    for bad in BAD[env_id]:
        with pytest.raises((ValueError, TypeError), match="scenario") as single:
            env.reset(seed=0, options={"scenario": bad})
        with pytest.raises(type(single.value), match="scenario"):
            venv.reset(seed=0, options={"scenario": bad})
    venv.close()
    env.close()


def test_a_good_custom_drive_runs_to_its_end_with_finite_numbers():
    env = gym.make(TRIPOD, scenario=TripodScenario("mine", speed=1.0, distance=5.0, push=(2, 2.0, 0.02),
                                                  heading_error=(0.0, 0.01, 0.0)))
    obs, _ = env.reset(seed=0)
    done = False
    while not done:
        obs, r, te, tr, _ = env.step(np.zeros(6, np.float32))
        assert np.isfinite(obs).all() and np.isfinite(r)
        done = te or tr
    env.close()
