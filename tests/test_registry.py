"""The registry is the one place that says what an env id is: every row is whole and consistent."""

import importlib
from pathlib import Path

import gymnasium as gym
import pytest

import paragym
from paragym import registry


def _load(entry: str):
    module, name = entry.split(":")
    return getattr(importlib.import_module(module), name)


@pytest.mark.parametrize("row", registry.ROWS, ids=lambda r: r.name)
def test_every_row_is_whole_and_registered_as_it_says(row):
    spec = gym.spec(row.id)
    assert (spec.entry_point, spec.max_episode_steps, spec.vector_entry_point) == \
        (row.entry_point, row.max_episode_steps, row.vector_entry_point)
    single = _load(row.entry_point)
    vector = None if row.vector_entry_point is None else _load(row.vector_entry_point)
    assert vector is None or (vector.task, vector.rules) == (single.task, single.rules)
    assert row.paper_scenario in row.scenario_names and "random" in row.scenario_names
    assert row.summary and len(row.summary) < 120


def test_versions_of_a_task_are_contiguous_and_share_models_only_backwards():
    for task in {r.task for r in registry.ROWS}:
        versions = [r.version for r in registry.rows_of(task)]
        assert versions == list(range(len(versions))), task
    for r in registry.ROWS:
        if r.models_from is not None:
            source = registry.row(r.models_from)
            assert source.task == r.task and source.version < r.version, r.id


def test_the_tables_derived_from_the_registry_and_its_checks():
    assert list(paragym.ENVIRONMENTS) == [r.id for r in registry.ROWS]
    assert registry.check_env_id("HybridSingularityFree-v2") == "paragym/HybridSingularityFree-v2"
    assert registry.first_version("paragym/MobileTripodOdometry-v2") == "paragym/MobileTripodOdometry-v0"
    with pytest.raises(ValueError, match="unknown env id"):
        registry.row("paragym/Nope-v0")


@pytest.mark.parametrize("row", registry.ROWS, ids=lambda r: r.name)
def test_every_registered_id_has_a_complete_bench(row):
    """What the CLI and the leaderboard know of a task comes from its bench (``paragym.baselines.tasks``);
    the check names what a bench lacks for an id."""
    from paragym.baselines.tasks import bench_of, missing

    bench = bench_of(row.id)
    assert bench.task == row.task
    assert missing(bench, row.id) == []


def test_an_incomplete_bench_is_named_part_by_part():
    import dataclasses

    from paragym.baselines.tasks import bench_of, missing

    bench = dataclasses.replace(bench_of("paragym/CaPaManCollisionFree-v1"), reference="nobody",
                                primary=("nothing", 2), reference_success=1.5)
    said = " ".join(missing(bench, "paragym/CaPaManCollisionFree-v1"))
    for part in ("'nothing'", "direction", "'nobody'", "success rate"):
        assert part in said


