"""Paper 002's hybrid robot: kinematics, singularity, the planner and its env."""

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import paragym  # noqa: F401
from paragym.baselines import ZeroPolicy
from paragym.mechanisms import hybrid
from paragym.planners import PlanningError
from paragym.planners.polynomial_detour import PolynomialDetourPlanner, PolynomialDetourPolicy
from paragym.rollout import run_episode
from paragym.tasks.hybrid import HybridScenario, paper_scenario
from paragym.trajectories import nominal_path

G = hybrid.DEFAULT_GEOMETRY
ENV_ID = "paragym/HybridSingularityFree-v0"
# found by searching seeded pairs: no Delta works somewhere on the nominal path, a detour does
DETOUR = ((0.0763, 0.1088, 0.0292, -0.2817, -0.3225, -0.2099), (-0.0779, 0.0769, 0.0043, -0.2282, 0.2792, 0.3271))

small = st.floats(-1.0, 1.0)
poses = st.tuples(*[small] * 6).map(lambda v: np.array(v) * [0.04, 0.04, 0.04, 0.12, 0.12, 0.12])


@settings(max_examples=60, deadline=None)
@given(poses, st.floats(0.0, 1.0))
def test_forward_of_inverse_is_identity(p, delta):
    state = hybrid.solve(p, delta)
    np.testing.assert_allclose(hybrid.forward(state.lengths)[0], p, atol=1e-10)


def test_end_effector_pose_is_exact_for_every_split():
    p = np.array([0.03, -0.02, 0.05, 0.1, -0.15, 0.05])
    for delta in (0.0, 0.3, 0.5, 1.0):
        st_ = hybrid.solve(p, delta)
        np.testing.assert_allclose(st_.t_a @ st_.t_t, st_.t_e, atol=1e-14)
        np.testing.assert_allclose(hybrid._pose_of(st_.t_e)[0], hybrid.home_pose() + p, atol=1e-14)


def test_tripod_parasitic_motion_keeps_each_leg_in_its_plane():
    rng = np.random.default_rng(0)
    z, roll, pitch = rng.uniform(0.2, 0.26, 200), rng.uniform(-0.4, 0.4, 200), rng.uniform(-0.4, 0.4, 200)
    pose = hybrid.tripod_pose(z, roll, pitch)
    t = hybrid.pose_matrix(pose)
    joints = np.einsum("nij,kj->nki", t[:, :3, :3], G.tripod_top) + t[:, None, :3, 3]
    np.testing.assert_allclose(np.einsum("ki,nki->nk", G.tripod_axes, joints), 0.0, atol=1e-15)
    assert np.abs(pose[:, 5]).max() > 1e-3  # the parasitic yaw is there, not ignored


def test_force_matrix_is_the_transposed_jacobian_of_the_leg_lengths():
    t_a = hybrid.pose_matrix(np.array([0.01, -0.02, 0.24, 0.05, -0.08, 0.1]))
    h = hybrid.hexapod_matrix(t_a)[0]
    eps = 1e-7
    for k in range(6):
        twist = np.zeros(6)
        twist[k] = eps
        moved = t_a.copy()
        moved[0, :3, 3] += twist[:3]
        moved[0, :3, :3] = hybrid._rotvec(twist[None, 3:] / G.platform_radius)[0] @ t_a[0, :3, :3]
        back = t_a.copy()
        back[0, :3, 3] -= twist[:3]
        back[0, :3, :3] = hybrid._rotvec(-twist[None, 3:] / G.platform_radius)[0] @ t_a[0, :3, :3]
        d_len = (hybrid.hexapod_lengths(moved) - hybrid.hexapod_lengths(back))[0] / (2 * eps)
        np.testing.assert_allclose(d_len, h[k], atol=1e-7)


def test_home_is_regular_and_the_other_pairing_is_singular():
    home = hybrid.solve(np.zeros(6))
    assert home.free[0] and home.mu_hexapod[0] == pytest.approx(1.0) and home.mu_tripod[0] == pytest.approx(1.0)
    # joining each base joint to the platform joint 60 deg further on the same side
    t_a = hybrid.pose_matrix(np.array([0, 0, G.hexapod_home_height, 0, 0, 0.0]))
    a = (t_a[0, :3, :3] @ np.roll(G.platform_joints, 1, axis=0).T).T + t_a[0, :3, 3]
    a = np.roll(a, -2, axis=0)
    legs = a - G.base_joints
    s = legs / np.linalg.norm(legs, axis=1, keepdims=True)
    h = np.vstack([s.T, (np.cross(a - t_a[0, :3, 3], s) / G.platform_radius).T])
    assert np.linalg.svd(h, compute_uv=False)[-1] < 1e-9


