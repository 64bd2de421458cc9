"""The grid shortest-path planner: through the task points, collision-free in PyBullet."""

import numpy as np
import pytest

from paragym.planners import GridPathPlanner, PlanningError, Policy
from paragym.planners.grid_path import GridPathPolicy
from paragym.sim.capaman_scene import CaPaManScene
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


def test_field_leads_from_any_free_cell_down_its_shortest_path_to_each_task_point():
    """GridField.next_waypoint is Dijkstra's tree toward the target: each step from a free cell
    shortens the free path left by the joint distance moved, and ends at the T.P.'s own cell."""
    f = GridPathPlanner().field(paper_scenario())
    rng = np.random.default_rng(0)
    for target in range(3):
        reachable = f.free_idx[np.isfinite(f.dist[target, f.free_idx])]
        for node in rng.choice(reachable, 20, replace=False):
            steps = 0
            while node != f.entry[target]:
                nxt = np.flatnonzero(np.all(f.points == f.next_waypoint(f.points[node], target), axis=1))[0]
                moved = np.linalg.norm(f.points[nxt] - f.points[node])
                assert f.dist[target, nxt] == pytest.approx(f.dist[target, node] - moved)
                node, steps = nxt, steps + 1
                assert steps < len(f.points)
            np.testing.assert_array_equal(f.next_waypoint(f.points[node], target), f.tp[target])


def test_field_paths_from_random_free_cells_are_clear_in_pybullet():
    """What an expert queried off its own path must give: from cells the tour never visits, the
    field's way to each T.P. is collision-free for PyBullet, the judge."""
    from paragym.trajectories import JointPath

    scenario = paper_scenario()
    f = GridPathPlanner().field(scenario)
    scene = CaPaManScene()
    scene.set_obstacles(scenario.obstacles)
    rng = np.random.default_rng(2)
    for target in range(3):
        reachable = f.free_idx[np.isfinite(f.dist[target, f.free_idx])]
        for node in rng.choice(reachable, 4, replace=False):
            alpha, points = f.points[node], [f.points[node]]
            while not np.array_equal(alpha, f.tp[target]):
                alpha = f.next_waypoint(alpha, target)
                points.append(alpha)
                assert len(points) < len(f.points), "the field goes round in circles"
            dense = JointPath(np.array(points), (0, len(points) - 1)).densify(np.radians(0.5))
            clear = np.array([(scene.set_configuration(a), scene.clearance()[0])[1] for a in dense])
            assert clear.min() > 0, f"a collision on the way from cell {node} to T.P.{target + 1}"
    scene.close()


def test_field_policy_completes_the_tour_in_the_env():
    import gymnasium as gym

    import paragym  # noqa: F401
    from paragym.planners import GridFieldPolicy

    env = gym.make("paragym/CaPaManCollisionFree-v1")
    policy = GridFieldPolicy(max_joint_step=env.unwrapped.max_joint_step)
    assert isinstance(policy, Policy)
    from paragym.rollout import run_episode

    for seed in range(3):
        assert run_episode(env, policy, seed).success
