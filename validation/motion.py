"""Rigid-body motions as time series: what the validation compares.

A :class:`RigidMotion` is any rigid body's motion about a reference point
(CaPaMan: the plate centre H): pose, twist and their derivatives on a time
grid, in the world frame (SI). It is generic: planned motions (from a joint
trajectory's analytic derivatives) and executed ones (from a dynamic run) of
any mechanism are validated by the same code.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from paragym.mechanisms import capaman
from paragym.trajectories import JointTrajectory

__all__ = ["RigidMotion", "capaman_planned_motion"]


@dataclass(frozen=True)
class RigidMotion:
    """A rigid body's motion on the time grid ``t`` (s), world frame.

    Attributes:
        position: reference point (N, 3), m.
        rotation: body-to-world rotations (N, 3, 3).
        velocity: of the reference point (N, 3), m/s.
        angular_velocity: (N, 3), rad/s.
        acceleration: of the reference point (N, 3), m/s^2.
        angular_acceleration: (N, 3), rad/s^2.
    """

    t: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    acceleration: np.ndarray
    angular_acceleration: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.t)
        for name in ("position", "velocity", "angular_velocity", "acceleration", "angular_acceleration"):
            if np.shape(getattr(self, name)) != (n, 3):
                raise ValueError(f"RigidMotion.{name} must have shape ({n}, 3); got {np.shape(getattr(self, name))}")
        if np.shape(self.rotation) != (n, 3, 3):
            raise ValueError(f"RigidMotion.rotation must have shape ({n}, 3, 3); got {np.shape(self.rotation)}")

    def body(self, name: str) -> np.ndarray:
        """A world-frame vector series expressed in the body frame: R^T v."""
        return np.einsum("nji,nj->ni", self.rotation, getattr(self, name))

    def at(self, t: np.ndarray) -> RigidMotion:
        """The motion on another time grid (linear interpolation of every
        series; rotations re-orthonormalised). ``t`` must lie in the range."""
        t = np.asarray(t, float)
        if t.min() < self.t[0] - 1e-9 or t.max() > self.t[-1] + 1e-9:
            raise ValueError(f"times must lie in [{self.t[0]}, {self.t[-1]}] s")

        def interp(a: np.ndarray) -> np.ndarray:
            flat = a.reshape(len(self.t), -1)
            return np.stack([np.interp(t, self.t, flat[:, j]) for j in range(flat.shape[1])], axis=1)

        u, _, vt = np.linalg.svd(interp(self.rotation).reshape(-1, 3, 3))
        return RigidMotion(t, interp(self.position), u @ vt, interp(self.velocity),
                           interp(self.angular_velocity), interp(self.acceleration),
                           interp(self.angular_acceleration))

    def shifted(self, delay: float) -> RigidMotion:
        """The same motion ``delay`` s later (held at its first state before)."""
        return RigidMotion(self.t, *(_shift(self.t, a, delay) for a in (
            self.position, self.rotation, self.velocity, self.angular_velocity, self.acceleration,
            self.angular_acceleration)))


def _shift(t: np.ndarray, a: np.ndarray, delay: float) -> np.ndarray:
    idx = np.clip(np.searchsorted(t, t - delay), 0, len(t) - 1)
    return a[idx]


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


def pose_path_motion(t_knots: np.ndarray, poses: np.ndarray, rate: float, settle: float = 0.0) -> RigidMotion:
    """A body's planned motion from poses (K, 6) = (x, y, z, roll, pitch, yaw)
    (m, rad; ``R = Rz(yaw) Ry(pitch) Rx(roll)``) at times ``t_knots`` (K,):
    cubic splines through the poses (at rest at both ends), sampled at
    ``rate`` Hz, plus ``settle`` s at rest. Angular velocity from the angle
    rates, ``omega = roll' Rz Ry e_x + pitch' Rz e_y + yaw' e_z``; angular
    acceleration by central differences of omega."""
    from scipy.interpolate import CubicSpline

    from paragym.mechanisms.hybrid import euler_matrix

    spline = CubicSpline(t_knots, poses, bc_type="clamped")
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
