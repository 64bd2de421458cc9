"""Rigid-body motions as time series: what the validation compares.

A :class:`~paragym.trajectories.RigidMotion` is any rigid body's motion
about a reference point (CaPaMan: the plate centre H): pose, twist and their
derivatives on a time grid, in the world frame (SI). It is generic: planned
motions (built here from a joint trajectory's analytic derivatives or from a
pose path) and executed ones (recorded by a dynamic run) of any mechanism are
validated by the same code.
"""

from __future__ import annotations

import numpy as np

from paragym.mechanisms import capaman
from paragym.trajectories import JointTrajectory, RigidMotion

__all__ = ["RigidMotion", "capaman_planned_motion"]


def capaman_planned_motion(trajectory: JointTrajectory, rate: float,
                           geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                           settle: float = 0.0, h: float = 1e-5) -> RigidMotion:
    """The plate's planned motion (about H) sampled at ``rate`` Hz.

    Pose from the closed-form direct kinematics of alpha(t); twist from the
    analytic Jacobian and the trajectory's analytic alpha_dot:
    ``[v; omega] = J(alpha) alpha_dot``; accelerations
    ``J(alpha) alpha_ddot + dJ/dt alpha_dot`` with dJ/dt by a central
    difference along the trajectory (step ``h`` s). ``settle`` s of rest are
    appended (the executed run holds its last targets that long).
    """
    t = np.arange(0.0, trajectory.duration + settle + 0.5 / rate, 1.0 / rate)
    lo, hi = geometry.alpha_min, geometry.alpha_max
    alpha = np.clip(trajectory.position(t), lo, hi)
    rate1, rate2 = trajectory.velocity(t), trajectory.acceleration(t)
    pose = capaman.forward(alpha, geometry, validate=False)
    j, _ = capaman.jacobian(alpha, geometry, validate=False)
    j_plus, _ = capaman.jacobian(np.clip(trajectory.position(t + h), lo, hi), geometry, validate=False)
    j_minus, _ = capaman.jacobian(np.clip(trajectory.position(t - h), lo, hi), geometry, validate=False)
    twist = np.einsum("nij,nj->ni", j, rate1)
    acc = np.einsum("nij,nj->ni", j, rate2) + np.einsum("nij,nj->ni", (j_plus - j_minus) / (2 * h), rate1)
    return RigidMotion(t, pose.position, pose.rotation, twist[:, :3], twist[:, 3:], acc[:, :3], acc[:, 3:])


def pose_path_motion(t_knots: np.ndarray, poses: np.ndarray, rate: float, settle: float = 0.0,
                     moving_at_end: bool = False) -> RigidMotion:
    """A body's planned motion from poses (K, 6) = (x, y, z, roll, pitch, yaw)
    (m, rad; ``R = Rz(yaw) Ry(pitch) Rx(roll)``) at times ``t_knots`` (K,):
    cubic splines through the poses (at rest at both ends, or, with
    ``moving_at_end``, free of acceleration at the end: a path cut off while
    moving), sampled at ``rate`` Hz, plus ``settle`` s at rest. Angular velocity from the angle
    rates, ``omega = roll' Rz Ry e_x + pitch' Rz e_y + yaw' e_z``; angular
    acceleration by central differences of omega."""
    from scipy.interpolate import CubicSpline

    from paragym.mechanisms.geometry import euler_matrix

    spline = CubicSpline(t_knots, poses, bc_type=((1, np.zeros(6)), (2, np.zeros(6))) if moving_at_end else "clamped")
    end = float(t_knots[-1])
    t = np.arange(0.0, end + settle + 0.5 / rate, 1.0 / rate)
    tc = np.clip(t, 0.0, end)
    moving = (t <= end)[:, None]
    p, v, a = spline(tc), np.where(moving, spline(tc, 1), 0.0), np.where(moving, spline(tc, 2), 0.0)
    roll, pitch, yaw = p[:, 3], p[:, 4], p[:, 5]
    rz_ry = euler_matrix(np.zeros_like(roll), pitch, yaw)
    rz = euler_matrix(np.zeros_like(roll), np.zeros_like(roll), yaw)
    omega = v[:, 3:4] * rz_ry[:, :, 0] + v[:, 4:5] * rz[:, :, 1] + v[:, 5:6] * np.array([0.0, 0.0, 1.0])
    return RigidMotion(t, p[:, :3], euler_matrix(roll, pitch, yaw), v[:, :3], omega, a[:, :3],
                       np.gradient(omega, t, axis=0))
