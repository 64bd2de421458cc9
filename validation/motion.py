"""Rigid-body motions as time series: what the validation compares.

A :class:`~paragym.trajectories.RigidMotion` is any rigid body's motion
about a reference point (CaPaMan: the plate centre H): pose, twist and their
derivatives on a time grid, in the world frame (SI). It is generic: planned
motions (built here from a pose path; a task's own, as the CaPaMan's from its
joint trajectory, in ``validation/<task>.py``) and executed ones (recorded by a
dynamic run) of any mechanism are validated by the same code.
"""

from __future__ import annotations

import numpy as np

from paragym.trajectories import RigidMotion

__all__ = ["RigidMotion", "pose_path_motion"]


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


def __getattr__(name: str) -> object:
    """``capaman_planned_motion``, the name of before paragym 0.9: it is :mod:`paragym.validation.capaman`'s now,
    with a DeprecationWarning."""
    if name == "capaman_planned_motion":
        import warnings

        from paragym.validation import capaman as _capaman

        warnings.warn("paragym.validation.motion.capaman_planned_motion is "
                      "paragym.validation.capaman.planned_motion since paragym 0.9", DeprecationWarning, stacklevel=2)
        return _capaman.planned_motion
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
