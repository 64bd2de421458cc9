"""The per-accelerometer Kalman filter of paper 000 (eqs 8-10, 18-20, Table 1).

Each 3-axis accelerometer has the state ``X = [a_x, da_x/dt, a_y, da_y/dt,
a_z, da_z/dt]`` with the constant-rate model ``A`` (eq 18, B = 0), process
noise ``Q`` built from mu_m1 and mu_m2 with ``G = I`` (eq 19), and the
observation of the three accelerations ``C`` with noise ``R = sigma^2 I``
(eq 20). Table 1: mu_m1 = 0.01 m/s^2, mu_m2 = 0.05 m/s^3, sigma = 0.5 m/s^2.

Two implementations that agree to 1e-9 (tested):

* :func:`filter_filterpy`, the reference: one ``filterpy.kalman.KalmanFilter``
  per sensor, stepped sample by sample.
* :func:`filter_vectorised`: A, Q, R and C are block-diagonal with identical
  2x2 blocks, so every axis is the same 2-state filter and shares its gains,
  which do not depend on the data. The gains are run until they stop
  changing (a few hundred samples), the states for those samples are
  updated for all axes at once, and the rest, a time-invariant linear
  recursion, is a second-order IIR filter (``scipy.signal.lfilter``) on all
  axes at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter, lfiltic

__all__ = ["KalmanSettings", "filter_filterpy", "filter_vectorised", "sensor_matrices", "smooth_filterpy",
           "smooth_vectorised"]


@dataclass(frozen=True)
class KalmanSettings:
    """Table 1 of paper 000, and the initial covariance of each 2-state block."""

    mu_m1: float = 0.01  # m/s^2
    mu_m2: float = 0.05  # m/s^3
    sigma: float = 0.5  # m/s^2, the same for the three axes
    p0_value: float = 0.25  # initial variance of the acceleration (sigma^2)
    p0_rate: float = 1.0  # initial variance of its rate


def _blocks(dt: float, k: KalmanSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a = np.array([[1.0, dt], [0.0, 1.0]])
    q = np.array([[k.mu_m1 ** 2, k.mu_m1 * k.mu_m2], [k.mu_m1 * k.mu_m2, k.mu_m2 ** 2]])
    p0 = np.diag([k.p0_value, k.p0_rate])
    return a, q, p0


def sensor_matrices(dt: float, k: KalmanSettings = KalmanSettings()) -> dict[str, np.ndarray]:
    """A (6x6, eq 18), Q and G (eq 19), C and R (eq 20), and P0 of one 3-axis sensor."""
    a, q, p0 = _blocks(dt, k)
    eye = np.eye(3)
    c = np.zeros((3, 6))
    c[[0, 1, 2], [0, 2, 4]] = 1.0
    return {"A": np.kron(eye, a), "Q": np.kron(eye, q), "G": np.eye(6), "C": c,
            "R": k.sigma ** 2 * eye, "P0": np.kron(eye, p0)}


def _check(y: np.ndarray, dt: float) -> np.ndarray:
    y = np.asarray(y, float)
    if y.ndim != 2 or y.shape[1] % 3 or len(y) < 3:
        raise ValueError(f"y must be (N >= 3, 3 S) readings of S 3-axis sensors; got {y.shape}")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number of seconds; got {dt!r}")
    return y


def filter_filterpy(y: np.ndarray, dt: float, k: KalmanSettings = KalmanSettings()) -> np.ndarray:
    """Filtered accelerations (N, 3 S) with one filterpy KalmanFilter per
    sensor (eqs 9-10), each started at its first reading with zero rates."""
    from filterpy.kalman import KalmanFilter

    y = _check(y, dt)
    m = sensor_matrices(dt, k)
    out = np.empty_like(y)
    for s in range(y.shape[1] // 3):
        kf = KalmanFilter(dim_x=6, dim_z=3)
        kf.F, kf.Q, kf.H, kf.R, kf.P = m["A"], m["Q"], m["C"], m["R"], m["P0"].copy()
        kf.x = np.zeros((6, 1))
        kf.x[[0, 2, 4], 0] = y[0, 3 * s:3 * s + 3]
        out[0, 3 * s:3 * s + 3] = y[0, 3 * s:3 * s + 3]
        for i in range(1, len(y)):  # the reference: one sample after the other
            kf.predict()
            kf.update(y[i, 3 * s:3 * s + 3])
            out[i, 3 * s:3 * s + 3] = kf.x[[0, 2, 4], 0]
    return out


def filter_vectorised(y: np.ndarray, dt: float, k: KalmanSettings = KalmanSettings(),
                      tol: float = 1e-15) -> np.ndarray:
    """The same filter as :func:`filter_filterpy` on every axis at once (module docstring)."""
    y = _check(y, dt)
    a, q, p = _blocks(dt, k)
    r = k.sigma ** 2
    n = len(y)
    gains = [np.zeros(2)]
    steady = n
    for i in range(1, n):  # the gain sequence (2x2 Riccati); stops when it no longer changes
        p = a @ p @ a.T + q
        gain = p[:, 0] / (p[0, 0] + r)
        p = p - np.outer(gain, p[0])
        gains.append(gain)
        if i > 3 and np.max(np.abs(gain - gains[-2])) < tol:
            steady = i
            break
    head = min(n, steady + 3)
    x = np.stack([y[0], np.zeros(y.shape[1])])  # (2, axes): value and rate of every axis
    out = np.empty_like(y)
    out[0] = y[0]
    for i in range(1, head):  # the transient, every axis at once
        gain = gains[min(i, len(gains) - 1)]
        pred = a @ x
        x = pred + np.outer(gain, y[i] - pred[0])
        out[i] = x[0]
    if head < n:  # then x_k = F x_k-1 + K y_k with F = (I - K C) A: an IIR filter from y to a
        gain = gains[-1]
        f = a - np.outer(gain, a[0])
        b_coef = np.array([gain[0], f[0, 1] * gain[1] - f[1, 1] * gain[0]])
        a_coef = np.array([1.0, -np.trace(f), np.linalg.det(f)])
        zi = np.stack([lfiltic(b_coef, a_coef, out[head - 1::-1][:2, j], y[head - 1::-1][:1, j])
                       for j in range(y.shape[1])], axis=1)
        out[head:], _ = lfilter(b_coef, a_coef, y[head:], axis=0, zi=zi)
    return out


def smooth_filterpy(y: np.ndarray, dt: float, k: KalmanSettings = KalmanSettings()) -> np.ndarray:
    """Rauch-Tung-Striebel smoothed accelerations (N, 3 S): filterpy's
    ``batch_filter`` then ``rts_smoother``, one sensor at a time (the reference)."""
    from filterpy.kalman import KalmanFilter

    y = _check(y, dt)
    m = sensor_matrices(dt, k)
    out = np.empty_like(y)
    for s in range(y.shape[1] // 3):
        kf = KalmanFilter(dim_x=6, dim_z=3)
        kf.F, kf.Q, kf.H, kf.R = m["A"], m["Q"], m["C"], m["R"]
        kf.x = np.zeros((6, 1))
        kf.x[[0, 2, 4], 0] = y[0, 3 * s:3 * s + 3]
        kf.P = m["P0"].copy()
        xs, ps = [kf.x.copy()], [kf.P.copy()]
        for i in range(1, len(y)):
            kf.predict()
            kf.update(y[i, 3 * s:3 * s + 3])
            xs.append(kf.x.copy())
            ps.append(kf.P.copy())
        smoothed, *_ = kf.rts_smoother(np.array(xs), np.array(ps))
        out[:, 3 * s:3 * s + 3] = smoothed[:, [0, 2, 4], 0]
    return out


def smooth_vectorised(y: np.ndarray, dt: float, k: KalmanSettings = KalmanSettings()) -> np.ndarray:
    """The RTS smoother of :func:`smooth_filterpy` on every axis at once: the
    forward filter's states (all axes), then the backward pass
    ``x_s[i] = x_f[i] + C_i (x_s[i+1] - A x_f[i])`` with the gains
    ``C_i = P_f[i] A^T P_p[i+1]^-1`` shared by all axes. Offline, no lag: the
    validation's verdict uses it (the forward filter lags fast motions)."""
    y = _check(y, dt)
    a, q, p = _blocks(dt, k)
    r = k.sigma ** 2
    n = len(y)
    p_f = np.empty((n, 2, 2))
    p_p = np.empty((n, 2, 2))
    x_f = np.empty((n, 2, y.shape[1]))
    p_f[0] = p
    x_f[0] = np.stack([y[0], np.zeros(y.shape[1])])
    for i in range(1, n):  # forward filter: 2x2 covariances, all axes' states together
        p_p[i] = a @ p_f[i - 1] @ a.T + q
        gain = p_p[i][:, 0] / (p_p[i][0, 0] + r)
        p_f[i] = p_p[i] - np.outer(gain, p_p[i][0])
        pred = a @ x_f[i - 1]
        x_f[i] = pred + np.outer(gain, y[i] - pred[0])
    x_s = x_f[-1].copy()
    out = np.empty_like(y)
    out[-1] = x_s[0]
    for i in range(n - 2, -1, -1):  # backward pass
        c = p_f[i] @ a.T @ np.linalg.inv(p_p[i + 1])
        x_s = x_f[i] + c @ (x_s - a @ x_f[i])
        out[i] = x_s[0]
    return out
