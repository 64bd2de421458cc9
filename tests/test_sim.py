"""The PyBullet layer: the kinematic tree matches the analytic part frames,
clients are freed, and paper 000's grid test agrees with PyBullet."""

import os

import gymnasium as gym
import numpy as np
import pybullet as pb
import pytest

import paragym  # noqa: F401  (registers the envs)
from paragym.envs.capaman_scenarios import paper_scenario, random_scenario
from paragym.mechanisms import capaman
from paragym.sim import occupancy
from paragym.sim.capaman_model import CaPaManScene
from paragym.sim.client import PyBulletSim

G = capaman.DEFAULT_GEOMETRY


@pytest.fixture
def scene():
    s = CaPaManScene()
    yield s
    s.close()


def test_pybullet_links_sit_where_the_model_puts_the_parts(scene):
    rng = np.random.default_rng(0)
    alpha = rng.uniform(G.alpha_min, G.alpha_max, (40, 3))
    centres, quats = capaman.part_frames(alpha)
    names = [p.name for p in capaman.part_shapes()]
    for i, a in enumerate(alpha):
        tip = scene.set_configuration(a)
        np.testing.assert_allclose(tip, capaman.tool_tip(capaman.forward(a))[0], atol=1e-12)
        for j, name in enumerate(names):
            pos, q = scene.part_frame(name)
            np.testing.assert_allclose(pos, centres[i, j], atol=1e-6)  # PyBullet keeps float32-ish poses
            assert min(np.abs(q - quats[i, j]).max(), np.abs(q + quats[i, j]).max()) < 1e-6


def test_close_frees_the_client():
    """200 environments made and closed leave no PyBullet connection behind."""
    ids = []
    for _ in range(200):
        env = gym.make("paragym/CaPaManCollisionFree-v0", scenario="paper")
        env.reset(seed=0)
        ids.append(env.unwrapped.scene.sim._client)
        env.close()
        env.close()  # idempotent
    assert not any(pb.isConnected(physicsClientId=i) for i in set(ids))
    assert len(set(ids)) < 5  # the same few ids are reused: nothing leaked


def test_gui_without_display_is_refused(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    if os.name != "posix":
        pytest.skip("the DISPLAY check is for X11")
    with pytest.raises(RuntimeError, match="display"):
        PyBulletSim(gui=True)


def test_clearance_sees_every_part(scene):
    """The plate and a crank are caught too, not only the tool."""
    from paragym.sim.obstacles import Box

    scene.set_configuration(G.alpha_home)
    scene.set_obstacles([Box((0.1, 0.0, G.a + G.h), (0.02, 0.02, 0.02))])
    d, part = scene.clearance()
    assert d < 0 and part == "plate"
    crank_tip = G.r_f * G.e[0] - (G.c / 2) * G.u[0] + G.a * np.array([0, 0, 1.0])
    scene.set_obstacles([Box(tuple(crank_tip - [0, 0, 0.02]), (0.005, 0.005, 0.005))])
    d, part = scene.clearance()
    assert d < 0 and part == "leg1_crank_a"


@pytest.mark.parametrize("seed", [None, 0, 1, 2])
def test_grid_test_agrees_with_pybullet(scene, seed):
    """Eq 2 on Psi against PyBullet's exact distance, on random configurations:
    a grid collision is never farther than 1.6 cells from an obstacle, and a
    penetration deeper than the cluster spacing is never missed."""
    scenario = paper_scenario() if seed is None else random_scenario(np.random.default_rng(seed), scene)
    eps = 0.005
    grid = occupancy.OccupancyGrid.from_obstacles(scenario.obstacles, resolution=eps)
    clusters = occupancy.cluster_points(spacing=0.005)
    rng = np.random.default_rng(10)
    alpha = rng.uniform(G.alpha_min, G.alpha_max, (1500, 3))
    grid_hit = occupancy.grid_collision(alpha, grid, clusters)
    scene.set_obstacles(scenario.obstacles)
    dist = np.array([(scene.set_configuration(a), scene.clearance()[0])[1] for a in alpha])
    assert grid_hit.any() and (~grid_hit).any()
    assert dist[grid_hit].max() <= 1.6 * eps
    assert dist[~grid_hit].min() >= -clusters.spacing
    # Theta over the reachable parts only equals eq 2 over all parts.
    theta, axis = occupancy.joint_matrix(grid, clusters, 9)
    full = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    np.testing.assert_array_equal(theta.ravel(), occupancy.grid_collision(full, grid, clusters))


def test_swept_boxes_hold_every_part_over_the_joint_range():
    lo, hi = capaman.swept_part_boxes(G, 9)
    rng = np.random.default_rng(5)
    alpha = rng.uniform(G.alpha_min, G.alpha_max, (20000, 3))
    centres, _ = capaman.part_frames(alpha)
    assert np.all(centres >= lo) and np.all(centres <= hi)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_clearance_query_on_the_parts_that_can_reach_equals_the_full_query(scene, seed):
    scenario = random_scenario(np.random.default_rng(seed), scene)
    scene.set_obstacles(scenario.obstacles)
    assert len(scene._query_links) < len(capaman.part_shapes())
    rng = np.random.default_rng(seed)
    for a in rng.uniform(G.alpha_min, G.alpha_max, (300, 3)):
        scene.set_configuration(a)
        full = scene.sim.clearance(scene.ROBOT, ["obstacles"], scene.clearance_cap)
        assert scene.clearance() == full
