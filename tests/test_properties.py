"""Property-based guards for every env and native vector env (issue 15, item 13).

Valid input never crashes and gives finite observations inside the observation space; invalid
input gets a ValueError or TypeError that names the argument, at the boundary. Kept small
(a few dozen examples each) so that the suite stays fast; hypothesis remembers failures.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from env_ids import STEP_IDS
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from paragym import registry
from paragym.sim.tripod_drive import Terrain
from paragym.tasks.hybrid import HybridScenario
from paragym.tasks.orthoglide import OrthoglideScenario, circle_task
from paragym.tasks.tripod import TripodScenario

IDS = STEP_IDS  # one id per transition and spaces (tests/env_ids.py)
SCENARIOS = {r.id: ["random", *(n for n in r.scenario_names if n != "random")] for r in registry.ROWS}
FAST = settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                       HealthCheck.function_scoped_fixture])
_ENVS: dict[str, gym.Env] = {}
_VECS: dict[str, gym.vector.VectorEnv] = {}


def _env(env_id):
    if env_id not in _ENVS:
        _ENVS[env_id] = gym.make(env_id, disable_env_checker=True)
    return _ENVS[env_id]


def _vec(env_id):
    if env_id not in _VECS:
        _VECS[env_id] = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
    return _VECS[env_id]


def _inside(space, obs) -> bool:
    return bool(np.all(np.isfinite(obs)) and space.contains(np.asarray(obs, space.dtype)))


actions = st.lists(st.floats(-3.0, 3.0, allow_nan=False, width=32), min_size=1, max_size=6)


@pytest.mark.parametrize("env_id", IDS)
@FAST
@given(seed=st.integers(0, 2 ** 31 - 1), choice=st.integers(0, 4), steps=st.lists(actions, min_size=1, max_size=15))
def test_valid_input_never_crashes_and_stays_in_the_space(env_id, seed, choice, steps):
    env = _env(env_id)
    names = SCENARIOS[env_id]
    obs, info = env.reset(seed=seed, options={"scenario": names[choice % len(names)]})
    assert _inside(env.observation_space, obs)
    dim = env.action_space.shape[0]
    for values in steps:
        action = np.resize(np.array(values, np.float32), dim)  # in and out of the Box
        obs, reward, term, trunc, info = env.step(action)
        assert _inside(env.observation_space, obs) and math.isfinite(reward)
        if term or trunc:
            break


@pytest.mark.parametrize("env_id", IDS)
@FAST
@given(seed=st.integers(0, 2 ** 31 - 1), steps=st.lists(st.floats(-3.0, 3.0, allow_nan=False), min_size=1,
                                                          max_size=12), mask=st.lists(st.booleans(), min_size=3,
                                                                                      max_size=3))
def test_the_native_vector_env_never_crashes_and_stays_in_the_space(env_id, seed, steps, mask):
    venv = _vec(env_id)
    obs, _ = venv.reset(seed=seed)
    assert _inside(venv.observation_space, obs)
    shape = venv.action_space.shape
    for k, value in enumerate(steps):
        action = np.full(shape, value, np.float32) * np.linspace(-1, 1, int(np.prod(shape))).reshape(shape)
        obs, reward, term, trunc, _ = venv.step(action)
        assert _inside(venv.observation_space, obs) and np.isfinite(reward).all()
        if k == 3 and any(mask):
            obs, _ = venv.reset(options={"reset_mask": np.array(mask)})
            assert _inside(venv.observation_space, obs)


junk = st.one_of(st.text(max_size=4), st.complex_numbers(allow_nan=False, allow_infinity=False).filter(
    lambda z: z.imag != 0), st.none(), st.just(float("nan")), st.just(float("inf")), st.just(10 ** 400),
    st.lists(st.floats(-1, 1), min_size=7, max_size=9), st.dictionaries(st.text(max_size=2), st.integers(),
                                                                        max_size=2))


@pytest.mark.parametrize("env_id", IDS)
@FAST
@given(bad=junk)
def test_invalid_actions_get_a_clear_error(env_id, bad):
    env = _env(env_id)
    env.reset(seed=0)
    dim = env.action_space.shape[0]
    action = bad
    if isinstance(bad, float | complex | int) and not isinstance(bad, bool):
        action = np.full(dim, bad, dtype=object if isinstance(bad, int) else type(bad))
    with pytest.raises((ValueError, TypeError), match="action"):
        env.step(action)


@FAST
@given(p0=st.lists(st.floats(-0.3, 0.3) | st.just(float("nan")), min_size=6, max_size=6),
       p1=st.lists(st.floats(-0.3, 0.3), min_size=6, max_size=6))
def test_custom_hybrid_scenarios_are_refused_at_reset_or_run(p0, p1):
    env = _env("paragym/HybridSingularityFree-v0")
    scenario = HybridScenario("h", tuple(v * 0.3 for v in p0), tuple(v * 0.3 for v in p1))
    _refused_or_runs(env, scenario)


@FAST
@given(speed=st.floats(-1.0, 3.0), distance=st.floats(-1.0, 30.0), heading=st.floats(-7, 7),
       error=st.lists(st.floats(-2.0, 2.0), min_size=2, max_size=4),
       push=st.none() | st.tuples(st.integers(-1, 4), st.floats(-1.0, 40.0), st.floats(-0.1, 0.1)),
       slip=st.floats(-0.01, 0.02), bumps=st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5),
                                                             st.floats(-0.05, 0.05), st.floats(-0.1, 1.0)),
                                                   max_size=3))
def test_custom_drives_are_refused_at_reset_or_run(speed, distance, heading, error, push, slip, bumps):
    env = _env("paragym/MobileTripodOdometry-v0")
    scenario = TripodScenario("d", speed=speed, distance=distance, heading=heading, heading_error=tuple(error),
                             push=push, slip=slip, terrain=Terrain(tuple(bumps)))
    _refused_or_runs(env, scenario, steps=40)


@FAST
@given(cx=st.floats(-1.5, 1.5), cy=st.floats(-1.5, 1.5), r=st.floats(0.0, 1.0), duration=st.floats(0.5, 20.0),
       broken=st.booleans())
def test_custom_orthoglide_tasks_are_refused_at_reset_or_run(cx, cy, r, duration, broken):
    env = _env("paragym/Orthoglide2PRRKappa-v0")
    task = circle_task((cx, cy), r, duration, steps=100)
    if broken:
        task = OrthoglideScenario("broken", task.t[::-1], task.points, task.velocities)
    _refused_or_runs(env, task)


def _refused_or_runs(env, scenario, steps=30):
    try:
        obs, _ = env.reset(seed=0, options={"scenario": scenario})
    except (ValueError, TypeError) as exc:
        assert "scenario" in str(exc)
        return
    assert _inside(env.observation_space, obs)
    for _ in range(steps):
        obs, reward, term, trunc, _ = env.step(env.action_space.sample())
        assert _inside(env.observation_space, obs) and math.isfinite(reward)
        if term or trunc:
            break
