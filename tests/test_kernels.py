"""The compiled-entry calls of paragym.kernels: typed once, retyped where the caller says the types changed,
never kept in a copy, and equal to numba's dispatcher."""

from __future__ import annotations

import copy
import pickle
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np
import pytest
from numba import njit

import paragym  # noqa: F401
from paragym.kernels import KernelArrays, entry


@njit(cache=False)
def _first_plus(arrays, extra):
    return arrays[0].ravel()[0] + extra.ravel()[0]


@dataclass
class _State(KernelArrays):
    KERNEL_FIELDS = ("a",)
    a: np.ndarray = field(default_factory=lambda: np.full(3, 2.0))


def test_an_entry_computes_what_the_dispatcher_does():
    arrays, extra = (np.full(3, 2.0),), np.full(2, 0.5)
    assert entry(_first_plus, (arrays, extra))(arrays, extra) == _first_plus(arrays, extra) == 2.5


def test_a_new_owner_or_key_types_the_call_again():
    s = _State()
    one, two = object(), object()
    assert s.call(_first_plus, (s.kernel_arrays(), np.full(2, 0.5)), one, (1,)) == 2.5
    # an int64 array read through the float64 entry would be garbage: the new owner retypes the call
    assert s.call(_first_plus, (s.kernel_arrays(), np.full(2, 3, np.int64)), two, (1,)) == 5.0
    # so does a key naming another number of dimensions
    assert s.call(_first_plus, (s.kernel_arrays(), np.full((1, 2), 1.5)), two, (2,)) == 3.5
    assert len(s.__dict__["_entries"]) == 1  # one entry per kernel: the last types


@pytest.mark.parametrize("env_id", ["paragym/Orthoglide2PRRKappa-v1", "paragym/HybridSingularityFree-v2",
                                    "paragym/MobileTripodOdometry-v2", "paragym/CaPaManCollisionFree-v1"])
def test_a_stepped_state_copies_and_pickles_without_its_entries(env_id):
    env = gym.make(env_id)
    env.reset(seed=3)
    env.step(env.action_space.sample())
    state = env.unwrapped.state
    assert state.__dict__.get("_entries"), "the step went through the compiled entries"
    for twin in (copy.deepcopy(state), pickle.loads(pickle.dumps(state))):
        assert "_entries" not in twin.__dict__ and "_kernel_arrays" not in twin.__dict__
        assert twin.kernel_arrays()[0] is not state.kernel_arrays()[0]
        np.testing.assert_array_equal(twin.kernel_arrays()[0], state.kernel_arrays()[0])
    env.close()


def test_a_task_step_takes_an_integer_mask_and_integer_actions():
    """``task.step`` is public: a caller's int mask and int actions, after bool and float ones on the same state,
    are made the entry's types, not misread as them."""
    from paragym.tasks.hybrid_task import RULES, TASK

    params = TASK.Params.from_kwargs(RULES[2])
    states = [TASK.State.empty(2, params) for _ in range(2)]
    for s in states:
        rngs = [np.random.default_rng(7), np.random.default_rng(8)]
        TASK.reset(s, params, np.arange(2), TASK.draw_scenarios("random", rngs, params, None), rngs, None)
    a, b = states
    for _ in range(2):
        TASK.step(a, params, np.zeros((2, 4)), np.array([False, True]), None)
    TASK.step(b, params, np.zeros((2, 4)), np.array([False, True]), None)
    TASK.step(b, params, np.zeros((2, 4), np.int64), np.array([0, 1]), None)
    np.testing.assert_array_equal(a.obs, b.obs)
    np.testing.assert_array_equal(a.k, b.k)
