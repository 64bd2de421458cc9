"""Dependencies point one way (DESIGN, issue 16): checked on the source, so that a new upward import fails."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: folder -> the paragym packages it must not import (the layers above it)
FORBIDDEN = {
    "paragym/mechanisms": ("paragym.sim", "paragym.envs", "paragym.planners", "paragym.baselines",
                           "paragym.validation", "pybullet", "gymnasium"),
    "paragym/sim": ("paragym.envs", "paragym.planners", "paragym.baselines", "paragym.validation"),
    "validation": ("paragym.planners", "paragym.envs", "paragym.baselines"),
}


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
    return names


@pytest.mark.parametrize("folder", sorted(FORBIDDEN))
def test_no_upward_import(folder):
    bad = []
    for path in sorted((ROOT / folder).glob("*.py")):
        for name in _imports(path):
            if any(name == f or name.startswith(f + ".") for f in FORBIDDEN[folder]):
                bad.append(f"{path.relative_to(ROOT)} imports {name}")
    assert not bad, "\n".join(bad)
