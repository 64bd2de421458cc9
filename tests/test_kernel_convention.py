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


def _module_constants(tree: ast.Module) -> dict[str, object]:
    """The module's top-level names bound to a bool or int literal (numba freezes them as literals)."""
    out: dict[str, object] = {}
    for node in tree.body:
        if not isinstance(node, ast.Assign):
            continue
        for target in node.targets:
            pairs = ([(target, node.value)] if isinstance(target, ast.Name) else
                     list(zip(getattr(target, "elts", []), getattr(node.value, "elts", []), strict=False)))
            for name, value in pairs:
                if isinstance(name, ast.Name) and isinstance(value, ast.Constant) \
                        and isinstance(value.value, (bool, int)):
                    out[name.id] = value.value
    return out


def _literal(arg: ast.expr, constants: dict[str, object]) -> str | None:
    """What numba types ``arg`` as a literal, or None: a bool or int constant, or a module-level one."""
    if isinstance(arg, ast.UnaryOp) and isinstance(arg.operand, ast.Constant):
        return ast.unparse(arg)
    if isinstance(arg, ast.Constant) and isinstance(arg.value, (bool, int)):
        return repr(arg.value)
    if isinstance(arg, ast.Name) and arg.id in constants:
        return repr(constants[arg.id])
    return None


def _kernel_arguments() -> dict[str, dict[int, set[str]]]:
    """Each kernel ("module.name") -> each parameter's position -> the forms its callers give it: a literal's
    value, "omitted" (its default), or "typed" (a variable, or any call from Python, which numba types by value
    and never as a literal)."""
    kernels = {f"{m}.{k.name}": k for m, tree in MODULES for k in _kernels(tree)}
    by_name: dict[str, list[str]] = {}
    for full in kernels:
        by_name.setdefault(full.rsplit(".", 1)[1], []).append(full)

    def resolve(module: str, node: ast.expr) -> str | None:
        name = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else None
        found = by_name.get(name or "", [])
        if f"{module}.{name}" in found:
            return f"{module}.{name}"
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            found = [f for f in found if f.rsplit(".", 2)[-2] == node.value.id]
        return found[0] if len(found) == 1 else None

    forms: dict[str, dict[int, set[str]]] = {k: {} for k in kernels}
    for module, tree in MODULES:
        constants = _module_constants(tree)
        inside = {id(n) for k in _kernels(tree) for n in ast.walk(k)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and id(node) in inside:
                kernel = resolve(module, node.func)
                if kernel is None:
                    continue
                params = kernels[kernel].args.args
                given = [_literal(a, constants) or "typed" for a in node.args]
                given += ["omitted"] * (len(params) - len(given))
                for kw in node.keywords:
                    given[[p.arg for p in params].index(kw.arg)] = _literal(kw.value, constants) or "typed"
                for position, form in enumerate(given):
                    forms[kernel].setdefault(position, set()).add(form)
        for node in ast.walk(tree):  # a kernel named outside the kernels: called from Python
            if id(node) in inside or not isinstance(node, (ast.Name, ast.Attribute)):
                continue
            kernel = resolve(module, node)
            if kernel is not None:
                for position in range(len(kernels[kernel].args.args)):
                    forms[kernel].setdefault(position, set()).add("typed")
    return forms


#: (kernel, argument) compiled for a literal beside a typed value on purpose, and why
ON_PURPOSE = {("paragym.mechanisms.geometry._jacobi_lanes", 3): "the hybrid's n = 6 known to the compiler unrolls "
                                                                "its loops, 1.3x faster"}


def test_a_kernel_is_compiled_for_one_kind_of_each_argument():
    """numba types a literal argument of a call between kernels (``True``, ``0``, a module-level constant, an
    omitted default) as a type of its own: a kernel that is also called with a variable, from Python or from
    another kernel, is compiled once for each, seconds of a fresh install's first run apiece. Such a call passes
    a typed value instead (``np.bool_(True)``, ``np.int64(0)``, or a module constant made so)."""
    forms = _kernel_arguments()
    mixed = sorted(f"{kernel} argument {position}: {sorted(f)}" for kernel, by_position in forms.items()
                   for position, f in by_position.items() if len(f) > 1 and (kernel, position) not in ON_PURPOSE)
    assert forms["paragym.mechanisms.hybrid._stage_all"]  # the scan sees a kernel that only Python calls
    assert "typed" in forms["paragym.mechanisms.hybrid.k_solve"][10]  # and the calls between kernels
    assert not mixed, "kernels compiled for a literal and for a typed argument:\n" + "\n".join(mixed)


def _array_copies(kernel: ast.FunctionDef) -> list[str]:
    """Where ``kernel`` copies an array it made (``np.empty`` and the like) into a slice of another:
    ``out[0] = row``."""
    made = set()
    for node in ast.walk(kernel):
        if isinstance(node, ast.Assign):
            for target, value in ((t, v) for t in node.targets for t, v in (
                    zip(t.elts, node.value.elts, strict=False) if isinstance(t, ast.Tuple)
                    and isinstance(node.value, ast.Tuple) else [(t, node.value)])):
                if isinstance(target, ast.Name) and isinstance(value, ast.Call) \
                        and ast.unparse(value.func) in ("np.empty", "np.zeros", "np.ones", "np.full", "np.array"):
                    made.add(target.id)
    return [ast.unparse(node) for node in ast.walk(kernel) if isinstance(node, ast.Assign)
            and any(isinstance(t, ast.Subscript) for t in node.targets)
            and isinstance(node.value, ast.Name) and node.value.id in made]


def test_no_kernel_copies_an_array_into_a_slice():
    """An array copied into a slice (``pair[0] = p0``) makes numba compile a shape check whose error message
    formats tuples and strings: seconds of a fresh install's first run per kernel (``tests/test_compile.py``
    watches it compile for some). The kernels copy by element."""
    copies = [f"{name}.{k.name}: {c}" for name, tree in MODULES for k in _kernels(tree) for c in _array_copies(k)]
    assert not copies, copies
