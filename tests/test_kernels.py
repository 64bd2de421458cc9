"""The compiled-entry calls of paragym.kernels: typed once, retyped where the caller says the types changed,
never kept in a copy, and equal to numba's dispatcher."""

from __future__ import annotations

import copy
import math
import pickle
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np
import pytest
from numba import njit

import paragym  # noqa: F401
from paragym.kernels import SPLIT_MIN_ROWS, KernelArrays, entry, thread_count
from paragym.mechanisms.geometry import k_jacobi, k_jacobi_lanes


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


def _textbook_jacobi(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cyclic Jacobi (Golub and Van Loan, Algorithm 8.5.3) in plain Python floats: each rotation applied to the
    columns, then to the rows, then to the eigenvectors; the reference the compiled version must equal."""
    n = len(a)
    a, v = a.tolist(), np.eye(n).tolist()
    for sweep in range(60):
        if sum(abs(a[p][q]) for p in range(n - 1) for q in range(p + 1, n)) == 0.0:
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                apq = a[p][q]
                if apq == 0.0:
                    continue
                app, aqq = a[p][p], a[q][q]
                g = 100.0 * abs(apq)
                if sweep > 2 and abs(app) + g == abs(app) and abs(aqq) + g == abs(aqq):
                    a[p][q] = a[q][p] = 0.0
                    continue
                theta = (aqq - app) / (2.0 * apq)
                t = 0.5 / theta if abs(theta) > 1e150 else math.copysign(
                    1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0)), theta if theta != 0 else 1.0)
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):
                    a[k][p], a[k][q] = c * a[k][p] - s * a[k][q], s * a[k][p] + c * a[k][q]
                for k in range(n):
                    a[p][k], a[q][k] = c * a[p][k] - s * a[q][k], s * a[p][k] + c * a[q][k]
                a[p][q] = a[q][p] = 0.0
                for k in range(n):
                    v[k][p], v[k][q] = c * v[k][p] - s * v[k][q], s * v[k][p] + c * v[k][q]
    return np.array(a), np.array(v)


@pytest.mark.parametrize("n", [3, 4, 6])
def test_jacobi_in_lanes_is_the_textbook_rotation_bit_for_bit(n):
    # the compiled rotations update one half and mirror it, and run several matrices in lockstep; each matrix
    # must still meet exactly the textbook's arithmetic (the released hybrid ids' measures rest on its bits)
    rng = np.random.default_rng(n)
    mats = []
    for k in range(24):
        m = rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-3, 3)
        if k % 3 == 0:
            m[:, -1] = m[:, 0]  # singular
        mats.append(m.T @ m if k % 2 else m + m.T)
    mats = np.array(mats)
    values, vectors = mats.copy(), np.empty_like(mats)
    k_jacobi_lanes(values, vectors, len(mats))
    only_values = mats.copy()
    k_jacobi_lanes(only_values, np.empty((1, 0, 0)), len(mats))
    for m, got, got_v, got_only in zip(mats, values, vectors, only_values, strict=True):
        want, want_v = _textbook_jacobi(m)
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(got_v, want_v)
        np.testing.assert_array_equal(got_only, want)
        alone, alone_v = m.copy(), np.empty((n, n))
        k_jacobi(alone, alone_v)
        np.testing.assert_array_equal(alone, want)
        np.testing.assert_allclose(np.sort(np.diag(got)), np.linalg.eigvalsh(m), rtol=1e-10,
                                   atol=1e-12 * np.abs(m).max())


def test_thread_count_reads_paragym_threads(monkeypatch):
    monkeypatch.setenv("PARAGYM_THREADS", "3")
    assert thread_count() == 3
    for bad in ("two", "0"):
        monkeypatch.setenv("PARAGYM_THREADS", bad)
        with pytest.raises(ValueError, match="PARAGYM_THREADS"):
            thread_count()


def test_robots_shared_among_threads_step_as_in_one_call(monkeypatch):
    # the hybrid's step shares its robots among threads (KernelArrays.call_split): every robot must come out
    # exactly as one call steps it, through autoresets
    n = 2 * SPLIT_MIN_ROWS
    runs = []
    for threads in ("1", "3"):
        monkeypatch.setenv("PARAGYM_THREADS", threads)
        env = gym.make_vec("paragym/HybridSingularityFree-Easy-v0", num_envs=n,
                           vectorization_mode="vector_entry_point", train_scenarios=16)
        obs, _ = env.reset(seed=3)
        actions = np.random.default_rng(0).uniform(-1, 1, (40, *env.action_space.shape)).astype(np.float32)
        out = [obs]
        for a in actions:
            obs, reward, terminated, truncated, _ = env.step(a)
            out += [obs, reward, terminated, truncated]
        env.close()
        runs.append(out)
    for one, shared in zip(*runs, strict=True):
        np.testing.assert_array_equal(one, shared)
