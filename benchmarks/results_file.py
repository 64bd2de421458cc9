"""What a benchmark writes for the speed page: one JSON file per table, saying what produced it.

``record(name, ...)`` writes ``benchmarks/results/<name>.json``: the table's
title, its one paragraph, the command that printed it, the date, the machine
(:func:`paragym.machine.describe`), the commit (with ``+dirty`` when the tree
had changes) and the rows. ``python docs/build.py`` makes ``docs/speed.md``
from these files (``docs/pages.py``); nobody types a figure
into the page.
"""

from __future__ import annotations

import json
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"


def _commit() -> str:
    root = Path(__file__).resolve().parent.parent
    try:
        head = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=root, capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return head + ("+dirty" if dirty else "")


def machine() -> str:
    """One line: the CPU, its cores, the Python and numpy of this run."""
    import os
    import platform

    import numpy as np

    from paragym.machine import describe

    facts = describe()
    cpu = facts.get("cpu", {}).get("model") or platform.processor() or platform.machine()
    return f"{cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, numpy {np.__version__}"


def add_record_option(parser: Any) -> None:
    """``--record [DIR]``: write the table's result file to DIR (default ``benchmarks/results``, the speed page's)."""
    parser.add_argument("--record", nargs="?", const=str(RESULTS), default=None, metavar="DIR",
                        help="write the table's result file for the speed page (default folder: benchmarks/results)")


def paragraph(doc: str, index: int = 0) -> str:
    """Paragraph ``index`` of a script's docstring, on one line."""
    return " ".join(doc.split("\n\n")[index].split())


def record(name: str, title: str, paragraph: str, columns: list[str], rows: list[list[Any]],
           command: str | None = None, order: int = 50, folder: str | Path = RESULTS,
           figure: str | None = None, source: str | None = None) -> Path:
    """Write ``<folder>/<name>.json`` (``order``: where the table goes on the page, lowest first; ``figure``: a
    picture under docs/ shown below it; ``source``: what else produced it, e.g. the engines' versions)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"{name}.json"
    out.write_text(json.dumps({
        "name": name, "title": title, "paragraph": " ".join(paragraph.split()), "order": order,
        "command": command or "python " + " ".join([f"benchmarks/{Path(sys.argv[0]).name}", *sys.argv[1:]]),
        "date": datetime.now(UTC).strftime("%Y-%m-%d"), "machine": machine(), "commit": _commit(),
        "columns": columns, "rows": [[str(c) for c in r] for r in rows],
        **({"figure": figure} if figure else {}), **({"source": source} if source else {})}, indent=1) + "\n")
    print(f"wrote {out}")
    return out


def engine_versions() -> str:
    """The physics engines' versions installed here (MuJoCo's where it is), for a result file's ``source``."""
    from importlib.metadata import PackageNotFoundError, version

    out = []
    for name, package in (("PyBullet", "pybullet"), ("MuJoCo", "mujoco")):
        try:
            out.append(f"{name} {version(package)}")
        except PackageNotFoundError:
            pass
    return ", ".join(out)
