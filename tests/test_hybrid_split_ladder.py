"""The hybrid's ladders v1 and v2: the split as the only lever, on pairs that no constant action gets through, that the
reference provably plans, and that the lookahead rule fails at each rung's horizons. Played through the env
itself, so that a generator that kept the wrong pairs fails here."""

from __future__ import annotations

from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest
from pages import status

import paragym
from paragym import registry
from paragym.baselines.policies import get_policy
from paragym.baselines.simple import ConstantPolicy
from paragym.baselines.tasks.hybrid import Lookahead
from paragym.mechanisms import hybrid
from paragym.planners.polynomial_detour import PolynomialDetourPlanner
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


#: the ladder v2's rungs: the ladder v1's, certified with every stroke 1 mm inside its limits
SPLIT_RUNGS_V2 = [r.id for r in registry.ladders("hybrid")[2]]


def test_the_ladder_v2_is_the_ladder_v1_with_a_margin_in_its_certificate():
    assert SPLIT_RUNGS_V2 == [f"paragym/HybridSingularityFree-{n}-v2" for n in registry.RUNG_NAMES]
    assert [r.models_from for r in registry.ladders("hybrid")[2]] == SPLIT_RUNGS
    assert [gym.make(i).unwrapped.params.rules.rung for i in SPLIT_RUNGS_V2] == \
        [replace(r, margin=0.001) for r in SPLIT_LADDER]


@pytest.mark.parametrize("env_id", SPLIT_RUNGS + SPLIT_RUNGS_V2)
def test_a_split_rung_draws_pairs_no_constant_nor_its_lookahead_gets_through_and_the_reference_plans(env_id):
    rung = gym.make(env_id).unwrapped.params.rules.rung
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
        if rung.margin:  # and it plans it with every stroke the margin inside its limits
            g = hybrid.DEFAULT_GEOMETRY
            PolynomialDetourPlanner(replace(g, l_min=g.l_min + rung.margin, l_max=g.l_max - rung.margin),
                                    j_bar=0.0).plan(p0[0], p1[0])
        env.close()
    vec = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    vec.reset(seed=7000)
    assert vec.unwrapped.state.scenarios[0] == drawn.reset(seed=7000)[1]["scenario"]
    vec.close()
    drawn.close()


def test_the_ladder_v2_reference_holds_its_leg_limits_under_physics_where_the_ladder_v1_s_could_not():
    """Reset seed 300001 of the easy rung: the ladder v1 draws a pair with no schedule 1 mm inside the limits, the
    reference plans at them and the simulated actuators overshoot (leg-limit poses, a failure); the ladder v2
    draws again, and the reference's plan, 1 mm inside, holds under physics."""
    from paragym.baselines.leaderboard.evaluate import evaluate_dynamic

    rows = [evaluate_dynamic(get_policy(env_id, "polynomial-detour"), "random", 300001)
            for env_id in (SPLIT_RUNGS[0], SPLIT_RUNGS_V2[0])]
    assert not rows[0].success and rows[0].metrics["limit_violations"] > 0
    assert rows[1].success and rows[1].metrics["limit_violations"] == 0


def test_a_memoised_draw_is_the_draw_and_leaves_the_generator_where_the_draw_does():
    """The same generator state draws from the memo (a leaderboard's policies meet the same reset seeds): the
    same pair, and the generator after it in the state the draw leaves, so that what follows draws alike."""
    from paragym.tasks import hybrid as scenarios

    rung = scenarios.SPLIT_LADDER_V2[1]
    scenarios._SPLIT_MEMO.clear()
    drawn, fresh = np.random.default_rng(41), np.random.default_rng(41)
    first = scenarios.split_ladder_scenarios([drawn], rung)[0]
    after_draw = drawn.random(3)
    assert len(scenarios._SPLIT_MEMO) == 1
    again = scenarios.split_ladder_scenarios([fresh], rung)[0]
    assert again == first and np.array_equal(fresh.random(3), after_draw)
    assert len(scenarios._SPLIT_MEMO) == 1  # taken from the memo, not drawn again
    other = scenarios.split_ladder_scenarios([np.random.default_rng(42)], rung)[0]
    assert other != first and len(scenarios._SPLIT_MEMO) == 2
    env = gym.make(SPLIT_RUNGS_V2[1])
    runs = []
    for _ in range(2):  # drawn, then from the memo: the same observation and the env's generator where it was
        obs, _ = env.reset(seed=7)
        runs.append((obs, env.unwrapped.np_random.random(4)))
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1])
    env.close()