def test_nominal_polynomial_is_rest_to_rest():
    u, p = nominal_path(np.zeros(6), np.ones(6), tau=0.01)
    poly = np.polynomial.Polynomial.fit(u, p[:, 0], 7).convert()  # the samples are exactly a 7th-degree polynomial
    for order in (1, 2, 3):
        np.testing.assert_allclose(poly.deriv(order)([0.0, 1.0]), 0.0, atol=1e-8)
    np.testing.assert_allclose(p[[0, -1]], [np.zeros(6), np.ones(6)])


def test_paper_plan_is_free_serial_only_and_smooth():
    sc = paper_scenario()
    plan = PolynomialDetourPlanner().plan(np.array(sc.p0), np.array(sc.p1))
    assert (~plan.nominal_free).sum() > 0  # the nominal path at Delta = 0.5 leaves the limits ...
    assert plan.free.all()  # ... the plan does not
    np.testing.assert_array_equal(plan.path, plan.nominal)  # serial optimisation keeps E on the nominal path
    assert np.abs(np.diff(plan.delta)).max() <= 0.05 + 1e-12 and plan.delta[0] == 0.5
    assert ((plan.lengths >= G.l_min) & (plan.lengths <= G.l_max)).all()


def test_detour_where_no_split_works():
    plan = PolynomialDetourPlanner().plan(np.array(DETOUR[0]), np.array(DETOUR[1]))
    assert (plan.method == 2).any() and plan.free.all()
    assert np.abs(plan.offsets).max() <= 0.02 + 1e-12
    np.testing.assert_array_equal(plan.offsets[[0, -1]], 0.0)  # the end poses stay exact


def test_detour_where_the_split_cannot_follow_the_splits_that_work():
    """Step 4: the easy rung's seed 0 has a working split at every pose, but near u = 0.7 the working band
    jumps from above 0.54 to below it faster than Delta may move (0.05 a sample). The planner as first written
    finds no schedule; with repairs it detours there and the plan is whole: every pose free, the rate limit
    kept, the offsets within j_bar and zero at both ends."""
    _, info = gym.make("paragym/HybridSingularityFree-Easy-v0").reset(seed=0)
    p0, p1 = np.array(info["scenario"].p0), np.array(info["scenario"].p1)
    with pytest.raises(PlanningError, match="rate limit"):
        PolynomialDetourPlanner().plan(p0, p1)
    table = PolynomialDetourPlanner()._table(nominal_path(p0, p1)[1])
    assert table.any(axis=1).all()  # no pose is blocked: only the schedule dies
    plan = PolynomialDetourPlanner(max_repairs=20).plan(p0, p1)
    assert plan.free.all() and (plan.method == 2).any()
    assert np.abs(np.diff(plan.delta)).max() <= 0.05 + 1e-12 and plan.delta[0] == 0.5
    assert np.abs(plan.offsets).max() <= 0.02 + 1e-12
    np.testing.assert_array_equal(plan.offsets[[0, -1]], 0.0)


