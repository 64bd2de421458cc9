"""Version 1 of the CaPaMan, tripod and hybrid envs (issue 17): what changed, and that it poses a task."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import paragym  # noqa: F401
from paragym.baselines.policies import get_policy
from paragym.mechanisms import capaman, hybrid
from paragym.sim.capaman_scene import CaPaManScene
from paragym.tasks.capaman_step import LOOKAHEAD
from paragym.units import DEG

TRIPOD, CAPAMAN = "paragym/MobileTripodOdometry-v1", "paragym/CaPaManCollisionFree-v1"
HYBRID = "paragym/HybridSingularityFree-v1"


def _run(env: gym.Env, act, seed: int, **reset) -> tuple[float, dict, list[dict]]:
    obs, info = env.reset(seed=seed, **reset)
    total, infos, done = 0.0, [info], False
    while not done:
        obs, reward, terminated, truncated, info = env.step(act(obs, info))
        total += reward
        infos.append(info)
        done = terminated or truncated
    return total, info, infos


# --- the tripod --------------------------------------------------------------------------------------------------

def test_tripod_v1_zero_and_negative_actions_are_odometry():
    """No trust, no correction: the estimate is the odometry at every sample,
    and an action never accumulates into it."""
    env = gym.make(TRIPOD)
    for action in (np.zeros(3, np.float32), -np.ones(3, np.float32)):
        _, _, infos = _run(env, lambda o, i, a=action: a, seed=3, options={"scenario": "push"})
        for info in infos:
            np.testing.assert_allclose(info["estimate"][:, :2], info["odometry"][:, :2], rtol=0, atol=1e-12)


def test_tripod_v1_trust_moves_a_unit_toward_the_circle_intersection():
    """Full trust in unit 0 moves it trust_rate (0.2) of the way to where the
    encoder distances put it, then by the odometric increment."""
    from paragym.mechanisms import tripod as mt

    env = gym.make(TRIPOD)
    env.reset(seed=0, options={"scenario": "push"})
    u = env.unwrapped
    for _ in range(5):
        env.step(np.zeros(3, np.float32))
    before = u.state.estimate[0].copy()
    target = u.state.smoothed[0].copy()
    odometry = u.state.drive.odometry[0].copy()
    _, _, _, _, info = env.step(np.array([1.0, 0.0, 0.0], np.float32))
    moved = mt.relocate(before, 0, target)
    increment = info["odometry"][:, :2] - odometry[:, :2]
    want = before[:, :2] + increment
    want[0] += 0.2 * (moved[0, :2] - before[0, :2])
    np.testing.assert_allclose(info["estimate"][:, :2], want, rtol=0, atol=1e-12)


def test_tripod_v1_reference_beats_odometry_through_the_action():
    """The paper's test of the faulty unit, acting through v1's action, ends
    the initial-heading drive within 4 cm; odometry alone does not."""
    env = gym.make(TRIPOD)
    ref = get_policy(TRIPOD, "encoder-correction").factory(env, 0)
    ref.reset(None, None)
    _, ref_info, _ = _run(env, ref.act, seed=0, options={"scenario": "initial_heading"})
    _, odo_info, _ = _run(env, lambda o, i: np.zeros(3, np.float32), seed=0,
                          options={"scenario": "initial_heading"})
    assert ref_info["unit_error"] < 0.04 < odo_info["unit_error"]


def test_tripod_v1_observation_is_in_the_robot_frame():
    """The observation's layout: residuals against the smoothed encoder
    distances, and the offsets of the estimate from odometry."""
    from paragym.mechanisms import tripod as mt

    env = gym.make(TRIPOD)
    obs, info = env.reset(seed=1)
    assert obs.shape == (16,) and env.observation_space.contains(obs)
    for _ in range(30):
        obs, _, _, _, info = env.step(np.array([1.0, 1.0, 1.0], np.float32))
    residual = (mt.distances(info["estimate"][None])[0] - info["encoder_distances"]) / 0.05
    np.testing.assert_allclose(obs[:3], residual, rtol=0, atol=1e-5)
    heading = env.unwrapped.scenario.heading
    offset = info["estimate"][:, :2] - info["odometry"][:, :2]
    along = offset @ np.array([np.cos(heading), np.sin(heading)])
    np.testing.assert_allclose(obs[6:12:2], along / 0.1, rtol=0, atol=1e-5)


# --- the CaPaMan -------------------------------------------------------------------------------------------------

def test_capaman_v1_standing_still_scores_below_any_progress():
    """Standing still for the 400 steps returns -4; a step toward the target
    earns more than it costs."""
    env = gym.make(CAPAMAN)
    total, info, infos = _run(env, lambda o, i: np.zeros(3, np.float32), seed=5)
    assert len(infos) == 401 and not info["is_success"]
    assert total == pytest.approx(-4.0, abs=1e-9)
    obs, info = env.reset(seed=5)
    toward = np.clip(obs[3:6] * 45 / 2, -1, 1).astype(np.float32)  # the target minus the cranks, in steps
    _, reward, _, _, _ = env.step(toward)
    assert reward > 0


def test_capaman_v1_look_ahead_is_the_clearance_three_degrees_on():
    """Entries 37-39: the clearance if one crank moved 3 deg further, minus
    the clearance, over the cap, from PyBullet's scene; 0 far from obstacles."""
    env = gym.make(CAPAMAN)
    rng = np.random.default_rng(0)
    seen_near = False
    for seed in range(6):
        obs, info = env.reset(seed=seed)
        for _ in range(25):
            obs, _, terminated, _, info = env.step(rng.uniform(-1, 1, 3).astype(np.float32))
            if terminated:
                break
        if info["collision"]:
            continue
        scene = CaPaManScene(capaman.DEFAULT_GEOMETRY)
        scene.set_obstacles(env.unwrapped.scenario.obstacles)
        cap = 0.05
        scene.set_configuration(info["alpha"])
        now = min(scene.clearance()[0], cap)
        for k in range(3):
            probe = info["alpha"].copy()
            probe[k] = min(probe[k] + LOOKAHEAD, 135 * DEG)
            scene.set_configuration(probe)
            ahead = min(scene.clearance()[0], cap)
            want = (ahead - now) / cap if now < cap else 0.0
            assert obs[37 + k] == pytest.approx(np.clip(want, -1, 1), abs=1e-5)
        seen_near |= now < cap
        scene.close()
    assert seen_near


