"""Dependencies point one way (DESIGN, issue 16), checked on the source so that a new upward import fails.

Every import counts, at module level or inside a function: a lazy import that
dodges a cycle is still an edge of the graph, so it shows as an upward import
or a cycle here.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: source folder -> the package it installs as (pyproject's package-dir)
FOLDERS = {"paragym": "paragym", "envs": "paragym.envs", "planners": "paragym.planners",
           "baselines": "paragym.baselines", "validation": "paragym.validation", "models": "paragym.models"}
#: the layers, bottom first. A module imports from its own layer's package or from lower layers only;
#: packages that share a layer (envs, planners, validation) do not import each other.
LAYERS = [
    ("paragym.registry", "paragym.machine"),  # one row per env id; what results depend on: every layer may read them
    ("paragym", "paragym.units", "paragym.trajectories", "paragym.rollout", "paragym.kernels"),  # plain data
    ("paragym.mechanisms",),  # the papers' math
    ("paragym.sim",),  # PyBullet
    ("paragym.tasks",),  # each task's scenario: dataclass, validation, the paper's case, the random generator
    ("paragym.envs", "paragym.planners", "paragym.validation"),
    ("paragym.plots", "paragym.models"),
    ("paragym.baselines",),
    ("paragym.cli",),
]
EXTERNAL = {  # third-party imports a layer must not make
    "paragym.mechanisms": ("pybullet", "gymnasium"),
    "paragym.sim": ("gymnasium",),
    "paragym.tasks": ("gymnasium",),
}


def _modules() -> dict[str, Path]:
    out = {}
    for folder, package in FOLDERS.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = path.relative_to(ROOT / folder).with_suffix("")
            parts = [p for p in rel.parts if p != "__init__"]
            out[".".join([package, *parts])] = path
    return out


MODULES = _modules()


def _imports(path: Path) -> set[str]:
    """The paragym modules a file imports (``from paragym.x import y`` names
    paragym.x.y when that is a module), and third-party top-level names."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for a in node.names:
                sub = f"{node.module}.{a.name}"
                names.add(sub if sub in MODULES else node.module)
    return names


def _layer(module: str) -> tuple[int, str]:
    """(rank, package) of the longest layer prefix of ``module``."""
    best = (-1, "")
    for rank, packages in enumerate(LAYERS):
        for p in packages:
            if (module == p or module.startswith(p + ".") and p != "paragym") and len(p) > len(best[1]):
                best = (rank, p)
    if best[0] < 0:
        raise AssertionError(f"{module} is in no layer: add it to LAYERS")
    return best


def test_every_module_is_in_a_layer():
    for module in MODULES:
        _layer(module)


def test_no_upward_or_sideways_import():
    bad = []
    for module, path in MODULES.items():
        rank, package = _layer(module)
        for name in _imports(path):
            if name.split(".")[0] in EXTERNAL.get(package, ()):
                bad.append(f"{module} imports {name}")
            if name != "paragym" and not name.startswith("paragym."):
                continue
            their_rank, their_package = _layer(name)
            if their_rank > rank or (their_rank == rank and their_package != package):
                bad.append(f"{module} ({package}) imports {name} ({their_package})")
    assert not bad, "\n".join(sorted(bad))


def test_no_import_cycle():
    graph = {m: sorted(n for n in _imports(p) if n in MODULES and n != m) for m, p in MODULES.items()}
    state: dict[str, int] = {}  # 1: on the stack, 2: done
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in graph[m]:
            if state.get(n) == 1:
                raise AssertionError("import cycle: " + " -> ".join([*stack[stack.index(n):], n]))
            if n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m)


def test_the_checks_see_a_lazy_upward_import(tmp_path):
    """The checker itself: a function-level import of an env from a mechanism is found."""
    src = tmp_path / "m.py"
    src.write_text("def f():\n    from paragym.envs.capaman import CaPaManCollisionFreeEnv\n")
    assert "paragym.envs.capaman" in _imports(src)
    assert _layer("paragym.envs.capaman")[0] > _layer("paragym.mechanisms.capaman")[0]


def test_only_the_sim_wrapper_calls_pybullet():
    """Every PyBullet call goes through paragym.sim.client (bodies by name)."""
    bad = [m for m, path in MODULES.items() if m != "paragym.sim.client" and "pybullet" in _imports(path)]
    assert not bad, bad
