"""Geometry every mechanism shares: rotations as (x, y, z, w) quaternions (PyBullet's order) and the
rigid parts that the PyBullet scenes are built of."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["PartShape", "euler_matrix", "k_jacobi", "k_jacobi_lanes", "k_quat_to_matrix", "matrix_euler",
           "matrix_to_quat", "pose6", "quat_multiply", "quat_to_matrix"]


def quat_multiply(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Hamilton product of (x, y, z, w) quaternions, broadcast over leading axes."""
    x1, y1, z1, w1 = q1[..., 0], q1[..., 1], q1[..., 2], q1[..., 3]
    x2, y2, z2, w2 = q2[..., 0], q2[..., 1], q2[..., 2], q2[..., 3]
    return np.stack([
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
    ], axis=-1)


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit (x, y, z, w) quaternions (..., 4)."""
    if q.ndim == 1 and q.dtype == np.float64:  # one (a simulated link's): the same sums in floats, 10x faster
        x, y, z, w = q.tolist()
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack([
        1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
        2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
        2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
    ], axis=-1).reshape(q.shape[:-1] + (3, 3))


@njit(cache=True, inline="always")
def k_quat_to_matrix(q: np.ndarray, out: np.ndarray) -> None:
    """:func:`quat_to_matrix` of one quaternion (4,) into ``out`` (3, 3), in compiled code: the same sums in
    the same order, so the same floats."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    out[0, 0], out[0, 1], out[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
    out[1, 0], out[1, 1], out[1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
    out[2, 0], out[2, 1], out[2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)


#: :func:`k_jacobi`'s lane count, typed as a call from Python types it (a literal 1 would compile
#: :func:`k_jacobi_lanes` a second time)
_ONE_LANE = np.int64(1)


@njit(cache=True, error_model="numpy")
def k_jacobi(a, v):
    """The eigen-decomposition of the symmetric ``a`` (n, n) in place: the eigenvalues end on ``a``'s diagonal,
    the eigenvectors in ``v``'s columns (a ``v`` of shape (0, 0) asks for the eigenvalues only).
    :func:`k_jacobi_lanes` of one matrix."""
    n = a.shape[0]
    k_jacobi_lanes(a.reshape(1, n, n), v.reshape(1, v.shape[0], v.shape[1]), _ONE_LANE)


@njit(cache=True, error_model="numpy")
def k_jacobi_lanes(a, v, lanes):
    """The eigen-decompositions of the symmetric matrices ``a[:lanes]`` (L, n, n) in place, by cyclic Jacobi
    rotations: the eigenvalues end on each matrix's diagonal, the eigenvectors in ``v[l]``'s columns (``v``
    (L, n, n) is set to the identity first; a ``v`` of shape (1, 0, 0) asks for the eigenvalues only).

    Each sweep zeroes every off-diagonal element in row order (Golub and Van Loan, Algorithm 8.5.3); an element
    too small to change either diagonal element it couples is set to zero after three sweeps, and a matrix's
    sweeps stop when every off-diagonal element is zero (six to eight sweeps for n = 6). A rotation updates the
    two columns it couples and mirrors them into the rows: the same products as rotating the columns and then
    the rows, since the matrix stays exactly symmetric. The matrices are independent and rotated in lockstep,
    every lane's angle before any lane's update, so that the divisions and square roots of one lane overlap
    another's in the CPU; each matrix meets exactly the arithmetic it would alone. Plain arithmetic and sqrt
    only, in a fixed order, where LAPACK runs on OpenBLAS's per-CPU kernels: the same bits on every CPU."""
    if a.shape[1] == 6:  # the size of the hybrid's matrices, known to the compiler: its loops unrolled, 1.3x faster
        _jacobi_lanes(a, v, lanes, 6)
    else:
        _jacobi_lanes(a, v, lanes, a.shape[1])


@njit(cache=True, error_model="numpy", inline="always")
def _jacobi_lanes(a, v, lanes, n):
    vectors = v.shape[1] == n
    if vectors:
        for lane in range(lanes):
            for i in range(n):
                for j in range(n):
                    v[lane, i, j] = 1.0 if i == j else 0.0
    done = np.zeros(lanes, np.bool_)
    rotate = np.empty(lanes, np.bool_)
    cos, sin = np.empty(lanes), np.empty(lanes)
    for sweep in range(60):
        busy = False
        for lane in range(lanes):
            if not done[lane]:
                off = 0.0
                for p in range(n - 1):
                    for q in range(p + 1, n):
                        off += abs(a[lane, p, q])
                done[lane] = off == 0.0
                busy = busy or not done[lane]
        if not busy:
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                for lane in range(lanes):  # the angles
                    rotate[lane] = False
                    apq = a[lane, p, q]
                    if done[lane] or apq == 0.0:
                        continue
                    app, aqq = a[lane, p, p], a[lane, q, q]
                    g = 100.0 * abs(apq)
                    if sweep > 2 and abs(app) + g == abs(app) and abs(aqq) + g == abs(aqq):
                        a[lane, p, q] = a[lane, q, p] = 0.0
                        continue
                    theta = (aqq - app) / (2.0 * apq)
                    if abs(theta) > 1e150:
                        t = 0.5 / theta
                    else:
                        t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                        if theta < 0.0:
                            t = -t
                    c = 1.0 / math.sqrt(t * t + 1.0)
                    rotate[lane], cos[lane], sin[lane] = True, c, t * c
                for lane in range(lanes):  # the rotations
                    if not rotate[lane]:
                        continue
                    c, s, m = cos[lane], sin[lane], a[lane]
                    for k in range(n):
                        if k != p and k != q:
                            akp, akq = m[k, p], m[k, q]
                            m[k, p] = m[p, k] = c * akp - s * akq
                            m[k, q] = m[q, k] = s * akp + c * akq
                    app, apq, aqq = m[p, p], m[p, q], m[q, q]
                    # the 2x2 block, as the columns' rotation and then the rows' would leave it
                    pp, pq = c * app - s * apq, s * app + c * apq
                    qp, qq = c * apq - s * aqq, s * apq + c * aqq
                    m[p, p], m[q, q] = c * pp - s * qp, s * pq + c * qq
                    m[p, q] = m[q, p] = 0.0
                    if vectors:
                        w = v[lane]
                        for k in range(n):
                            vkp, vkq = w[k, p], w[k, q]
                            w[k, p] = c * vkp - s * vkq
                            w[k, q] = s * vkp + c * vkq


def matrix_to_quat(m: np.ndarray) -> np.ndarray:
    """(x, y, z, w) of one rotation matrix (used once per geometry, not in hot paths)."""
    w = np.sqrt(max(0.0, 1.0 + np.trace(m))) / 2
    if w > 1e-3:
        return np.array([(m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
                         (m[1, 0] - m[0, 1]) / (4 * w), w])
    i = int(np.argmax(np.diag(m)))
    j, k = (i + 1) % 3, (i + 2) % 3
    v = np.sqrt(max(0.0, 1.0 + m[i, i] - m[j, j] - m[k, k])) / 2
    q = np.empty(4)
    q[i], q[j], q[k] = v, (m[j, i] + m[i, j]) / (4 * v), (m[k, i] + m[i, k]) / (4 * v)
    q[3] = (m[k, j] - m[j, k]) / (4 * v)
    return q


@dataclass(frozen=True)
class PartShape:
    """A rigid part of the manipulator: a box or a cylinder about its local z.

    ``half_extents`` (m) for a box; ``radius`` and ``length`` (m) for a
    cylinder. Its pose comes from :func:`part_frames`.
    """

    name: str
    kind: str  # "box", "cylinder" or "sphere" (``radius``)
    half_extents: tuple[float, float, float] = (0.0, 0.0, 0.0)
    radius: float = 0.0
    length: float = 0.0


def euler_matrix(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll), batched: (N, 3, 3)."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    flat = np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
                     sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
                     -sp, cp * sr, cp * cr], -1)
    return flat.reshape(flat.shape[:-1] + (3, 3))


def matrix_euler(r: np.ndarray) -> np.ndarray:
    """(roll, pitch, yaw) (N, 3) of rotation matrices (N, 3, 3) (inverse of :func:`euler_matrix`)."""
    return np.stack([np.arctan2(r[..., 2, 1], r[..., 2, 2]), -np.arcsin(np.clip(r[..., 2, 0], -1, 1)),
                     np.arctan2(r[..., 1, 0], r[..., 0, 0])], -1)


def pose6(position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """A pose as (6,): the position (m) and the roll, pitch, yaw (rad) of the rotation matrix."""
    return np.concatenate([position, matrix_euler(rotation[None])[0]])