def test_repairs_leave_a_plan_that_needs_none_as_it_was():
    for p0, p1 in ((paper_scenario().p0, paper_scenario().p1), DETOUR):
        a = PolynomialDetourPlanner().plan(np.array(p0), np.array(p1))
        b = PolynomialDetourPlanner(max_repairs=20).plan(np.array(p0), np.array(p1))
        for name in ("path", "offsets", "delta", "lengths"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for bad in (-1, 1.5, True, "3"):
        with pytest.raises(ValueError, match="max_repairs"):
            PolynomialDetourPlanner(max_repairs=bad)


def test_unreachable_goal_and_bad_input_are_refused():
    with pytest.raises(PlanningError, match="not singularity-free"):
        PolynomialDetourPlanner().plan(np.zeros(6), np.array([0.3, 0, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="finite"):
        hybrid.solve(np.array([np.nan, 0, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="delta"):
        hybrid.solve(np.zeros(6), 1.5)
    with pytest.raises(ValueError, match="angles"):
        hybrid.solve(np.array([0, 0, 0, 2.0, 0, 0]))
    with pytest.raises(ValueError, match="scenario must be"):
        gym.make(ENV_ID, scenario="moon")
    bad = HybridScenario("bad", (0.0,) * 5, (0.0,) * 6)
    with pytest.raises(ValueError, match="shape"):
        gym.make(ENV_ID, scenario=bad).reset(seed=0)
    far = HybridScenario("far", (0.0,) * 6, (0.3, 0.0, 0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="outside the workspace"):
        gym.make(ENV_ID, scenario=far).reset(seed=0)


def test_planner_succeeds_where_doing_nothing_fails():
    env = gym.make(ENV_ID)
    hard = 0
    for seed in range(16):
        ep_plan = run_episode(env, PolynomialDetourPolicy(), seed=seed)
        ep_zero = run_episode(env, ZeroPolicy(env.action_space), seed=seed)
        assert ep_plan.success, seed
        hard += not ep_zero.success
    assert hard >= 4  # about half of the random scenarios need the planner (hard_share = 0.5)
    paper = gym.make(ENV_ID, scenario="paper")
    assert run_episode(paper, PolynomialDetourPolicy(), seed=0).success
    assert not run_episode(paper, ZeroPolicy(paper.action_space), seed=0).success


@pytest.mark.slow
def test_dynamic_model_follows_the_plan_and_the_validation_judges_it():
    from paragym.sim.hybrid_dynamic import HybridDynamics
    from paragym.validation.hybrid import validate_hybrid

    sc = paper_scenario()
    plan = PolynomialDetourPlanner().plan(np.array(sc.p0), np.array(sc.p1))
    good = validate_hybrid(plan, duration=2.0)
    assert good.position_error < 1e-3 and good.orientation_error < np.radians(0.2)  # 1 mm, 0.2 deg
    assert good.run.closure_error < 0.1e-3
    assert good.report.passed, good.report.table()
    assert sum(c.observable for c in good.report.components) >= 3  # a_H is seen at this speed
    assert not validate_hybrid(plan, duration=2.0, delay=0.2).report.passed
    weak = validate_hybrid(plan, duration=2.0, dynamics=HybridDynamics(motor_force=20.0))
    assert weak.position_error > 5e-3 and not weak.report.passed


def _by_definition(poses, deltas, g=hybrid.DEFAULT_GEOMETRY):
    """Lengths, measures and eq 14 from 4x4 transforms and eq 11's matrices built here in plain numpy
    (an SVD for the measures): an independent formulation that the kernels must agree with."""
    share = 1.0 - deltas
    t_e = hybrid.pose_matrix(hybrid.home_pose(g) + poses)
    roll, pitch = share * poses[:, 3], share * poses[:, 4]
    yaw = np.arctan2(np.sin(pitch) * np.sin(roll), np.cos(pitch) + np.cos(roll))  # the parasitic yaw
    r_t = hybrid.euler_matrix(roll, pitch, yaw)
    e = np.einsum("nij,kj->nki", r_t, g.tripod_top)  # spherical joints about E's centre, A's frame
    rhs = -np.einsum("ki,nki->nk", g.tripod_axes, e)  # each leg in its plane: t_j . (p + R q_j) = 0
    xy = np.linalg.lstsq(g.tripod_axes[:, :2], rhs.T, rcond=None)[0].T
    t_t = hybrid.pose_matrix(np.column_stack([xy, g.tripod_home_height + share * poses[:, 2], roll, pitch, yaw]))
    t_a = t_e @ np.linalg.inv(t_t)

    def stage(t, joints, bases, radius):
        a = np.einsum("nij,kj->nki", t[:, :3, :3], joints)
        legs = a + t[:, None, :3, 3] - bases
        length = np.linalg.norm(legs, axis=2)
        s = legs / length[..., None]
        return length, np.concatenate([s, np.cross(a, s) / radius], axis=2)  # rows [s, a x s / r]

    len_h, rows_h = stage(t_a, g.platform_joints, g.base_joints, g.platform_radius)
    len_t, rows_t = stage(t_t, g.tripod_top, g.tripod_base, g.r_te)
    axes = np.broadcast_to(g.tripod_axes, e.shape)
    rows_t = np.concatenate([rows_t, np.concatenate([axes, np.cross(e, axes) / g.r_te], axis=2)], axis=1)
    lengths = np.concatenate([len_h, len_t], axis=1)
    home_h, home_t = hybrid._home_sigmas(g)
    mu_h = np.linalg.svd(rows_h, compute_uv=False)[:, -1] / home_h
    mu_t = np.linalg.svd(rows_t, compute_uv=False)[:, -1] / home_t
    within = np.all((lengths >= g.l_min) & (lengths <= g.l_max), axis=1)
    free = within & (mu_h > g.singularity_threshold) & (mu_t > g.singularity_threshold)
    return lengths, mu_h, mu_t, within, free, t_a, t_t


def test_the_kernels_equal_the_definition():
    """solve_rows (the env's step), solve, split, the stage functions and one
    pose at a time (the single env's N = 1) against eqs 3, 11-14 computed
    independently in matrix form."""
    rng = np.random.default_rng(0)
    poses = rng.uniform(-1, 1, (300, 6)) * [0.1, 0.1, 0.1, 0.3, 0.3, 0.4]
    deltas = rng.uniform(0, 1, 300)
    lengths, mu_h, mu_t, within, free, t_a, t_t = _by_definition(poses, deltas)
    assert 0 < free.sum() < 300 and 0 < within.sum() < 300  # both outcomes are exercised
    got = hybrid.solve_rows(poses, deltas)
    for ours, theirs in zip(got, (lengths, mu_h, mu_t, within, free), strict=True):
        np.testing.assert_allclose(ours, theirs, atol=1e-12)
    state = hybrid.solve(poses, deltas)
    np.testing.assert_allclose(state.lengths, lengths, atol=1e-12)
    np.testing.assert_allclose(state.t_a, t_a, atol=1e-12)
    np.testing.assert_allclose(state.t_t, t_t, atol=1e-12)
    np.testing.assert_allclose(hybrid.split(poses, deltas)[1], t_a, atol=1e-12)
    np.testing.assert_allclose(hybrid.leg_lengths_rows(poses, deltas), lengths, atol=1e-12)
    np.testing.assert_allclose(hybrid.hexapod_lengths(t_a), lengths[:, :6], atol=1e-12)
    np.testing.assert_allclose(hybrid.tripod_lengths(t_t), lengths[:, 6:], atol=1e-12)
    for k in range(0, 300, 7):  # one robot through the same kernel equals the batch, bit for bit
        one = hybrid.solve_rows(poses[k:k + 1], deltas[k:k + 1])
        for ours, batch in zip(one, got, strict=True):
            np.testing.assert_array_equal(ours[0], batch[k])


def test_the_measures_are_the_smallest_singular_values():
    # the kernel goes through the eigenvalues of M^T M; an SVD is the definition
    rng = np.random.default_rng(1)
    poses = rng.uniform(-1, 1, (200, 6)) * [0.1, 0.1, 0.1, 0.3, 0.3, 0.4]
    t_e, t_a, t_t = hybrid.split(poses, rng.uniform(0, 1, 200))
    for m in (hybrid.hexapod_matrix(t_a), hybrid.tripod_matrix(t_t)):
        ours = np.empty(len(m))
        hybrid._sigma_mins(np.ascontiguousarray(m.transpose(0, 2, 1)), ours)
        np.testing.assert_allclose(ours, np.linalg.svd(m, compute_uv=False)[:, -1], atol=1e-13)


def test_a_pair_of_poses_solves_as_each_alone():
    # k_solve_pair finds four measures in one call of Jacobi rotations: each exactly k_solve's
    rng = np.random.default_rng(2)
    consts = hybrid.kernel_consts(hybrid.DEFAULT_GEOMETRY)
    work = np.empty((7, 6, 6))
    for _ in range(100):
        pose, other = rng.uniform(-1, 1, (2, 6)) * [0.04, 0.04, 0.03, 0.15, 0.15, 0.2]
        delta = rng.uniform(0, 1)
        lengths, other_lengths, alone_lengths, alone_other = (np.empty(9) for _ in range(4))
        got = hybrid.k_solve_pair(pose, other, delta, *consts, lengths, other_lengths, work)
        alone = (*hybrid.k_solve(pose, delta, *consts, True, alone_lengths, np.empty((5, 6, 6))),
                 *hybrid.k_solve(other, delta, *consts, True, alone_other, np.empty((5, 6, 6))))
        assert got == alone
        np.testing.assert_array_equal(lengths, alone_lengths)
        np.testing.assert_array_equal(other_lengths, alone_other)


def test_random_scenarios_in_a_batch_equal_one_at_a_time():
    from paragym.tasks.hybrid import random_scenario, random_scenarios

    together = random_scenarios([np.random.default_rng(s) for s in range(24)])
    alone = [random_scenario(np.random.default_rng(s)) for s in range(24)]
    assert together == alone


@pytest.mark.slow
def test_the_solver_kernel_compiles_once_for_every_caller():
    """A fresh process: the geometry's constants, one pose, a batch and a fixed split reach the kernel as one
    signature (a read-only constant in one call and a writable one in another had compiled it three times,
    about 20 s of the main job's first run)."""
    import subprocess
    import sys

    code = ("import numpy as np\nfrom paragym.mechanisms import hybrid\n"
            "hybrid.solve(np.zeros(6)); hybrid.solve(np.zeros((3, 6)), np.full(3, 0.4))\n"
            "hybrid.solve_rows(np.zeros((2, 6)), np.full(2, 0.5)); hybrid.split(np.zeros(6), 0.5)\n"
            "print(len(hybrid._solve_all.signatures))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split()[-1] == "1"
