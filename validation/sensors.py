"""Simulated accelerometer arrays and their inversion (paper 000, eqs 11-17 and 21).

An axis with unit sensitivity direction ``s`` at point ``r`` of the body
(body frame) reads (eq 12, with the specific force an accelerometer feels)::

    a_S = s . (a_B - g + alpha_B x r + omega_B x (omega_B x r)) + a_0 + noise

which is linear in the 12-vector (eqs 13-14, our ordering)::

    z = [f_B (3), alpha_B (3), wx^2, wy^2, wz^2, wx wy, wy wz, wx wz],   f_B = a_B - g

so twelve axes give ``y = M z + a_0`` (eqs 15-16) and ``z = M^-1 (y - a_0)``
(eq 17, solved by least squares so that more axes also work).

The default layout (the paper's Fig 4 shows four 3-axis sensors symmetric
under the plate; its exact positions are not printed) is P1, P2 = (+-r, 0, 0)
on the plate's underside and P3, P4 = (0, +-r, -L) on a bracket L below it,
every sensor with axes along the plate's. Four coplanar sensors cannot
separate alpha_x from wy wz (their columns of M coincide); the offset L
makes M invertible, and it gives the direct formulas of eq 21 their form
(:meth:`AccelerometerArray.direct`).

A sample is the mean of eq 12 over the sample period (:meth:`AccelerometerArray.read_mean`), as a real
accelerometer's anti-aliasing filter makes it; the paper's simulated readings are instants of smooth motions,
where the two agree. A simulated contact chatters at the physics step, far above the sensors' band, and read
at the instant that chatter folds into the band the filter judges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from paragym.trajectories import RigidMotion

__all__ = ["AccelerometerArray", "GRAVITY", "angular_velocity_from_z", "design_rows"]

GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s^2, world frame


def design_rows(positions: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Rows of M (eq 14) for axes of unit directions ``axes`` (K, 3) at body
    points ``positions`` (K, 3): (K, 12)."""
    r, s = np.asarray(positions, float), np.asarray(axes, float)
    rx, ry, rz = r.T
    sx, sy, sz = s.T
    return np.column_stack([
        s, np.cross(r, s),  # f_B and alpha_B (s . (alpha x r) = alpha . (r x s))
        -(sy * ry + sz * rz), -(sx * rx + sz * rz), -(sx * rx + sy * ry),  # wx^2, wy^2, wz^2
        sx * ry + sy * rx, sy * rz + sz * ry, sx * rz + sz * rx,  # wx wy, wy wz, wx wz
    ])


