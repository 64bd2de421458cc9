"""The 2PRR + table of paper 003: kinematics, Jacobians, condition number, null space."""

import gymnasium as gym
import numpy as np
import pytest

from paragym.mechanisms import orthoglide as o

G = o.DEFAULT_GEOMETRY


def _configs(n: int = 200, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    p = rng.uniform([-0.3, 0.2], [0.5, 0.9], (n, 2))
    rho1 = rng.uniform(-0.5, 0.5, n)
    rho, ok = o.inverse(rho1, p)
    return rho[ok], p[ok]


def test_forward_of_inverse_is_identity():
    rho, p = _configs()
    np.testing.assert_allclose(o.forward(rho), p, atol=1e-12)


def test_jacobian_matches_finite_differences_of_the_kinematics():
    rho, _ = _configs(50)
    _, _, j = o.jacobian(rho)
    eps = 1e-7
    for k in range(3):
        d = np.zeros(3)
        d[k] = eps
        np.testing.assert_allclose((o.forward(rho + d) - o.forward(rho - d)) / (2 * eps), j[:, :, k], atol=1e-7)


def test_kappa_is_one_at_the_isotropic_pose():
    c = np.array(o.isotropic_point())
    rho, ok = o.inverse(np.zeros(1), (c - np.asarray(G.table_origin))[None])
    assert ok[0]
    assert o.kappa(rho)[0] == pytest.approx(1.0, abs=1e-8)
    assert np.all(o.kappa(_configs()[0]) >= 1.0)


def test_kappa_gradient_complex_step_matches_finite_differences():
    rho, _ = _configs(40)
    grad = o.kappa_gradient(rho)
    eps = 1e-6
    for k in range(3):
        d = np.zeros(3)
        d[k] = eps
        fd = (o.kappa(rho + d) - o.kappa(rho - d)) / (2 * eps)
        np.testing.assert_allclose(grad[:, k], fd, rtol=1e-5, atol=1e-6)


def test_null_space_motion_leaves_the_tool_fixed():
    rho, p = _configs(50)
    n = o.null_direction(rho)
    _, _, j = o.jacobian(rho)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", j, n), 0.0, atol=1e-12)
    step = 1e-5  # a small null-space step moves the tool by second order only
    assert np.abs(o.forward(rho + step * n) - p).max() < 1e-9
    pinv = np.linalg.pinv(j)
    np.testing.assert_allclose(np.eye(3) - pinv @ j, n[:, :, None] * n[:, None, :], atol=1e-12)


def test_singularities_and_bad_input():
    # sliders 2L apart: C midway, the links anti-parallel -> A is singular (parallel singularity)
    far = np.sqrt(2.0) - G.slider2_origin
    parallel, _ = o.singularity(np.array([[0.0, far, far]]), tol=1e-6)
    assert parallel[0]
    # C straight above A: r4 orthogonal to slider 2's axis -> B loses rank (serial singularity)
    rho, ok = o.inverse(np.zeros(1), np.array([[-0.3, 0.999999]]) - np.asarray(G.table_origin))
    assert ok[0]
    _, serial = o.singularity(rho, tol=1e-2)
    assert serial[0]
    with pytest.raises(ValueError, match="limits"):
        o.check_joints(np.array([2.0, 0.5, 0.5]))
    with pytest.raises(ValueError, match="finite"):
        o.check_joints(np.array([np.nan, 0.5, 0.5]))


def test_the_point_and_the_joint_parametrisations_agree():
    """J, kappa and n from the joints (planners) and from the table point (the
    env, which knows the path point) are the same equations (one kernel,
    :func:`o._j_of_links`) on links found two ways: equal to rounding."""
    rho, p = _configs(100, seed=3)
    _, _, j = o.jacobian(rho)
    k, n = o.kappa(rho), o.null_direction(rho)
    r, ok = o.inverse(rho[:, 0], p)
    assert ok.all()
    np.testing.assert_allclose(r, rho, atol=1e-12)
    jp, kp, np_ = o.jacobian_at(rho[:, 0], p[:, 0], p[:, 1])
    np.testing.assert_allclose(jp, j, atol=1e-12)
    np.testing.assert_allclose(kp, k, rtol=1e-10)
    np.testing.assert_allclose(np_, n, atol=1e-10)
    np.testing.assert_array_equal(o.kappa_at(rho[:, 0], p[:, 0], p[:, 1]), kp)
    t = np.array([0.3, -0.2])
    np.testing.assert_allclose(o.least_norm(jp, t), np.linalg.pinv(j) @ t, atol=1e-10)
    # one robot through the kernels equals the batch: the same code
    one = o.jacobian_at(rho[7, 0], p[7, 0], p[7, 1])
    np.testing.assert_array_equal(one[0][0], jp[7])
    assert one[1][0] == kp[7]


def test_task_generation_in_batches_equals_one_at_a_time():
    from paragym.planners import nullspace_gradient as ng
    from paragym.tasks.orthoglide import random_scenario, random_scenarios, servable, start_table_position

    together = random_scenarios([np.random.default_rng(s) for s in range(12)])
    for s, task in enumerate(together):
        alone = random_scenario(np.random.default_rng(s))
        assert task.name == alone.name
        np.testing.assert_array_equal(task.points, alone.points)
    # servable tries every tenth table position first: the same answer as the full sweep
    pts = np.random.default_rng(0).uniform([-1.5, -1.0], [2.0, 2.0], (3000, 2))
    full = np.zeros(len(pts), bool)
    for r1 in np.linspace(-1, 1, 101):
        rho, ok = o.inverse(np.full(len(pts), r1), pts)
        full |= ok & o.within_limits(rho)
    np.testing.assert_array_equal(servable(pts), full)
    assert 0.2 < full.mean() < 0.9  # both answers occur
    # the start configuration: the optimum of the 401-position sweep, as the planner finds it
    first = np.array([t.points[0] for t in together])
    kap, r1 = start_table_position(first)
    ref_kap, ref_r1 = ng.pointwise_optimum(ng.OrthoglideScenario("first", np.zeros(len(first)), first, first),
                                           samples=401)
    np.testing.assert_allclose(kap, ref_kap, rtol=1e-10)
    np.testing.assert_allclose(r1, ref_r1, atol=1e-12)


def test_the_papers_three_cases():
    from paragym.planners import nullspace_gradient as ng

    task = ng.paper_scenario()
    a, b = ng.case_fixed_table(task), ng.case_least_norm(task)
    c = ng.case_gradient(task, start=b)
    assert c.kappa.mean() <= b.kappa.mean() < a.kappa.mean()
    assert c.kappa.max() <= b.kappa.max() < a.kappa.max()
    assert abs(a.t[np.argmax(a.kappa)] - 2.2) < 0.3  # the fixed table is worst near 2.2 s, as in the paper
    optimum, _ = ng.pointwise_optimum(task)
    assert np.all(c.kappa <= 1.02 * optimum)  # within 2% of the best reachable at every path point
    for case in (a, b, c):  # all inside the joint limits, tool on the path
        assert o.within_limits(case.rho).all()
        np.testing.assert_allclose(o.forward(case.rho), task.points, atol=1e-9)
    assert np.ptp(a.rho[:, 0]) == 0.0


def test_env_policies_and_modes():
    import gymnasium as gym

    import paragym  # noqa: F401
    from paragym.baselines import ZeroPolicy
    from paragym.planners.nullspace_gradient import GradientPolicy, OrthoglideScenario
    from paragym.rollout import run_episode

    env = gym.make("paragym/Orthoglide2PRRKappa-v0", scenario="paper")
    grad = run_episode(env, GradientPolicy(), seed=0)
    least = run_episode(env, ZeroPolicy(env.action_space), seed=0)  # case (b): no null-space motion
    assert grad.success and least.success
    k_grad = np.array([i["kappa"] for i in grad.infos])
    k_least = np.array([i["kappa"] for i in least.infos])
    assert k_grad.mean() < k_least.mean() and grad.episode_return > least.episode_return
    assert max(i["tracking_error"] for i in grad.infos) == 0.0  # tracking is exact in the default mode
    joint = gym.make("paragym/Orthoglide2PRRKappa-v0", scenario="paper", action_mode="joint_velocity")
    obs, info = joint.reset(seed=0)
    obs, r, term, trunc, info = joint.step(np.zeros(3, np.float32))
    assert info["tracking_error"] > 0  # standing still leaves the moving path point behind
    far = OrthoglideScenario("far", np.array([0.0, 0.01]), np.array([[3.0, 3.0], [3.0, 3.0]]), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="reachable"):
        gym.make("paragym/Orthoglide2PRRKappa-v0", scenario=far).reset(seed=0)
    with pytest.raises(ValueError, match="action_mode"):
        gym.make("paragym/Orthoglide2PRRKappa-v0", action_mode="torque")


def _hard_rung_run(robots: int, steps: int) -> list[np.ndarray]:
    env = gym.make_vec("paragym/Orthoglide2PRRKappa-Hard-v0", num_envs=robots,
                       vectorization_mode="vector_entry_point", train_scenarios=6)
    obs, _ = env.reset(seed=5)
    actions = np.random.default_rng(1).uniform(-1, 1, (steps, robots, *env.single_action_space.shape))
    out = [obs]
    for a in actions.astype(np.float32):  # random joint rates fail within steps: resets every step
        obs, reward, terminated, truncated, _ = env.step(a)
        state = env.unwrapped.state  # the rung's kappa bound decides success only at a path's end: compare it
        out += [obs, reward, terminated, truncated, state.bound.copy(), state.rho.copy()]
    env.close()
    return out


def test_a_remembered_start_is_the_start_computed_anew(monkeypatch):
    # a reset remembers each scenario's start (its table position, sliders and the rung's kappa bound): with a
    # training set each is computed once, and must then be what computing it again gives, bit for bit
    from paragym.tasks import orthoglide_step

    remembered = _hard_rung_run(24, 30)
    monkeypatch.setattr(orthoglide_step, "_STARTS_KEPT", 0)  # nothing kept: every reset computes anew
    for got, want in zip(remembered, _hard_rung_run(24, 30), strict=True):
        np.testing.assert_array_equal(got, want)


def test_two_scenarios_of_one_name_have_their_own_starts():
    from paragym.tasks.orthoglide import circle_task
    from paragym.tasks.orthoglide_step import _starts

    params = gym.make("paragym/Orthoglide2PRRKappa-Hard-v0").unwrapped.params
    a, b = circle_task((0.1, 0.55), 0.4, 10.0, start=0.0), circle_task((0.1, 0.55), 0.4, 10.0, start=2.0)
    first, second = _starts(params, [a]), _starts(params, [b])
    assert a.name == b.name and not np.array_equal(first[0], second[0])
    assert {id(a), id(b)} <= params.__dict__["_starts"].keys()  # both remembered, each by its own identity
    for got, want in zip(_starts(params, [b, a]), (np.concatenate([second[0], first[0]]),
                                                   np.concatenate([second[1], first[1]])), strict=True):
        np.testing.assert_array_equal(got, want)
