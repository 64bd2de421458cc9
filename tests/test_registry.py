"""The registry is the one place that says what an env id is: every row is whole and consistent."""

import importlib

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
    assert row.vector_entry_point is None or _load(row.vector_entry_point).single_class is single
    assert row.paper_scenario in row.scenarios and "random" in row.scenarios
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
    """Each task's scenario module has ``<Task>Scenario``, ``paper_scenario()`` and ``random_scenario(rng, ...)``,
    its step module ``<Task>State`` and ``<Task>Params``; the names of before 0.9 still work, with a warning."""
    import importlib
    import warnings

    import numpy as np

    modules = {"capaman": ("capaman", "CaPaMan"), "hybrid": ("hybrid", "Hybrid"),
               "orthoglide": ("orthoglide", "Orthoglide"), "tripod": ("mobile_tripod", "Tripod")}
    for task, (module, prefix) in modules.items():
        scenarios, step = (importlib.import_module(f"paragym.tasks.{module}{s}") for s in ("", "_step"))
        assert isinstance(scenarios.paper_scenario(), getattr(scenarios, f"{prefix}Scenario")), task
        assert callable(scenarios.random_scenario) and hasattr(step, f"{prefix}State") and \
            hasattr(step, f"{prefix}Params"), task
    from paragym.tasks import mobile_tripod, orthoglide

    assert isinstance(mobile_tripod.random_scenario(np.random.default_rng(0)), mobile_tripod.TripodScenario)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        assert orthoglide.Task is orthoglide.OrthoglideScenario
        assert mobile_tripod.DriveScenario is mobile_tripod.TripodScenario
    assert len(said) == 2 and all(w.category is DeprecationWarning for w in said)
    with pytest.raises(AttributeError):
        orthoglide.Nope  # noqa: B018
