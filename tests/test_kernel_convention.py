"""The compiled kernels' convention (:mod:`paragym.kernels`): few parameters, and a state's arrays unpacked in the
order its ``KERNEL_FIELDS`` declares.

A kernel that takes a state's arrays unpacks the tuple by position; a name out of place there reads one array as
another and numba cannot tell (the arrays share a type). The names a kernel gives the tuple's elements must be the
declared fields, in their order (a trailing underscore allowed: a name kept apart from one the kernel calls)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the folders of the package whose modules may hold kernels
FOLDERS = ("paragym", "envs", "planners", "baselines", "validation")
#: the most parameters a kernel takes; more are gathered into tuples (a state's arrays, a geometry's constants)
MOST_PARAMETERS = 14
#: the variable a kernel gives a state's tuple -> the class that declares its fields: "arrays" is the state of
#: the module's own task, "drive" the tripod's drives
TUPLES = {"arrays": None, "drive": ("paragym.sim.tripod_drive", "DriveState")}


def _modules() -> list[tuple[str, ast.Module]]:
    out = []
    for folder in FOLDERS:
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts if folder == "paragym" else ("paragym", *parts))
            out.append((name.removesuffix(".__init__"), ast.parse(path.read_text())))
    return out


MODULES = _modules()


def _kernels(tree: ast.Module) -> list[ast.FunctionDef]:
    return [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)
            and any("jit" in ast.unparse(d) for d in n.decorator_list)]


def test_every_kernel_takes_at_most_14_parameters():
    many = [f"{name}.{k.name} ({len(k.args.args)})" for name, tree in MODULES for k in _kernels(tree)
            if len(k.args.args) + len(k.args.kwonlyargs) > MOST_PARAMETERS]
    assert sum(len(_kernels(tree)) for _, tree in MODULES) > 50  # the scan finds the kernels
    assert not many, f"kernels of more than {MOST_PARAMETERS} parameters: {many}"


def _fields(module: str, variable: str) -> tuple[str, ...]:
    if TUPLES[variable] is not None:
        owner, cls = TUPLES[variable]
        return getattr(importlib.import_module(owner), cls).KERNEL_FIELDS
    mod = importlib.import_module(module)
    states = [v for v in vars(mod).values() if isinstance(v, type) and v.__module__ == module
              and getattr(v, "KERNEL_FIELDS", ())]
    assert len(states) == 1, f"{module}: one state class with KERNEL_FIELDS expected, found {states}"
    return states[0].KERNEL_FIELDS


def _unpackings() -> list[tuple[str, str, int, list[str | None]]]:
    """Every place a kernel names a state tuple's elements: (module, variable, first index, the names)."""
    out = []
    for name, tree in MODULES:
        for kernel in _kernels(tree):
            for node in ast.walk(kernel):
                if not isinstance(node, ast.Assign) or len(node.targets) != 1:
                    continue
                target, value = node.targets[0], node.value
                if isinstance(value, ast.Name) and value.id in TUPLES and isinstance(target, ast.Tuple):
                    out.append((name, value.id, 0, [getattr(e, "id", None) for e in target.elts]))
                elif (isinstance(value, ast.Subscript) and isinstance(value.value, ast.Name)
                      and value.value.id in TUPLES and isinstance(value.slice, ast.Constant)
                      and isinstance(target, ast.Name)):
                    out.append((name, value.value.id, value.slice.value, [target.id]))
    return out


UNPACKINGS = _unpackings()


def test_the_scan_finds_every_tasks_unpacking():
    tasks = {m.split(".")[-1] for m, *_ in UNPACKINGS}
    assert {"capaman_step", "hybrid_step", "orthoglide_step", "tripod_step", "tripod_drive"} <= tasks


@pytest.mark.parametrize("module, variable, first, names", UNPACKINGS,
                         ids=[f"{m.split('.')[-1]}:{v}[{i}]" for m, v, i, _ in UNPACKINGS])
def test_a_kernel_unpacks_a_state_in_its_declared_order(module, variable, first, names):
    fields = _fields(module, variable)
    if first == 0:
        assert len(names) == len(fields), f"{module}: {variable} unpacked into {len(names)} names, " \
                                          f"its fields are {len(fields)}"
    assert tuple(n.rstrip("_") for n in names) == fields[first:first + len(names)], \
        f"{module}: {variable} unpacked as {names}, declared {fields[first:first + len(names)]}"


@pytest.mark.parametrize("task", ["capaman", "hybrid", "orthoglide", "tripod"])
def test_a_pickled_params_types_its_kernel_arguments_as_the_original(task):
    """The kernels' arguments a task's parameters make once (``kernel_args``) hold read-only arrays, so that numba
    compiles each kernel for one signature. A pickle (a process pool's job, a Ray task, a deep copy) that carried
    them would bring them back writable: every process it reaches would compile the task's kernels a second time
    (9 s for the hybrid's step on a fresh install)."""
    import copy
    import pickle

    import gymnasium as gym
    import numba

    from paragym import registry

    env_id = next(r.id for r in registry.rows() if r.task == task and r.rung is None)
    params = gym.make(env_id).unwrapped.params
    params.kernel_args  # noqa: B018 (made, and cached on the parameters, before the copy)
    for copied in (pickle.loads(pickle.dumps(params)), copy.deepcopy(params)):
        assert numba.typeof(copied.kernel_args) == numba.typeof(params.kernel_args)
