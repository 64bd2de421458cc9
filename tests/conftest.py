"""Fixtures shared by several test modules."""

import pytest

from paragym.planners import RrtGaPlanner
from paragym.tasks.capaman import paper_scenario


@pytest.fixture(scope="session")
def paper_result():
    """The RRT + GA plan of the CaPaMan paper scenario, seed 0 (planned once per test session)."""
    planner = RrtGaPlanner(seed=0)
    result = planner.solve(paper_scenario())
    planner.close()
    return result
