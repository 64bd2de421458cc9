"""One task contract (issue 39): every task implements :class:`paragym.tasks.base.Task`, the env classes are
generic shells over it, success is decided in one function per task, and one lifecycle holds for every id and
fidelity."""

from __future__ import annotations

import copy
import importlib
import pickle
import re
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from env_ids import KINEMATIC_IDS

from paragym import registry
from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.tasks.base import Task

ROOT = Path(__file__).resolve().parent.parent


def _cls(entry_point: str) -> type:
    module, name = entry_point.split(":")
    return getattr(importlib.import_module(module), name)


def _task(name: str):
    return importlib.import_module(f"paragym.tasks.{name}_task").TASK


@pytest.mark.parametrize("row", registry.ROWS, ids=lambda r: r.name)
def test_every_id_is_a_task_and_its_rules(row):
    single, vector = _cls(row.entry_point), _cls(row.vector_entry_point)
    assert issubclass(single, ParagymEnv) and issubclass(vector, ParagymVectorEnv)
    assert single.task is vector.task and single.rules == vector.rules, row.id
    assert isinstance(single.task, Task) and single.task.name == row.task
    assert isinstance(single.rules, single.task.Rules) and single.rules.version == row.version
    if row.rung is None:
        assert row.scenarios is None and row.scenario_names == single.task.scenario_names  # read from the task
    else:  # a rung ranks its own drawn scenarios, the task's "random"
        assert row.scenarios == ("random",) and "random" in single.task.scenario_names
    # the class adds no code: the shells do it all
    assert {k for k in vars(single) if not k.startswith("__")} <= {"task", "rules", "metadata"}, single
    assert {k for k in vars(vector) if not k.startswith("__")} <= {"task", "rules"}, vector


def test_the_shells_hold_no_task_hooks_flags_or_single_envs():
    base = (ROOT / "envs" / "base.py").read_text()
    vector = (ROOT / "envs" / "vector.py").read_text()
    assert "NotImplementedError" not in base and "NotImplementedError" not in vector
    assert "single_env" not in vector and "single_class" not in vector
    for path in [*(ROOT / "envs").glob("*.py"), *(ROOT / "paragym" / "tasks").glob("*.py")]:
        text = path.read_text()
        assert not re.search(r"_v2_rules|_defaults\b|\bversion = \d", text), path


def test_an_env_refuses_an_unknown_argument_by_name():
    for row in registry.newest():
        with pytest.raises(TypeError, match="'bogus'"):
            gym.make(row, bogus=1)
        with pytest.raises(TypeError, match="'bogus'"):
            gym.make_vec(row, num_envs=2, vectorization_mode="vector_entry_point", bogus=1)


# --- success decided once -------------------------------------------------------------------------------------------


#: one Orthoglide episode that ends in four zero actions, told by the single env, the vector env and the
#: leaderboard's evaluate_episode; argv[1] breaks success in one place first: "decide" (the compiled transition's
#: one function, with numba's JIT off) or "evaluate" (the task's report of it)
SUCCESS_EVERYWHERE = r"""
import json, sys
import gymnasium as gym
import numpy as np
import paragym.tasks.orthoglide_step as step_module
from paragym.baselines.leaderboard import evaluate as board
from paragym.baselines.policies import get_policy
from paragym.tasks.base import Evaluation
from paragym.tasks.orthoglide import circle_task
from paragym.tasks.orthoglide_task import TASK

if sys.argv[1] == "decide":
    honest = step_module.decide
    step_module.decide = lambda k, last, failed, *bound: not honest(k, last, failed, *bound)
if sys.argv[1] == "evaluate":
    real = type(TASK).evaluate
    def broken(self, state, params, world):
        ev = real(self, state, params, world)
        return Evaluation(~ev.success, ev.failure, ev.numbers)
    type(TASK).evaluate = broken
env_id, short = "paragym/Orthoglide2PRRKappa-v1", circle_task((0.1, 0.55), 0.4, 0.2, steps=4)
env = gym.make(env_id, scenario=short)
env.reset(seed=0)
while True:
    *_, terminated, truncated, info = env.step(np.zeros(1, np.float32))
    if terminated or truncated:
        break
venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", scenario=short)
venv.reset(seed=0)
for _ in range(4):
    *_, vinfo = venv.step(np.zeros((2, 1), np.float32))
board._ENVS[env_id] = gym.make(env_id, scenario=short)
row = board.evaluate_episode(get_policy(env_id, "zero"), 0, 0)
print(json.dumps([info["is_success"], bool(vinfo["is_success"][0]), row.success]))
"""


