"""Every env's step time here and at another commit, alternating, pinned to one core.

A change to the shells or the kernels must leave no released env slower. This script checks out the commit
``REV`` in a temporary git worktree and times both trees in fresh processes, one after the other, ``--rounds``
times; each process imports paragym from its own tree (the package layout its ``pyproject.toml`` names,
whatever is installed), is pinned to one core and times each env through ``gym.make``'s wrappers over
pre-drawn uniform random actions, resets included, as the best of five runs of ``--steps`` steps. An env's
figure is the best over the rounds: the machine's load only ever adds time, so the least disturbed run is
the one to compare, and alternating the trees lets a slow minute fall on both. Only ids registered in both
trees are timed.

    python benchmarks/against.py REV [--rounds 3] [--steps 2000] [--env ID ...] [--dynamic] [--record]

``--dynamic`` adds each id's dynamic fidelity (a tenth of the steps). ``--record`` writes
``benchmarks/results/against.json`` for the speed page.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
REPEATS = 5


def use_tree(tree: Path) -> None:
    """Import ``paragym`` and its sub-packages from ``tree``'s folders (its ``[tool.setuptools.package-dir]``),
    ahead of any installed copy."""
    import importlib.abc
    import importlib.util

    dirs = tomllib.loads((tree / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    where = {name: tree / folder for name, folder in dirs.items()}

    class TreeFinder(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):  # noqa: ANN001, ANN201
            folder = where.get(name)
            if folder is None:
                return None
            return importlib.util.spec_from_file_location(name, folder / "__init__.py",
                                                          submodule_search_locations=[str(folder)])

    sys.meta_path.insert(0, TreeFinder())


def time_envs(ids: list[str], steps: int, dynamic: bool) -> dict[str, float]:
    """Microseconds per step of each id (and ``<id> dynamic``), best of :data:`REPEATS` runs."""
    import warnings

    import gymnasium as gym
    import numpy as np

    import paragym  # noqa: F401

    warnings.filterwarnings("ignore")
    out = {}
    for env_id in ids:
        for fidelity in ("kinematic", "dynamic") if dynamic else ("kinematic",):
            env = gym.make(env_id, fidelity=fidelity)
            n = steps if fidelity == "kinematic" else max(20, steps // 10)
            space = env.action_space
            actions = np.random.default_rng(0).uniform(space.low, space.high, (n, *space.shape)).astype(space.dtype)
            best = float("inf")
            for repeat in range(REPEATS):
                env.reset(seed=repeat)
                start = time.perf_counter()
                for action in actions:
                    _, _, terminated, truncated, _ = env.step(action)
                    if terminated or truncated:
                        env.reset()
                best = min(best, (time.perf_counter() - start) / n)
            env.close()
            out[env_id if fidelity == "kinematic" else f"{env_id} dynamic"] = best * 1e6
    return out


def _child(tree: Path, ids: list[str], steps: int, dynamic: bool) -> Any:
    result = subprocess.run([sys.executable, __file__, "--child", str(tree), "--steps", str(steps),
                             *(["--dynamic"] if dynamic else []), "--", *ids],
                            capture_output=True, text=True, check=True)
    return json.loads(result.stdout.strip().splitlines()[-1])


def _ids(tree: Path) -> list[str]:
    """The env ids ``tree`` registers."""
    return _child(tree, ["--list"], 0, False)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev", help="the commit to compare with (anything git rev-parse takes)")
    parser.add_argument("--rounds", type=int, default=3, help="alternations of the two trees")
    parser.add_argument("--steps", type=int, default=2000, help="steps of each timed run")
    parser.add_argument("--env", action="append", default=None, help="only this env id (repeatable)")
    parser.add_argument("--dynamic", action="store_true", help="time the dynamic fidelity too")
    from results_file import add_record_option, paragraph, record

    add_record_option(parser)
    if sys.argv[1:2] == ["--child"]:  # a timing process: the tree, then what to time
        child = argparse.ArgumentParser()
        child.add_argument("--child", type=Path, required=True)
        child.add_argument("--steps", type=int, required=True)
        child.add_argument("--dynamic", action="store_true")
        child.add_argument("ids", nargs="*")
        args = child.parse_args()
        if hasattr(os, "sched_setaffinity"):
            os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
        use_tree(args.child)
        if args.ids == ["--list"]:
            import paragym

            print(json.dumps(list(paragym.ENVIRONMENTS)))
            return
        print(json.dumps(time_envs(args.ids, args.steps, args.dynamic)))
        return
    args = parser.parse_args()
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))  # a killed run still removes its worktree
    commit = subprocess.run(["git", "rev-parse", "--short=12", args.rev], cwd=ROOT, capture_output=True, text=True,
                            check=True).stdout.strip()
    with tempfile.TemporaryDirectory(prefix="paragym-against-") as tmp:
        other = Path(tmp) / "tree"
        subprocess.run(["git", "worktree", "add", "--detach", str(other), commit], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            ids = [i for i in _ids(ROOT) if i in set(_ids(other))]
            if args.env:
                wanted = {e if e.startswith("paragym/") else f"paragym/{e}" for e in args.env}
                ids = [i for i in ids if i in wanted]
            before: dict[str, float] = {}
            after: dict[str, float] = {}
            for r in range(args.rounds):
                for tree, best in ((other, before), (ROOT, after)):
                    for key, us in _child(tree, ids, args.steps, args.dynamic).items():
                        best[key] = min(best.get(key, float("inf")), us)
                print(f"round {r + 1} of {args.rounds} done", flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(other)], cwd=ROOT, capture_output=True)
    rows = [[key, f"{before[key]:.2f}", f"{after[key]:.2f}", f"{before[key] / after[key]:.3f}"] for key in after]
    print(f"\n{'environment':48s} {commit + ' (us)':>20s} {'here (us)':>10s} {'speed-up':>9s}")
    for key, b, a, ratio in rows:
        print(f"{key:48s} {b:>20s} {a:>10s} {ratio:>9s}")
    print("speed-up: the other commit's time over this tree's (above 1: this tree is faster)")
    if args.record:
        record("against", f"Step time against {commit}", paragraph(__doc__, 1),
               ["environment", f"{commit} (us/step)", "this tree (us/step)", "speed-up"], rows, order=15,
               folder=args.record)


if __name__ == "__main__":
    main()
