"""CaPaMan kinematics: closed-form direct kinematics against its inverse, the
Jacobian against finite differences, and the limits."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import quat_to_matrix

G = capaman.DEFAULT_GEOMETRY
angle = st.floats(min_value=G.alpha_min, max_value=G.alpha_max, allow_nan=False)
configs = st.lists(st.tuples(angle, angle, angle), min_size=1, max_size=20)


@settings(max_examples=200, deadline=None)
@given(configs)
def test_inverse_of_forward_is_identity(batch):
    alpha = np.array(batch)
    pose = capaman.forward(alpha)
    back, sliders = capaman.inverse(pose.position, pose.rotation)
    np.testing.assert_allclose(back, alpha, atol=1e-12)
    np.testing.assert_allclose(sliders, pose.sliders, atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(configs)
def test_forward_satisfies_the_leg_equation_and_rigid_plate(batch):
    alpha = np.array(batch)
    pose = capaman.forward(alpha)
    z = np.array([0.0, 0.0, 1.0])
    legs = (G.r_f * G.e + G.a * np.cos(alpha)[..., None] * G.u + pose.sliders[..., None] * G.w
            + (G.a * np.sin(alpha) + G.h)[..., None] * z)  # eq (M1)
    np.testing.assert_allclose(pose.ball_joints, legs, atol=1e-14)
    rot = pose.rotation
    np.testing.assert_allclose(rot @ np.swapaxes(rot, 1, 2), np.broadcast_to(np.eye(3), rot.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-14)
    np.testing.assert_allclose(quat_to_matrix(pose.quaternion), rot, atol=1e-14)


def test_home_pose():
    pose = capaman.forward(G.alpha_home)
    np.testing.assert_allclose(pose.position[0], [0.0, 0.0, G.a + G.h], atol=1e-15)
    np.testing.assert_allclose(pose.rotation[0], np.eye(3), atol=1e-15)
    np.testing.assert_allclose(pose.sliders[0], 0.0, atol=1e-15)


def test_one_configuration_through_the_kernel_equals_the_batch():
    """The scene poses one configuration with the kernel the batch loops: the
    same numbers, and the tip is H - L_tool R z of the pose's rotation."""
    rng = np.random.default_rng(3)
    alpha = rng.uniform(G.alpha_min, G.alpha_max, (300, 3))
    pose = capaman.forward(alpha)
    consts = capaman.kernel_consts(G)
    for a, h, q, tip in zip(alpha, pose.position, pose.quaternion, pose.tip, strict=True):
        out = capaman.k_forward(*a, consts)
        assert out[-1]
        np.testing.assert_array_equal(out[:3], h)
        np.testing.assert_array_equal(out[3:7], q)
        np.testing.assert_array_equal(out[8:11], tip)
    np.testing.assert_allclose(capaman.tool_tip(pose), pose.position - G.tool_length * pose.rotation[:, :, 2],
                               atol=1e-15)


def test_jacobian_matches_finite_differences():
    rng = np.random.default_rng(0)
    alpha = rng.uniform(G.alpha_min + 0.01, G.alpha_max - 0.01, (50, 3))
    j_plate, j_tip = capaman.jacobian(alpha)
    eps = 1e-6
    for j in range(3):
        d = np.zeros(3)
        d[j] = eps
        p_plus, p_minus = capaman.forward(alpha + d), capaman.forward(alpha - d)
        v = (p_plus.position - p_minus.position) / (2 * eps)
        np.testing.assert_allclose(j_plate[:, :3, j], v, atol=1e-8)
        # omega from R(+) R(-)^T = I + 2 eps [omega]x
        dr = (p_plus.rotation @ np.swapaxes(p_minus.rotation, 1, 2)) / (2 * eps)
        omega = np.stack([dr[:, 2, 1], dr[:, 0, 2], dr[:, 1, 0]], axis=1)
        np.testing.assert_allclose(j_plate[:, 3:, j], omega, atol=1e-7)
        tip = (capaman.tool_tip(p_plus) - capaman.tool_tip(p_minus)) / (2 * eps)
        np.testing.assert_allclose(j_tip[:, :, j], tip, atol=1e-8)


def test_tool_tip_inverse_reaches_the_target():
    rng = np.random.default_rng(1)
    alpha = rng.uniform(G.alpha_min, G.alpha_max, (200, 3))
    tips = capaman.tool_tip(capaman.forward(alpha))
    found = capaman.inverse_tool_tip(tips)
    np.testing.assert_allclose(capaman.tool_tip(capaman.forward(found)), tips, atol=1e-6)


def test_zero_gamma_makes_home_singular():
    """Design note: with radial leg planes (gamma = 0) the yaw equation has a
    double root at home, so the plate's parallel Jacobian loses rank there."""
    flat = capaman.CaPaManGeometry(gamma=0.0)
    pose = capaman.forward(flat.alpha_home, flat)
    np.testing.assert_allclose(pose.rotation[0], np.eye(3), atol=1e-7)
    with pytest.raises(np.linalg.LinAlgError):
        capaman.jacobian(flat.alpha_home, flat)
    assert np.linalg.cond(capaman.jacobian(G.alpha_home)[0][0]) < 1e3


@pytest.mark.parametrize("bad, message", [
    (np.array([np.nan, 1.5, 1.5]), "finite"),
    (np.array([1.5, 1.5]), "shape"),
    (np.ones((2, 2, 3)), "shape"),
    (np.radians([30.0, 90.0, 90.0]), "joint range"),
    (np.radians([90.0, 90.0, 140.0]), "joint range"),
])
def test_bad_joint_angles_are_refused(bad, message):
    with pytest.raises(ValueError, match=message):
        capaman.forward(bad)


def test_unreachable_pose_and_tip_are_refused():
    with pytest.raises(ValueError, match="not reachable"):
        capaman.inverse(np.array([0.0, 0.0, 0.5]), np.eye(3))
    with pytest.raises(ValueError, match="not reachable"):
        capaman.inverse_tool_tip(np.array([0.0, 0.0, 0.01]))