def _success_everywhere(broken: str, jit: bool) -> dict[str, list[bool]]:
    """The honest and the ``broken`` outcome of :data:`SUCCESS_EVERYWHERE`, each in a process of its own."""
    import json
    import os
    import subprocess
    import sys

    env = {**os.environ, **({} if jit else {"NUMBA_DISABLE_JIT": "1"})}
    outcome = {}
    for mode in ("honest", broken):
        proc = subprocess.run([sys.executable, "-c", SUCCESS_EVERYWHERE, mode], capture_output=True, text=True,
                              env=env, timeout=600)
        assert proc.returncode == 0, proc.stderr[-3000:]
        outcome[mode] = json.loads(proc.stdout.strip().splitlines()[-1])
    return outcome


@pytest.mark.slow
def test_success_is_decided_in_one_place():
    """Break the Orthoglide's ``evaluate`` in its one place: the single env, the vector env and the
    leaderboard's episode all report the broken success."""
    outcome = _success_everywhere("evaluate", jit=True)
    assert outcome["evaluate"] == [not s for s in outcome["honest"]], outcome


def test_success_is_decided_by_one_function_of_the_transition():
    """The decision itself is one function (``paragym.tasks.<task>_step.decide``), which the compiled transition
    calls: with numba's JIT off, replacing it in that one place changes the single env's, the vector env's and
    the leaderboard's success alike."""
    outcome = _success_everywhere("decide", jit=False)
    assert outcome["decide"] == [not s for s in outcome["honest"]], outcome


# --- one lifecycle, every id and fidelity ----------------------------------------------------------------------------


def _short_scenario(task: str):
    """A scenario that ends within a few zero actions."""
    from paragym.sim.obstacles import Capsule
    from paragym.tasks.capaman import CaPaManScenario
    from paragym.tasks.orthoglide import circle_task
    from paragym.tasks.tripod import TripodScenario

    if task == "capaman":  # the three T.P.s the same: each step reaches the next one (a post every id takes)
        point = (1.4, 1.4, 1.4)
        return CaPaManScenario("same", (Capsule((0.1, 0.1, 0.04), 0.005, 0.07),), (point, point, point))
    if task == "orthoglide":
        return circle_task((0.1, 0.55), 0.4, 0.2, steps=4)
    if task == "tripod":
        return TripodScenario("short", distance=0.1)
    return "paper"  # the hybrid's path has 100 samples


#: the dynamic fidelity of every id, the kinematic of one id per kinematic fidelity (tests/env_ids.py)
CASES = [(row.id, fidelity) for row in registry.ROWS for fidelity in ("kinematic", "dynamic")
         if fidelity == "dynamic" or row.id in KINEMATIC_IDS]


def _make(env_id: str, fidelity: str, **kwargs) -> gym.Env:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gym.make(env_id, fidelity=fidelity, scenario=_short_scenario(registry.task_of(env_id)),
                        disable_env_checker=True, **kwargs)


@pytest.mark.parametrize("env_id, fidelity", CASES)
def test_one_lifecycle(env_id, fidelity):
    env = _make(env_id, fidelity)
    zero = np.zeros(env.action_space.shape, np.float32)
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        env.unwrapped.step(zero)  # (Gymnasium's OrderEnforcing wrapper says it first)
    with pytest.raises(ValueError, match="unknown key 'bogus'"):
        env.reset(seed=0, options={"bogus": 1})
    env.reset(seed=0)
    for _ in range(200):
        terminated = env.step(zero)[2]
        if terminated:
            break
    assert terminated, "the short scenario ends"
    with pytest.raises(RuntimeError, match="the episode has ended"):
        env.step(zero)
    env.reset(seed=1, options={"scenario": _short_scenario(registry.task_of(env_id))})
    env.step(zero)  # a reset starts the next one
    env.close()
    env.close()  # closing twice is harmless
    for call in (lambda: env.step(zero), lambda: env.reset(seed=0)):
        with pytest.raises(RuntimeError, match="is closed: make a new env"):
            call()


