"""The 2PRR + table of paper 003: kinematics, Jacobians, condition number, null space."""

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


def test_float_path_equals_batched():
    rho, p = _configs(100, seed=3)
    _, _, j = o.jacobian(rho)
    k, n = o.kappa(rho), o.null_direction(rho)
    for i in range(len(rho)):
        r2, r3, ok = o.inverse_one(rho[i, 0], *p[i])
        assert ok and r2 == pytest.approx(rho[i, 1], abs=1e-12) and r3 == pytest.approx(rho[i, 2], abs=1e-12)
        j0, j1, kap, nn = o.jacobian_one(rho[i, 0], *p[i])
        np.testing.assert_allclose([j0, j1], j[i], atol=1e-12)
        assert kap == pytest.approx(k[i], rel=1e-10)
        np.testing.assert_allclose(nn, n[i], atol=1e-10)
        t = np.array([0.3, -0.2])
        np.testing.assert_allclose(o.least_norm_one(j0, j1, *t), np.linalg.pinv(j[i]) @ t, atol=1e-10)
