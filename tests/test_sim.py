"""The PyBullet layer: the kinematic tree matches the analytic part frames,
clients are freed, and paper 000's grid test agrees with PyBullet."""

import os

import gymnasium as gym
import numpy as np
import pybullet as pb
import pytest

import paragym  # noqa: F401  (registers the envs)
from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import quat_to_matrix
from paragym.sim import capaman_clearance, capaman_grid
from paragym.sim.capaman_scene import CaPaManScene
from paragym.sim.client import PyBulletSim
from paragym.sim.obstacles import Box
from paragym.tasks.capaman import paper_scenario, random_scenario

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
    grid = capaman_grid.OccupancyGrid.from_obstacles(scenario.obstacles, resolution=eps)
    clusters = capaman_grid.cluster_points(spacing=0.005)
    rng = np.random.default_rng(10)
    alpha = rng.uniform(G.alpha_min, G.alpha_max, (1500, 3))
    grid_hit = capaman_grid.grid_collision(alpha, grid, clusters)
    scene.set_obstacles(scenario.obstacles)
    dist = np.array([(scene.set_configuration(a), scene.clearance()[0])[1] for a in alpha])
    assert grid_hit.any() and (~grid_hit).any()
    assert dist[grid_hit].max() <= 1.6 * eps
    assert dist[~grid_hit].min() >= -clusters.spacing
    # Theta over the reachable parts only equals eq 2 over all parts.
    theta, axis = capaman_grid.joint_matrix(grid, clusters, 9)
    full = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    np.testing.assert_array_equal(theta.ravel(), capaman_grid.grid_collision(full, grid, clusters))


@pytest.mark.parametrize("seed", [0, 5])
def test_joint_matrix_of_the_scenarios_equals_eq_2_everywhere(seed):
    """The joint matrix as random scenarios draw it (16^3 configurations, cluster points every 10 mm: the
    kernel's threaded path) equals eq 2 at every cluster point, obstacles far from and near the axis."""
    from paragym.tasks.capaman import _random_obstacles

    grid = capaman_grid.OccupancyGrid.from_obstacles(_random_obstacles(np.random.default_rng(seed)))
    clusters = capaman_grid.cluster_points(spacing=0.01)
    theta, axis = capaman_grid.joint_matrix(grid, clusters, 16)
    full = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    assert theta.any() and not theta.all()
    np.testing.assert_array_equal(theta.ravel(), capaman_grid.grid_collision(full, grid, clusters))


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


