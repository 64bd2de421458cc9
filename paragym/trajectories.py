"""Joint-space paths shared by planners, policies and pictures (SI units: rad)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator

__all__ = ["JointPath", "JointTrajectory", "RigidMotion", "nominal_path"]


@dataclass(frozen=True)
class JointPath:
    """A piecewise-linear path through joint space.

    Attributes:
        waypoints: (K, n) configurations, rad.
        via_indices: indices into ``waypoints`` of the task points passed, in
            order (the first is the start).
    """

    waypoints: np.ndarray
    via_indices: tuple[int, ...]

    @property
    def length(self) -> float:
        """Sum of the Euclidean joint distances between consecutive waypoints
        (rad): the sum of d(Xi_i, Xi_i+1) in paper 000's fitness (eq 3)."""
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())

    def densify(self, max_step: float) -> np.ndarray:
        """Configurations along the path no more than ``max_step`` rad apart
        (for dense collision checks), all segments at once."""
        w = self.waypoints
        seg = np.diff(w, axis=0)
        counts = np.maximum(1, np.ceil(np.linalg.norm(seg, axis=1) / max_step).astype(int))
        starts = np.repeat(np.arange(len(seg)), counts)
        frac = np.concatenate([np.arange(c) / c for c in counts])
        return np.vstack([w[starts] + frac[:, None] * seg[starts], w[-1:]])


@dataclass(frozen=True)
class JointTrajectory:
    """A time-parameterised joint path: alpha(t), its velocity and acceleration.

    Through the via points at ``times`` with a piecewise-cubic Hermite
    interpolant whose interior slopes are PCHIP's (shape preserving: each
    joint stays between its neighbouring via values, so no overshoot past the
    checked path's bounding boxes) and whose end slopes are zero (rest to
    rest). Position and velocity are continuous (C1), as paper 000's section 5
    needs; acceleration is piecewise linear.
    """

    times: np.ndarray
    waypoints: np.ndarray
    max_velocity: float

    @classmethod
    def from_path(cls, path: JointPath, dt: float, max_velocity: float = 3.0) -> JointTrajectory:
        """Via points ``dt`` seconds apart (paper 000: 0.09, 0.45 or 0.9 s); if
        a joint would then exceed ``max_velocity`` (rad/s), every interval is
        stretched by the same factor until none does (``dt`` becomes the
        returned trajectory's ``dt``)."""
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds; got {dt!r}")
        if not (np.isfinite(max_velocity) and max_velocity > 0):
            raise ValueError(f"max_velocity must be > 0 rad/s; got {max_velocity!r}")
        times = dt * np.arange(len(path.waypoints))
        traj = cls(times, path.waypoints, max_velocity)
        peak = traj.peak_velocity
        if peak > max_velocity:
            traj = cls(times * (peak / max_velocity) * (1 + 1e-9), path.waypoints, max_velocity)
        return traj

    @cached_property
    def _spline(self) -> CubicHermiteSpline:
        slopes = PchipInterpolator(self.times, self.waypoints).derivative()(self.times)
        slopes[0] = slopes[-1] = 0.0
        return CubicHermiteSpline(self.times, self.waypoints, slopes)

    @property
    def dt(self) -> float:
        """Time between via points (s)."""
        return float(self.times[1] - self.times[0])

    @property
    def duration(self) -> float:
        """Total time (s)."""
        return float(self.times[-1])

    @property
    def peak_velocity(self) -> float:
        """Largest joint speed along the trajectory (rad/s), on a fine grid."""
        t = np.linspace(0.0, self.duration, 50 * len(self.times))
        return float(np.abs(self.velocity(t)).max())

    def position(self, t: np.ndarray) -> np.ndarray:
        """alpha(t), rad, shape (len(t), n)."""
        return self._spline(np.clip(t, 0.0, self.duration))

    def velocity(self, t: np.ndarray) -> np.ndarray:
        """d alpha / dt, rad/s (zero before the start and after the end: at rest)."""
        return self._outside_zero(t, self._spline.derivative(1))

    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """d2 alpha / dt2, rad/s^2 (zero before the start and after the end)."""
        return self._outside_zero(t, self._spline.derivative(2))

    def _outside_zero(self, t: np.ndarray, f: CubicHermiteSpline) -> np.ndarray:
        t = np.asarray(t, float)
        inside = (t >= 0.0) & (t <= self.duration)
        return np.where(inside[:, None], f(np.clip(t, 0.0, self.duration)), 0.0)

    def sample(self, rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(t, alpha, alpha_dot, alpha_ddot) at ``rate`` Hz over the whole trajectory."""
        t = np.arange(0.0, self.duration + 0.5 / rate, 1.0 / rate)
        return t, self.position(t), self.velocity(t), self.acceleration(t)


def nominal_path(p0: np.ndarray, p1: np.ndarray, tau: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """u (K,) and P(u) (K, n): paper 002's rest-to-rest 7th-degree polynomial
    ``P(u) = P0 + (P1 - P0)(35u^4 - 84u^5 + 70u^6 - 20u^7)`` (eqs 15-17: zero
    velocity, acceleration and jerk at both ends), sampled every ``tau``."""
    if not 0 < tau <= 0.5:
        raise ValueError(f"tau must lie in (0, 0.5]; got {tau}")
    u = np.linspace(0.0, 1.0, int(round(1.0 / tau)) + 1)
    s = 35 * u ** 4 - 84 * u ** 5 + 70 * u ** 6 - 20 * u ** 7
    return u, np.asarray(p0, float) + (np.asarray(p1, float) - np.asarray(p0, float)) * s[:, None]


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
