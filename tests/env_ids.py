"""The env ids the per-id tests run on (imported by the test modules; pytest puts this folder on the path).

``KINEMATIC_IDS``: one id per kinematic fidelity: an id whose registry row
says ``kinematic_as`` (its kinematic fidelity is that id's, bit for bit, tested in ``test_registry.py``) is left
out of the tests that exercise the kinematic fidelity alone. ``STEP_IDS``: of those, one rung per ladder where the
rungs differ in their generator's knobs alone (the same rules but the rung, the same spaces): the tests of the
transition and its spaces (``test_properties.py``) run on it; each rung's generator is tested by its ladder's
tests."""

from __future__ import annotations

import dataclasses
import importlib

import paragym
from paragym import registry

KINEMATIC_IDS = sorted(r.id for r in registry.rows() if r.id in paragym.ENVIRONMENTS and r.kinematic_as is None)


def _step_key(env_id: str) -> tuple:
    """What decides an id's transition and spaces: its task, its rules but the rung's knobs, its spaces."""
    module, name = registry.row(env_id).entry_point.split(":")
    env = getattr(importlib.import_module(module), name)()
    rules = env.rules
    if getattr(rules, "rung", None) is not None:
        rules = dataclasses.replace(rules, rung=type(rules.rung))
    spaces = tuple((s.shape, s.dtype.str, s.low.tobytes(), s.high.tobytes())
                   for s in (env.observation_space, env.action_space))
    key = (registry.row(env_id).task, rules, spaces)
    env.close()
    return key


def _one_per_step(ids: list[str]) -> list[str]:
    seen: dict[tuple, str] = {}
    for row in registry.rows():  # a ladder's easiest rung first
        if row.id in ids:
            seen.setdefault(_step_key(row.id), row.id)
    return sorted(seen.values())


STEP_IDS = _one_per_step(KINEMATIC_IDS)
