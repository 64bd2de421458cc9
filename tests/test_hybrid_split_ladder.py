"""The hybrid's ladder v1: the split as the only lever, on pairs that no constant action gets through, that the
reference provably plans, and that the lookahead rule fails at each rung's horizons. Played through the env
itself, so that a generator that kept the wrong pairs fails here."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import paragym
from paragym import registry
from paragym.baselines.policies import get_policy
from paragym.baselines.simple import ConstantPolicy
from paragym.baselines.tasks.hybrid import Lookahead
from paragym.docpages import status
from paragym.mechanisms import hybrid
from paragym.rollout import run_episode
from paragym.tasks.hybrid import SPLIT_LADDER, nominal_rows

SPLIT_RUNGS = [r.id for r in registry.ladders("hybrid")[1]]


def test_the_hybrid_has_a_second_ladder_of_ids_of_their_own():
    assert SPLIT_RUNGS == [f"paragym/HybridSingularityFree-{n}-v1" for n in registry.RUNG_NAMES]
    assert [r.id for r in registry.ladders("hybrid")[0]] == [
        f"paragym/HybridSingularityFree-{n}-v0" for n in registry.RUNG_NAMES]
    assert registry.newest()[1] == "paragym/HybridSingularityFree-v2"  # a ladder is not a version of its task
    assert status(SPLIT_RUNGS[2]).startswith("rung 2 of 3 (0 the easiest) of the ladder v1")
    assert set(SPLIT_RUNGS) <= set(paragym.ENVIRONMENTS) and set(SPLIT_RUNGS) <= set(paragym.VECTOR_ENTRY_POINTS)


def test_a_split_rung_acts_on_the_split_alone():
    env = gym.make(SPLIT_RUNGS[0])
    assert env.action_space.shape == (1,)
    env.reset(seed=1)
    _, _, _, _, info = env.step(np.array([2.0], np.float32))  # clipped to the Box: one whole step of the split
    assert info["delta"] == pytest.approx(0.55) and not np.any(info["offset"])
    with pytest.raises(ValueError):
        env.step(np.zeros(4, np.float32))  # the ladder v0's action is refused
    env.close()


@pytest.mark.parametrize("env_id", SPLIT_RUNGS)
def test_a_split_rung_draws_pairs_no_constant_nor_its_lookahead_gets_through_and_the_reference_plans(env_id):
    rung = SPLIT_LADDER[registry.row(env_id).rung]
    drawn = gym.make(env_id)
    for seed in range(7000, 7002):
        _, info = drawn.reset(seed=seed)
        pair = info["scenario"]
        p0, p1 = np.array([pair.p0]), np.array([pair.p1])
        assert hybrid.within_limits(p0, 0.5)[0] and hybrid.within_limits(p1, 0.5)[0]
        middle = nominal_rows(p0, p1)[0, 1:-1]
        assert not hybrid.within_limits(middle, 0.5).all()  # the nominal path breaks a limit midway
        env = gym.make(env_id, scenario=pair)  # the pair itself, played without drawing again
        space = env.action_space
        for rate in (-1.0, -0.5, -0.1, 0.0, 0.1, 0.5, 1.0):
            assert not run_episode(env, ConstantPolicy(space, np.array([rate], np.float32)), seed=0).success, rate
        for horizon in rung.lookahead:
            assert not run_episode(env, Lookahead(horizon), seed=0).success, horizon
        reference = get_policy(env_id, "polynomial-detour").factory(env, 0)
        assert run_episode(env, reference, seed=0).success  # the rung's certificate: the reference plans it
        env.close()
    vec = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    vec.reset(seed=7000)
    assert vec.unwrapped.state.scenarios[0] == drawn.reset(seed=7000)[1]["scenario"]
    vec.close()
    drawn.close()