@pytest.mark.parametrize("env_id, fidelity", CASES)
def test_the_reward_is_the_sum_of_its_named_terms(env_id, fidelity):
    """Every step's info holds the reward's terms under stable names (``reward_<name>``, the task's
    ``REWARD_TERMS``), as Gymnasium's MuJoCo v5 envs do, and the reward is their sum."""
    env = _make(env_id, fidelity)
    rng = np.random.default_rng(0)
    _, info = env.reset(seed=2)
    names = {k for k in info if k.startswith("reward_")}
    assert len(names) >= 2, info.keys()
    for _ in range(200):
        _, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        assert {k for k in info if k.startswith("reward_")} == names
        assert abs(sum(info[k] for k in names) - reward) <= 1e-12 * max(1.0, abs(reward)), (info, reward)
        if terminated or truncated:
            break
    env.close()


@pytest.mark.parametrize("env_id, fidelity", CASES)
def test_details_and_numbers_name_different_things(env_id, fidelity):
    """The single env's info is a task's details with its numbers added: a name in both would lose one."""
    env = _make(env_id, fidelity)
    env.reset(seed=4)
    u = env.unwrapped
    details = u.task.details(u.state, u.params, u.world, 0)
    numbers = u.task.evaluate(u.state, u.params, u.world).numbers
    assert details and not set(details) & set(numbers), (sorted(details), sorted(numbers))
    assert not set(details) & {"is_success", "failure"}
    env.close()


@pytest.mark.parametrize("env_id, fidelity", CASES)
@pytest.mark.slow
def test_a_copy_is_independent_or_refused(env_id, fidelity):
    env = _make(env_id, fidelity)
    env.reset(seed=3)
    u = env.unwrapped
    zero = np.zeros(env.action_space.shape, np.float32)
    if u.world is not None and getattr(u.world, "live", True):  # a PyBullet client of its own: refused
        for copier in (copy.deepcopy, pickle.dumps):
            with pytest.raises(TypeError, match="cannot be copied or pickled"):
                copier(u)
    else:
        twin = copy.deepcopy(u)
        again = pickle.loads(pickle.dumps(u))
        a, b, c = u.step(zero), twin.step(zero), again.step(zero)
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[0], c[0])
        twin.close()
        again.close()
        u.step(zero) if not a[2] else u.reset(seed=3)  # the original lives on after its copies are closed
    env.close()


def test_the_vector_env_refuses_unknown_options_and_a_closed_env():
    venv = gym.make_vec("paragym/HybridSingularityFree-v2", num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match="unknown key 'bogus'"):
        venv.reset(seed=0, options={"bogus": 1})
    venv.reset(seed=0)
    venv.close()
    with pytest.raises(RuntimeError, match="is closed"):
        venv.reset(seed=0)


def test_kernels_take_named_tuples_not_dozens_of_arguments():
    """Every numba kernel of the task layer (and the tripod's drive) takes at most 14 parameters: a state's
    arrays travel as one tuple their state names (``KERNEL_FIELDS``, :mod:`paragym.kernels`), not as 30
    positional arguments."""
    import inspect

    from numba.core.registry import CPUDispatcher

    modules = [importlib.import_module(f"paragym.tasks.{t}{s}") for t in ("capaman", "hybrid", "orthoglide", "tripod")
               for s in ("_step", "_task", "_worlds")] + [importlib.import_module("paragym.sim.tripod_drive")]
    seen = {}
    for module in modules:
        for name, obj in vars(module).items():
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__:
                seen[f"{module.__name__}.{name}"] = len(inspect.signature(obj.py_func).parameters)
    assert len(seen) >= 10, seen
    assert max(seen.values()) <= 14, {k: v for k, v in seen.items() if v > 14}


@pytest.mark.parametrize("row", [r for r in registry.ROWS if r.task in {"capaman", "hybrid", "orthoglide", "tripod"}],
                         ids=lambda r: r.name)
def test_parameters_carry_the_rules_flags_not_a_version_number(row):
    """A version is its Rules' named flags: the parameters copy the flags the transition reads and hold no
    version number for a kernel to branch on."""
    from dataclasses import fields

    single = _cls(row.entry_point)
    params = single.task.Params.from_kwargs(single.rules)
    names = {f.name for f in fields(params)}
    assert "version" not in names, row.id
    flags = [f.name for f in fields(single.rules) if isinstance(getattr(single.rules, f.name), bool)]
    shared = [name for name in flags if name in names]
    assert shared, row.id  # each task's version flag reaches its parameters by name
    for name in shared:
        assert getattr(params, name) == getattr(single.rules, name), (row.id, name)


def test_no_transition_branches_on_a_version_number():
    for path in (ROOT / "paragym" / "tasks").glob("*.py"):
        assert not re.search(r"\bversion\s*(==|>=|<=|!=|>|<)\s*\d|\bversion\)", path.read_text()), path