def test_capaman_v1_reach_tolerance_and_penalties():
    env = gym.make(CAPAMAN).unwrapped
    assert env.reach_tolerance == pytest.approx(3 * DEG) and env.collision_penalty == 4.0
    assert env.time_penalty == 0.01 and env.observation_space.shape == (41,)
    with pytest.raises(ValueError, match="time_penalty"):
        gym.make("paragym/CaPaManCollisionFree-v0", time_penalty=0.1)


# --- the hybrid --------------------------------------------------------------------------------------------------

def _excess(p1: np.ndarray, delta: float) -> float:
    g = hybrid.DEFAULT_GEOMETRY
    lengths = hybrid.solve_rows(p1[None], np.array([delta]), g)[0][0]
    return float(np.maximum(0, np.abs(2 * (lengths - g.l_min) / (g.l_max - g.l_min) - 1) - 1).sum())


def test_hybrid_v1_observation_shows_where_the_path_ends():
    """v0's observation, then P1, P1 solved at the current split, and its stroke excess with the
    excess's change one split step up and down; the step, flags and success are v0's."""
    from paragym.tasks.hybrid_step import POSE_SCALE

    old, new = gym.make("paragym/HybridSingularityFree-v0"), gym.make(HYBRID)
    g = hybrid.DEFAULT_GEOMETRY
    rng = np.random.default_rng(0)
    o0, i0 = old.reset(seed=100000 + 3003)  # a scenario whose end needs a split near 0.8
    o1, i1 = new.reset(seed=100000 + 3003)
    assert o1.shape == (48,) and new.observation_space.shape == (48,)
    p1 = np.array(i1["scenario"].p1)
    assert _excess(p1, 0.5) > 0.01
    t1 = False
    while not t1:
        d = i1["delta"]
        np.testing.assert_array_equal(o1[:28], o0)
        np.testing.assert_allclose(o1[28:34], p1 / POSE_SCALE, atol=1e-6)
        lengths, mu_h, mu_t, _, _ = hybrid.solve_rows(p1[None], np.array([d]), g)
        np.testing.assert_allclose(o1[34:43], 2 * (lengths[0] - g.l_min) / (g.l_max - g.l_min) - 1, atol=1e-6)
        np.testing.assert_allclose(o1[43:45], [mu_h[0], mu_t[0]], atol=1e-6)
        here = _excess(p1, d)
        np.testing.assert_allclose(o1[45:], [10 * here, 100 * (_excess(p1, min(1, d + 0.05)) - here),
                                             100 * (_excess(p1, max(0, d - 0.05)) - here)], atol=1e-5)
        a = rng.uniform(-1, 1, 4).astype(np.float32)
        o0, r0, t0, _, i0 = old.step(a)
        o1, r1, t1, _, i1 = new.step(a)
        assert r1 == r0 and t1 == t0 and i1["is_success"] == i0["is_success"]


@pytest.mark.parametrize("seed", [3, 4])
def test_hybrid_v1_shaping_sums_to_a_constant_of_the_scenario(seed):
    """With w_end, v1's return is v0's plus w_end * e(0.5) at P1, whatever the actions
    (potential-based); by default (w_end 0) it is v0's."""
    rng = np.random.default_rng(seed)
    old, new = gym.make("paragym/HybridSingularityFree-v0"), gym.make(HYBRID, w_end=10.0)
    for scenario_seed in (100000 + 3003, 100000 + 9):
        _, info = new.reset(seed=scenario_seed)
        old.reset(seed=scenario_seed)
        p1 = np.array(info["scenario"].p1)
        actions = rng.uniform(-1, 1, (100, 4)).astype(np.float32)
        actions[:, 0] = rng.choice([-1.0, 0.2, 1.0])  # walk the split far one way
        r_old = sum(old.step(a)[1] for a in actions)
        r_new = sum(new.step(a)[1] for a in actions)
        assert r_new - r_old == pytest.approx(new.unwrapped.params.w_end * _excess(p1, 0.5), abs=1e-9)
    assert gym.make(HYBRID).unwrapped.params.w_end == 0.0
    with pytest.raises(ValueError, match="w_end"):
        gym.make("paragym/HybridSingularityFree-v0", w_end=1.0)


def test_hybrid_v1_plays_the_v0_reference_and_floors():
    from paragym.baselines.policies import policies_for

    names = set(policies_for(HYBRID))
    assert {"polynomial-detour", "zero", "random"} <= names
    policy = get_policy(HYBRID, "polynomial-detour").factory(gym.make(HYBRID), 0)
    from paragym.rollout import run_episode

    assert run_episode(gym.make(HYBRID), policy, 100000 + 3003).success


@pytest.mark.parametrize("env_id", [CAPAMAN, TRIPOD, HYBRID])
def test_v1_envs_pass_the_env_checker(env_id):
    from gymnasium.utils.env_checker import check_env

    check_env(gym.make(env_id).unwrapped, skip_render_check=True)