@dataclass(frozen=True)
class AccelerometerArray:
    """Accelerometer axes on a rigid body (body frame, SI).

    Attributes:
        positions: (S, 3) sensor points relative to the reference point H, m.
        axes: (S, 3, 3) each sensor's three unit sensitivity directions (rows).
        offsets: (3 S,) signal offsets a_0, m/s^2 (known: calibrated).
        noise_std: Gaussian noise per axis, m/s^2 (Table 1: 0.5).
        rate: sampling rate, Hz.
    """

    positions: np.ndarray
    axes: np.ndarray
    offsets: np.ndarray
    noise_std: float = 0.5
    rate: float = 500.0

    @classmethod
    def paper_layout(cls, r: float = 0.15, depth: float = 0.05, noise_std: float = 0.5, rate: float = 500.0,
                     offsets: np.ndarray | None = None) -> AccelerometerArray:
        """Four 3-axis sensors, P1, P2 = (+-r, 0, 0), P3, P4 = (0, +-r, -depth)
        (m), axes along the body's (module docstring). Offsets default to
        0.02 m/s^2 alternating in sign (a documented, known bias)."""
        positions = np.array([[r, 0, 0], [-r, 0, 0], [0, r, -depth], [0, -r, -depth]], float)
        axes = np.broadcast_to(np.eye(3), (4, 3, 3)).copy()
        if offsets is None:
            offsets = 0.02 * (-1.0) ** np.arange(12)
        return cls(positions, axes, np.asarray(offsets, float), noise_std, rate)

    @property
    def matrix(self) -> np.ndarray:
        """M (eq 16), (3 S, 12): one row per axis, sensor by sensor."""
        return design_rows(np.repeat(self.positions, 3, axis=0), self.axes.reshape(-1, 3))

    def read(self, motion: RigidMotion, rng: np.random.Generator | None = None) -> np.ndarray:
        """Readings y (N, 3 S) of every axis along ``motion`` (eq 12, eq 15),
        with Gaussian noise drawn from ``rng`` (None: noise-free). The motion
        should already be on the sensors' time grid (:meth:`RigidMotion.at`)."""
        y = self.true_z(motion) @ self.matrix.T + self.offsets
        if rng is not None:
            y = y + rng.normal(0.0, self.noise_std, y.shape)
        return y

    def read_mean(self, motion: RigidMotion, t: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        """Readings y (N, 3 S) at the sample times ``t`` (s) of an array whose every axis reads the mean of eq 12
        over the sample period 1 / ``rate`` about its sample time (clipped to the motion's span): the band limit
        that a real accelerometer's anti-aliasing filter gives its samples. ``motion`` is on its own, finer grid
        (a simulation's steps), and the mean is the trapezoidal integral of z over the period on that grid
        (linearly interpolated at the period's ends), divided by its length; Gaussian noise from ``rng`` (None:
        noise-free) as :meth:`read`. Sampling the instant instead folds the motion's content above half the rate
        (a contact's chatter at the physics step) into the band the filter judges."""
        t = np.asarray(t, float)
        z = self.true_z(motion)
        steps = np.diff(motion.t)[:, None]
        integral = np.vstack([np.zeros((1, z.shape[1])), np.cumsum(0.5 * (z[1:] + z[:-1]) * steps, axis=0)])
        half = 0.5 / self.rate
        a, b = np.clip(t - half, motion.t[0], motion.t[-1]), np.clip(t + half, motion.t[0], motion.t[-1])

        def integral_at(x: np.ndarray) -> np.ndarray:
            return np.stack([np.interp(x, motion.t, integral[:, j]) for j in range(z.shape[1])], axis=1)

        mean = (integral_at(b) - integral_at(a)) / (b - a)[:, None]
        y = mean @ self.matrix.T + self.offsets
        if rng is not None:
            y = y + rng.normal(0.0, self.noise_std, y.shape)
        return y

    @staticmethod
    def true_z(motion: RigidMotion) -> np.ndarray:
        """The 12-vector z (N, 12) of a motion, body frame (module docstring)."""
        f = motion.body("acceleration") - np.einsum("nji,j->ni", motion.rotation, GRAVITY)
        w = motion.body("angular_velocity")
        al = motion.body("angular_acceleration")
        wx, wy, wz = w.T
        return np.column_stack([f, al, wx * wx, wy * wy, wz * wz, wx * wy, wy * wz, wx * wz])

    def invert(self, y: np.ndarray) -> np.ndarray:
        """z = M^-1 (y - a_0) (eq 17) for every sample at once (least squares), (N, 12)."""
        z, *_ = np.linalg.lstsq(self.matrix, (np.asarray(y) - self.offsets).T, rcond=None)
        return z.T

    def direct(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The paper's direct formulas (eq 21) for the default layout: the
        specific force at H as the mean of the symmetric pair P1, P2, and the
        squares of the angular-velocity components from the centripetal terms
        (``omega_x^2 = (S_y + S_z - S_x) / 2`` and so on, with
        ``S_x = wy^2 + wz^2 = -(f_1x - f_Hx) / r``,
        ``S_y = -(f_3y - f_4y) / (2 r)``, ``S_z = ((f_3z + f_4z)/2 - f_Hz) / L``).
        Returns f_H (N, 3) and |omega| per component (N, 3)."""
        f = (np.asarray(y) - self.offsets).reshape(len(y), -1, 3)  # per sensor, along its axes (body axes)
        r, depth = self.positions[0, 0], -self.positions[2, 2]
        f_h = 0.5 * (f[:, 0] + f[:, 1])
        s_x = -(f[:, 0, 0] - f_h[:, 0]) / r
        s_y = -(f[:, 2, 1] - f[:, 3, 1]) / (2 * r)
        s_z = (0.5 * (f[:, 2, 2] + f[:, 3, 2]) - f_h[:, 2]) / depth
        squares = 0.5 * np.column_stack([s_y + s_z - s_x, s_x + s_z - s_y, s_x + s_y - s_z])
        return f_h, np.sqrt(np.clip(squares, 0.0, None))


def angular_velocity_from_z(z: np.ndarray, t: np.ndarray) -> np.ndarray:
    """omega (N, 3) from the quadratic terms of z: the principal direction of
    W = omega omega^T scaled by the square root of its eigenvalue. Its sign,
    which the squares cannot give, is taken from the time integral of the
    estimated angular acceleration (the motion starts at rest)."""
    wx2, wy2, wz2, wxy, wyz, wxz = z[:, 6:].T
    w = np.stack([np.stack([wx2, wxy, wxz], -1), np.stack([wxy, wy2, wyz], -1),
                  np.stack([wxz, wyz, wz2], -1)], -2)
    vals, vecs = np.linalg.eigh(w)
    omega = vecs[:, :, -1] * np.sqrt(np.clip(vals[:, -1], 0.0, None))[:, None]
    dt = np.diff(t, prepend=t[0])
    integral = np.cumsum(0.5 * (z[:, 3:6] + np.roll(z[:, 3:6], 1, axis=0)) * dt[:, None], axis=0)
    sign = np.where(np.sum(omega * integral, axis=1) < 0, -1.0, 1.0)
    return omega * sign[:, None]
