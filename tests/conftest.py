"""Fixtures shared by several test modules."""

import sys
from pathlib import Path

import pytest

# the docs site's generator (docs/pages.py) is not part of the package: the tests of the pages import it from there
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))

from paragym.planners import RrtGaPlanner
from paragym.tasks.capaman import paper_scenario


@pytest.fixture(scope="session")
def paper_result():
    """The RRT + GA plan of the CaPaMan paper scenario, seed 0 (planned once per test session)."""
    planner = RrtGaPlanner(seed=0)
    result = planner.solve(paper_scenario())
    planner.close()
    return result


@pytest.fixture(scope="session")
def shared_folder(tmp_path_factory):
    """A folder every xdist worker of this session sees, and a lock on it: a worker that finds there what
    another stored (a leaderboard database, which runs only the episodes it lacks) does not run it again."""
    import contextlib
    import fcntl
    import os

    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "shared"
    folder.mkdir(exist_ok=True)

    @contextlib.contextmanager
    def locked(name: str):
        with open(folder / f"{name}.lock", "w") as handle:
            fcntl.flock(handle, fcntl.LOCK_EX)
            try:
                yield folder / name
            finally:
                fcntl.flock(handle, fcntl.LOCK_UN)

    return locked