def test_every_task_module_speaks_one_vocabulary_and_answers_to_its_old_names():
    """One name per task across every layer: ``mechanisms/<task>.py``, ``tasks/<task>.py`` (the scenarios:
    ``<Task>Scenario``, ``SCENARIOS``, ``paper_scenario``, ``random_scenario``, ``validate_scenario``,
    ``resolve_scenario``, ``draw_scenarios``), ``tasks/<task>_step.py`` (the transition: ``RULES``,
    ``<Task>Params``, ``<Task>State``, ``<Task>Rules``), ``tasks/<task>_worlds.py`` (its PyBullet worlds),
    ``tasks/<task>_task.py`` (the contract, ``TASK``), ``sim/<task>_*.py``, ``envs/<task>.py`` and
    ``baselines/tasks/<task>.py``; no scenario, contract or env module of a task names a scenario function
    otherwise; the names of before
    0.9 still work, with a warning."""
    import importlib
    import inspect
    import re
    import warnings

    import numpy as np

    root = Path(__file__).resolve().parent.parent
    words = ("resolve", "draw", "validate", "paper", "random")
    for task in sorted({r.task for r in registry.ROWS}):
        prefix = {"capaman": "CaPaMan", "hybrid": "Hybrid", "orthoglide": "Orthoglide", "tripod": "Tripod"}[task]
        names = (f"paragym.mechanisms.{task}", f"paragym.tasks.{task}", f"paragym.tasks.{task}_step",
                 f"paragym.envs.{task}", f"paragym.baselines.tasks.{task}", f"paragym.tasks.{task}_task",
                 f"paragym.tasks.{task}_worlds")
        modules = [importlib.import_module(m) for m in names]
        assert list((root / "paragym" / "sim").glob(f"{task}_*.py")), task
        scenarios, step = modules[1], modules[2]
        for name in (f"{prefix}Scenario", "SCENARIOS", "paper_scenario", "random_scenario", "validate_scenario",
                     "resolve_scenario", "draw_scenarios"):
            assert hasattr(scenarios, name), (task, name)
        for name in ("RULES", f"{prefix}Params", f"{prefix}State", f"{prefix}Rules"):
            assert hasattr(step, name), (task, name)
        assert hasattr(modules[5], "TASK") and hasattr(modules[6], "DynamicWorld"), task
        assert isinstance(scenarios.paper_scenario(), getattr(scenarios, f"{prefix}Scenario")), task
        for module in (scenarios, step, modules[3], modules[5]):
            public = [n for n, f in vars(module).items() if inspect.isfunction(f) and not n.startswith("_")
                      and f.__module__ == module.__name__]
            odd = [n for n in public if re.match(rf"({'|'.join(words)})_", n)
                   and n not in ("resolve_scenario", "draw_scenarios", "validate_scenario", "paper_scenario",
                                 "random_scenario", "random_scenarios")]
            assert not odd, (module.__name__, odd)
    from paragym.tasks import orthoglide, tripod

    assert isinstance(tripod.random_scenario(np.random.default_rng(0)), tripod.TripodScenario)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        assert orthoglide.Task is orthoglide.OrthoglideScenario
        assert tripod.DriveScenario is tripod.TripodScenario
        assert orthoglide.draw_tasks is orthoglide.draw_scenarios
        import paragym.tasks.mobile_tripod as old

        assert old is tripod
    assert len(said) == 4 and all(w.category is DeprecationWarning for w in said), [str(w.message) for w in said]
    with pytest.raises(AttributeError):
        orthoglide.Nope  # noqa: B018


TWINS = [r for r in registry.ROWS if r.kinematic_as is not None]


def test_a_kinematic_twin_names_an_older_id_of_its_task_that_has_its_own():
    assert {r.name for r in TWINS} == {"MobileTripodOdometry-v3", *(f"{t}-{n}-v1" for t in
                                       ("MobileTripodOdometry", "Orthoglide2PRRKappa") for n in registry.RUNG_NAMES)}
    for r in TWINS:
        twin = registry.row(r.kinematic_as)
        assert (twin.task, twin.rung, twin.kinematic_as) == (r.task, r.rung, None) and twin.version < r.version, r.id


@pytest.mark.parametrize("row", TWINS, ids=lambda r: r.name)
def test_a_kinematic_twin_plays_its_twins_episodes_bit_for_bit(row):
    """What lets the tests of the kinematic fidelity alone run once for both: the same spaces, and whole episodes
    of every scenario and of five random draws (three played by the reference) the same observations, rewards,
    ends and numbers, in the single and the vector env."""
    import pickle

    import numpy as np

    from paragym.baselines.policies import get_policy
    from paragym.baselines.tasks import bench_of

    runs = []
    starts = [(name, 11) for name in row.scenario_names] + [("random", seed) for seed in range(12, 17)]
    for env_id in (row.id, row.kinematic_as):
        env = gym.make(env_id)
        vec = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
        rng = np.random.default_rng(7)
        out = [env.observation_space, env.action_space]
        for name, seed in starts:
            obs, info = env.reset(seed=seed, options={"scenario": name})
            out.append((obs, pickle.dumps(info["scenario"])))
            reference = get_policy(env_id, bench_of(env_id).reference).factory(env, seed) if seed > 13 else None
            if reference is not None:
                reference.reset(obs, info)
            term = trunc = False
            while not (term or trunc):
                action = rng.uniform(-1.2, 1.2, env.action_space.shape) if reference is None else \
                    reference.act(obs, info)
                obs, reward, term, trunc, info = env.step(action)
                out.append((obs, reward, term, trunc, {key: info[key] for key in sorted(info)
                                                       if isinstance(info[key], (float, int, bool, np.ndarray))}))
            out.append((info.get("is_success"), info.get("failure")))
        out.append(vec.reset(seed=[3, 4])[0])
        out.extend(vec.step(rng.uniform(-1.2, 1.2, vec.action_space.shape))[:4] for _ in range(50))
        env.close()
        vec.close()
        runs.append(out)
    assert len(runs[0]) == len(runs[1])
    for mine, theirs in zip(*runs, strict=True):
        np.testing.assert_equal(mine, theirs)
