"""The single env and the native vector env are one task (issue 16): property-based.

Hypothesis draws custom scenarios (any that the task can express, valid or
not) and action sequences inside and outside the Box; two single envs
(gymnasium's SyncVectorEnv) and the native vector env of two robots must
then agree: both refuse the scenario with the same error, or both run it with
the same observations, rewards, flags and info, to 1e-9, across autoresets.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from paragym.sim.obstacles import Box, Cylinder
from paragym.sim.tripod_drive import Terrain
from paragym.tasks.capaman import CaPaManScenario
from paragym.tasks.hybrid import HybridScenario
from paragym.tasks.orthoglide import circle_task
from paragym.tasks.tripod import TripodScenario

SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=False)
ROBOTS = 2


def _same_run(env_id: str, scenario, actions: list[np.ndarray], seed: int, **kwargs) -> None:
    """Both vector envs refuse ``scenario`` alike, or run ``actions`` alike."""
    made = {}
    for mode in ("sync", "vector_entry_point"):
        try:
            made[mode] = gym.make_vec(env_id, num_envs=ROBOTS, vectorization_mode=mode, scenario=scenario, **kwargs)
        except (ValueError, TypeError) as exc:
            made[mode] = exc
    sync, native = made["sync"], made["vector_entry_point"]
    try:
        if isinstance(sync, Exception) or isinstance(native, Exception):
            assert type(sync) is type(native), f"sync: {sync!r}; native: {native!r}"
            event("refused at construction")
            return
        outcome = {}
        for name, env in (("sync", sync), ("native", native)):
            try:
                outcome[name] = env.reset(seed=seed)
            except (ValueError, TypeError) as exc:
                outcome[name] = exc
        if any(isinstance(o, Exception) for o in outcome.values()):
            assert type(outcome["sync"]) is type(outcome["native"]), outcome
            assert "scenario" in str(outcome["native"])
            event("refused at reset")
            return
        event("ran")
        np.testing.assert_allclose(outcome["native"][0], outcome["sync"][0], rtol=0, atol=1e-9)
        _same_info(outcome["native"][1], outcome["sync"][1])
        for a in actions:
            batch = np.tile(a, (ROBOTS, 1)).astype(np.float32)
            got, want = native.step(batch), sync.step(batch)
            for x, y in zip(got[:4], want[:4], strict=True):
                np.testing.assert_allclose(np.asarray(x, float), np.asarray(y, float), rtol=0, atol=1e-9)
            _same_info(got[4], want[4])
    finally:
        for env in (sync, native):
            if not isinstance(env, Exception):
                env.close()


def _same_info(native: dict, sync: dict) -> None:
    """Every entry the native env reports equals the single envs' (the native
    env reports the numeric ones; the objects, like the scenario, stay in the
    single env's info)."""
    for key, value in native.items():
        if key.startswith("_"):
            continue
        assert key in sync, f"info[{key!r}] is missing from the single env"
        if np.asarray(value).dtype == object:  # names, as "failure"
            assert list(value) == list(sync[key]), f"info[{key!r}]"
            continue
        np.testing.assert_allclose(np.asarray(value, float), np.asarray(sync[key], float), rtol=0, atol=1e-9,
                                   err_msg=f"info[{key!r}]")


def _actions(dim: int, most: int):
    one = st.lists(st.floats(-1.5, 1.5, allow_nan=False, width=32), min_size=dim, max_size=dim).map(np.array)
    return st.lists(one, min_size=1, max_size=most)


@settings(max_examples=12, **SETTINGS)
@given(cx=st.floats(-0.3, 0.5), cy=st.floats(0.2, 0.9), r=st.floats(0.0, 0.45), duration=st.floats(0.3, 4.0),
       start=st.floats(0, 6.3), mode=st.sampled_from(["null_space", "joint_velocity"]),
       seed=st.integers(0, 2 ** 16), data=st.data())
