"""The grid shortest-path planner: through the task points, collision-free in PyBullet."""

import numpy as np
import pytest

from paragym.planners import GridPathPlanner, PlanningError, Policy
from paragym.planners.grid_path import GridPathPolicy
from paragym.sim.capaman_model import CaPaManScene
from paragym.sim.obstacles import Box
from paragym.tasks.capaman import CaPaManScenario, paper_scenario


def test_paper_plan_visits_the_task_points_in_order_without_collision():
    scenario = paper_scenario()
    path = GridPathPlanner().plan(scenario)
    tp = scenario.alpha
    np.testing.assert_array_equal(path.waypoints[list(path.via_indices)], tp[[0, 1, 2, 0]])
    scene = CaPaManScene()
    scene.set_obstacles(scenario.obstacles)
    dense = path.densify(np.radians(0.5))
    dist = np.array([(scene.set_configuration(a), scene.clearance()[0])[1] for a in dense])
    assert dist.min() > 0, "PyBullet, the judge, finds a collision on the planned path"
    straight = sum(np.linalg.norm(tp[j] - tp[i]) for i, j in ((0, 1), (1, 2), (2, 0)))
    assert straight < path.length < 2.5 * straight
    scene.close()


def test_policy_protocol():
    assert isinstance(GridPathPolicy(), Policy)


def test_disconnected_task_points_raise():
    paper = paper_scenario()
    # a wall the tool cannot pass, between T.C.1 and the other two
    wall = Box((0.0, 0.012, 0.05), (0.08, 0.004, 0.05))
    scenario = CaPaManScenario("walled", (wall,), paper.task_points, paper.task_configs)
    with pytest.raises(PlanningError, match="not connected"):
        GridPathPlanner(points_per_axis=19).plan(scenario)