def _signed_distances_directly(obstacles, resolution=0.005, cap=0.05, unit=0.0005):
    """Psi with distances the plain way: every cell's centre tested against
    every obstacle, both distance transforms over the whole grid. Returns
    the grid's own rasterisation, this one, and the values."""
    from scipy import ndimage

    grid = capaman_grid.OccupancyGrid.from_obstacles(obstacles, resolution, margin=cap + 2 * resolution)
    shape = grid.occupied.shape
    axes = [grid.origin[i] + (np.arange(shape[i]) + 0.5) * resolution for i in range(3)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    occ = np.zeros(shape, bool)
    for o in obstacles:
        side = resolution / 2 if isinstance(o, Box) else resolution / 2 * np.sqrt(2.0)
        occ |= o.contains(centres, inflate=(side, resolution / 2))
    d = np.where(occ, -(ndimage.distance_transform_edt(occ) * resolution - resolution / 2),
                 ndimage.distance_transform_edt(~occ) * resolution - resolution / 2)
    return grid.occupied, occ, np.clip(np.round(d / unit), -round(cap / unit), round(cap / unit)).astype(np.int8)


@pytest.mark.parametrize("seed", range(6))
def test_signed_distances_equal_the_plain_computation_and_hold_the_cap_on_the_border(seed):
    from paragym.tasks.capaman import _random_obstacles

    obstacles = _random_obstacles(np.random.default_rng(seed))
    rasterised, occ, expected = _signed_distances_directly(obstacles)
    values, _ = capaman_clearance.signed_distances(obstacles)
    np.testing.assert_array_equal(rasterised, occ)
    np.testing.assert_array_equal(values, expected)
    # the clearance reads the border for points beyond the grid: it must hold the cap
    for k in range(3):
        assert np.all(np.take(values, [0, -1], axis=k) == 100)


def _values_at(grids, g, centres, rot, local):
    """Grid ``g``'s values (steps of ``grids.unit``) at points ``local`` (M, 3)
    of parts at ``centres`` (M, 3), ``rot`` (M, 3, 3), one point at a time in
    the same float32 cell arithmetic as the batch."""
    inv = 1.0 / grids.resolution
    m, t = (rot * inv).astype(np.float32), ((centres - grids.origin[g]) * inv).astype(np.float32)
    local = local.astype(np.float32)
    idx = [np.clip(t[:, k] + local[:, 0] * m[:, k, 0] + local[:, 1] * m[:, k, 1] + local[:, 2] * m[:, k, 2],
                   0, grids.shape[g, k] - 1).astype(np.int64) for k in range(3)]
    return grids.values[g * grids.slot + (idx[0] * grids.shape[g, 1] + idx[1]) * grids.shape[g, 2] + idx[2]]


def _clearance_at_every_point(alpha, grids, clusters, rows):
    """The grid's clearance with no block skipped: every cluster point of every
    part looked up, robot by robot."""
    centres, quats = capaman.part_frames(alpha, validate=False)
    rot = quat_to_matrix(quats)
    value, part = [], []
    for j, g in enumerate(rows):
        v = _values_at(grids, g, centres[j, clusters.part], rot[j, clusters.part], clusters.local)
        low = int(v.min())
        value.append(low * grids.unit)
        part.append(int(clusters.part[v == low].min()) if low < 100 else -1)
    return np.array(value), np.array(part)


@pytest.mark.slow
def test_grid_clearance_skips_only_blocks_that_cannot_matter(scene):
    """The batched clearance (blocks skipped when their sphere misses a robot's
    cells below the cap) equals a lookup of every cluster point, for robots
    in any order, near the task points and anywhere."""
    from paragym.tasks.capaman_worlds import _clusters

    clusters = _clusters(G)
    rng = np.random.default_rng(3)
    grids = capaman_clearance.DistanceGrids(4)
    scenarios = [random_scenario(np.random.default_rng(seed), scene, clusters) for seed in range(4)]
    for i, sc in enumerate(scenarios):
        grids.set(i, sc.obstacles)
    rows = rng.integers(4, size=3000)
    task = np.array([scenarios[g].alpha[rng.integers(3)] for g in rows])
    alpha = np.where(rng.random((3000, 1)) < 0.3, task + rng.normal(0, 0.1, (3000, 3)),
                     rng.uniform(G.alpha_min, G.alpha_max, (3000, 3)))
    alpha = np.clip(alpha, G.alpha_min, G.alpha_max)
    value, part = capaman_clearance.grid_clearance(alpha, grids, clusters, G, rows)
    expected_value, expected_part = _clearance_at_every_point(alpha, grids, clusters, rows)
    # collisions, and robots whose nearest point is near the cap, where a wrongly skipped block would show
    assert (expected_value < 0).any() and ((expected_value > 0.04) & (expected_value < 0.05)).sum() > 20
    np.testing.assert_array_equal(value, expected_value)
    np.testing.assert_array_equal(part, expected_part)
    # one after another (a short batch) as on numba's threads (a long one): the same answers
    assert len(alpha) >= capaman_clearance.PARALLEL_FROM > 60
    short = capaman_clearance.grid_clearance(alpha[:60], grids, clusters, G, rows[:60])
    np.testing.assert_array_equal(short[0], value[:60])
    np.testing.assert_array_equal(short[1], part[:60])
    # and the blocks skipped read the cap at every point
    parts, middles, radii, local = capaman_clearance._blocks(clusters)
    centres, quats = capaman.part_frames(alpha, validate=False)
    rot, f32 = quat_to_matrix(quats), np.float32
    reach = _spheres_meet_boxes(centres[:, parts].astype(f32), rot[:, parts].astype(f32), middles.astype(f32),
                                radii.astype(f32), grids.active_lo[rows, None].astype(f32),
                                grids.active_hi[rows, None].astype(f32))
    assert 0.005 < reach.mean() < 0.5
    robot, block = np.nonzero(~reach)
    pick = rng.choice(len(robot), 300_000, replace=False)
    robot, block = np.repeat(robot[pick], local.shape[1]), np.repeat(block[pick], local.shape[1])
    point = local[block[::local.shape[1]]].reshape(-1, 3)
    for g in range(4):
        mine = rows[robot] == g
        assert np.all(_values_at(grids, g, centres[robot[mine], parts[block[mine]]],
                                 rot[robot[mine], parts[block[mine]]], point[mine]) == 100)


def _spheres_meet_boxes(centres, rot, middles, radii, lo, hi):
    """Which blocks' bounding spheres (``middles``, ``radii`` in their part's frame ``centres``, ``rot``) meet
    their robot's box of cells below the cap (``lo``, ``hi``): the kernel's culling rule, in float32."""
    gap = np.zeros(np.broadcast_shapes(centres.shape[:2], middles.shape[:1]), centres.dtype)
    for k in range(3):
        c = (centres[..., k] + middles[:, 0] * rot[..., k, 0] + middles[:, 1] * rot[..., k, 1]
             + middles[:, 2] * rot[..., k, 2])
        d = np.maximum(np.maximum(lo[..., k] - c, c - hi[..., k]), 0)
        gap += d * d
    return gap <= radii * radii


def _closest_directly(sim, bodies, other="obstacles", cap=0.05):
    """PyBullet's own closest points between every link (the base included) of ``bodies`` and ``other``."""
    import pybullet as pb

    c, target = sim._client, sim.body(other)
    return min((pt[8] for body in bodies for pt in pb.getClosestPoints(sim.body(body), target, cap,
                                                                       physicsClientId=c)), default=cap)


@pytest.mark.parametrize("layout", ["kinematic", "tree", "split"])
def test_clearance_sees_every_link_of_every_body_the_base_included(layout):
    """A box 25 mm into the movable plate is a collision in every body layout of the CaPaMan: in the split
    dynamic layout the plate is a free body's base (link -1), which the query once dropped."""
    from paragym.sim.capaman_dynamic import CaPaManDynamics, CaPaManDynamicScene
    from paragym.sim.obstacles import Box

    if layout == "kinematic":
        s = CaPaManScene(G)
        bodies = [s.ROBOT]
    else:
        s = CaPaManDynamicScene(G, CaPaManDynamics(layout=layout))
        bodies = list(s.bodies)
    s.set_configuration(G.alpha_home)
    plate_z = G.a + G.h
    s.set_obstacles([Box((0.075, 0.13, plate_z), (0.02, 0.02, 0.02))])  # 25 mm into the plate, between legs 1 and 2
    d, part = s.clearance()
    exact = _closest_directly(s.sim, bodies)
    s.close()
    assert exact < -0.02
    assert part == "plate" and d == pytest.approx(exact, abs=1e-9)