def test_orthoglide(cx, cy, r, duration, start, mode, seed, data):
    task = circle_task((cx, cy), r, duration, start=start, steps=40)
    dim = 1 if mode == "null_space" else 3
    _same_run("paragym/Orthoglide2PRRKappa-v0", task, data.draw(_actions(dim, 90)), seed, action_mode=mode)


@settings(max_examples=12, **SETTINGS)
@given(p0=st.lists(st.floats(-0.12, 0.12), min_size=6, max_size=6),
       p1=st.lists(st.floats(-0.12, 0.12), min_size=6, max_size=6),
       seed=st.integers(0, 2 ** 16), version=st.sampled_from(["v0", "v1"]), data=st.data())
def test_hybrid(p0, p1, seed, version, data):
    scenario = HybridScenario("h", (p0[0], p0[1], abs(p0[2]), *p0[3:]), (p1[0], p1[1], abs(p1[2]), *p1[3:]))
    _same_run(f"paragym/HybridSingularityFree-{version}", scenario, data.draw(_actions(4, 120)), seed)


@settings(max_examples=12, **SETTINGS)
@given(speed=st.floats(0.2, 2.0), distance=st.floats(0.5, 3.0), heading=st.floats(-3.2, 3.2),
       error=st.floats(-0.05, 0.05), unit=st.integers(0, 2),
       push=st.none() | st.tuples(st.integers(0, 2), st.floats(0.0, 1.0), st.floats(-0.03, 0.03)),
       slip=st.floats(0.0, 0.02),
       bumps=st.lists(st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-0.1, 0.1), st.floats(0.05, 1.0)),
                      max_size=10),
       seed=st.integers(0, 2 ** 16), version=st.sampled_from(["v0", "v1"]), data=st.data())
def test_mobile_tripod(speed, distance, heading, error, unit, push, slip, bumps, seed, version, data):
    errors = [0.0, 0.0, 0.0]
    errors[unit] = error
    if push is not None:
        push = (push[0], push[1] * distance / speed, push[2])
    scenario = TripodScenario("d", speed=speed, distance=distance, heading=heading, heading_error=tuple(errors),
                             push=push, slip=slip, terrain=Terrain(tuple(bumps)))
    _same_run(f"paragym/MobileTripodOdometry-{version}", scenario,
              data.draw(_actions(6 if version == "v0" else 3, 80)), seed)


@settings(max_examples=10, **SETTINGS)
@given(alpha=st.lists(st.floats(0.8, 2.35), min_size=9, max_size=9),
       obstacle=st.tuples(st.floats(-0.04, 0.04), st.floats(-0.04, 0.04), st.floats(0.005, 0.02), st.booleans()),
       seed=st.integers(0, 2 ** 16), version=st.sampled_from(["v0", "v1"]), data=st.data())
def test_capaman(alpha, obstacle, seed, version, data):
    x, y, size, round_ = obstacle
    shape = Cylinder((x, y, 0.04), size, 0.08) if round_ else Box((x, y, 0.04), (size, size, 0.04))
    points = tuple(tuple(alpha[3 * i:3 * i + 3]) for i in range(3))  # T.P.1..3 in the joint range
    scenario = CaPaManScenario("mine", (shape,), points)
    _same_run(f"paragym/CaPaManCollisionFree-{version}", scenario, data.draw(_actions(3, 40)), seed,
              collision="grid")


@pytest.mark.parametrize("mode", ["sync", "vector_entry_point"])
def test_hybrid_refuses_a_start_outside_the_workspace_alike(mode):
    """The divergence the issue found: start and goal 0.3 m above home were
    refused by the single env and run by the vector env (reward about -9)."""
    high = HybridScenario("high", (0.0, 0.0, 0.3, 0.0, 0.0, 0.0), (0.0, 0.0, 0.3, 0.0, 0.0, 0.0))
    env = gym.make_vec("paragym/HybridSingularityFree-v0", num_envs=2, vectorization_mode=mode)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="scenario.p0 is outside the workspace"):
        env.reset(seed=0, options={"scenario": high})
    env.close()
