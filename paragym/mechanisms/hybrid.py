"""Kinematics of the hybrid parallel robot of paper 002: a hexapod carrying a tripod.

Paper 002 (Rakhodaei, Ding, Saadat, Rastegarpanah, "Free singularity path
planning of hybrid parallel robot") gives the model's structure and numbers
but not its geometry; every size below is an assumption from the project's
design notes, documented in :class:`HybridGeometry`.

* **Hexapod** (6-UPU, base B to platform A): leg i runs from B_i on the base
  to A_i on platform A, ``L_i = |T_A A_i - B_i|`` (eq 1). Base joints at radius
  0.150 m, 120 k +- 15 deg; platform joints at 0.100 m, 120 k +- 45 deg; each
  base joint joins its nearest platform joint.
* **Tripod** (3-RPS, platform A to end-effector platform E): leg j has a
  revolute joint on A at radius ``r_ta`` whose axis is tangential, a
  prismatic actuator, and a spherical joint on E at radius ``r_te``. Each
  leg therefore moves in the vertical plane through A's axis and its
  revolute joint, which constrains E: ``t_j . E_j = 0`` with t_j the
  revolute axis. The tripod has three degrees of freedom, heave z_T, roll
  and pitch; its x_T, y_T and yaw are *parasitic* motions that follow from
  those three (:func:`tripod_pose`), never ignored.
* **Series**: ``T_E = T_A T_T`` exactly (eq 3).
* **Split** Delta (eqs 19-20): of the end-effector's displacement P from
  home (x, y, z, roll, pitch, yaw; m and rad), the tripod takes the share
  (1 - Delta) of what it can do (z, roll, pitch); the hexapod takes the rest,
  ``T_A = T_E T_T^-1``, so that E's pose is met exactly whatever Delta.
* **Singularity**: the hexapod's force transformation matrix
  ``H = [s_i ; A_i x s_i]`` (eq 11) with moments about A's centre divided by
  the platform radius, measured by its smallest singular value normalised
  by its value at home; the tripod's 6x6 matrix of the three actuation
  wrenches (along the legs) and the three constraint wrenches (forces
  through the spherical joints along the revolute axes), measured the same
  way. Singular when a measure drops below ``singularity_threshold``;
  eq 14 adds the nine leg limits L_min = 226.11 mm <= L <= L_max = 326.11 mm.

Angles are XYZ fixed (roll about x, then pitch about y, then yaw about z:
``R = Rz(yaw) Ry(pitch) Rx(roll)``). SI units throughout (the paper's mm are
converted at the edge).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from paragym.units import DEG

__all__ = [
    "HybridGeometry", "HybridState", "euler_matrix", "forward", "hexapod_forward", "hexapod_lengths",
    "hexapod_matrix", "is_singularity_free", "within_limits", "pose_matrix", "solve", "split", "tripod_forward",
    "tripod_lengths", "tripod_pose",
]



@dataclass(frozen=True)
class HybridGeometry:
    """Sizes of the hybrid robot (m, rad). The paper gives only the leg
    limits; the joint layout is the design notes' assumption, and the home
    heights are chosen so that the paper's example (P0 -> P1) is feasible after
    planning while its nominal path at Delta = 0.5 is not."""

    base_radius: float = 0.150
    base_half_angle: float = 15 * DEG
    platform_radius: float = 0.100
    platform_half_angle: float = 45 * DEG
    r_ta: float = 0.090  # tripod revolute joints on A
    r_te: float = 0.060  # tripod spherical joints on E
    tripod_angles: tuple[float, float, float] = (90 * DEG, 210 * DEG, 330 * DEG)
    hexapod_home_height: float = 0.220  # A above B at home (m)
    tripod_home_height: float = 0.225  # E above A at home (m)
    l_min: float = 0.22611
    l_max: float = 0.32611
    singularity_threshold: float = 0.2  # of the home value, both stages

    @property
    def base_joints(self) -> np.ndarray:
        """B_i (6, 3) in the base frame."""
        ang = np.array([120 * DEG * k + s * self.base_half_angle for k in range(3) for s in (-1, 1)])
        return self.base_radius * np.stack([np.cos(ang), np.sin(ang), np.zeros(6)], axis=1)

    @property
    def platform_joints(self) -> np.ndarray:
        """A_i (6, 3) in A's frame; A_i pairs with B_i (its nearest)."""
        ang = np.array([120 * DEG * k + s * self.platform_half_angle for k in range(3) for s in (-1, 1)])
        return self.platform_radius * np.stack([np.cos(ang), np.sin(ang), np.zeros(6)], axis=1)

    @property
    def tripod_base(self) -> np.ndarray:
        """Revolute joint centres (3, 3) on A, A's frame."""
        a = np.asarray(self.tripod_angles)
        return self.r_ta * np.stack([np.cos(a), np.sin(a), np.zeros(3)], axis=1)

    @property
    def tripod_top(self) -> np.ndarray:
        """Spherical joint centres (3, 3) on E, E's frame."""
        a = np.asarray(self.tripod_angles)
        return self.r_te * np.stack([np.cos(a), np.sin(a), np.zeros(3)], axis=1)

    @property
    def tripod_axes(self) -> np.ndarray:
        """Revolute axes t_j (3, 3), tangential, A's frame."""
        a = np.asarray(self.tripod_angles)
        return np.stack([-np.sin(a), np.cos(a), np.zeros(3)], axis=1)


DEFAULT_GEOMETRY = HybridGeometry()


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


def pose_matrix(pose: np.ndarray) -> np.ndarray:
    """4x4 transforms (N, 4, 4) of poses (N, 6) = (x, y, z, roll, pitch, yaw)."""
    pose = np.atleast_2d(pose)
    t = np.zeros(pose.shape[:-1] + (4, 4))
    t[..., :3, :3] = euler_matrix(pose[..., 3], pose[..., 4], pose[..., 5])
    t[..., :3, 3] = pose[..., :3]
    t[..., 3, 3] = 1.0
    return t


def _pose_of(t: np.ndarray) -> np.ndarray:
    return np.concatenate([t[..., :3, 3], matrix_euler(t[..., :3, :3])], axis=-1)


def _apply(t: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (K, 3) through transforms (N, 4, 4): (N, K, 3)."""
    return np.einsum("nij,kj->nki", t[:, :3, :3], points) + t[:, None, :3, 3]


# --- tripod -------------------------------------------------------------------------


@lru_cache(maxsize=8)
def _tripod_consts(g: HybridGeometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return g.tripod_top, g.tripod_axes, g.tripod_base


@lru_cache(maxsize=8)
def _consts(g: HybridGeometry) -> tuple[np.ndarray, ...]:
    """Per-geometry constant arrays: B_i, A_i, pinv of the revolute axes' xy,
    the constraint wrench columns' force part."""
    return g.base_joints, g.platform_joints, np.linalg.pinv(g.tripod_axes[:, :2]).T, home_pose(g)


def tripod_pose(z: np.ndarray, roll: np.ndarray, pitch: np.ndarray,
                geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The tripod's full pose (N, 6) in A's frame from its three inputs.

    Summing the three plane constraints ``t_j . (p + R q_j) = 0`` removes p
    (the t_j sum to zero) and, for joints 120 deg apart, leaves ``R_10 = R_01``;
    with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` that is the parasitic yaw
    ``tan(yaw) = sin(pitch) sin(roll) / (cos(pitch) + cos(roll))``. The
    parasitic x and y then follow from the (linear, consistent) constraints.
    """
    g = geometry
    q, t, _ = _tripod_consts(g)
    z, roll, pitch = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, float)) for v in (z, roll, pitch)))
    yaw = np.arctan2(np.sin(pitch) * np.sin(roll), np.cos(pitch) + np.cos(roll))
    rq = np.einsum("nij,kj->nki", euler_matrix(roll, pitch, yaw), q)  # (N, 3, 3)
    rhs = -np.einsum("ki,nki->nk", t, rq)  # t_j . p = rhs_j
    xy = rhs @ _consts(g)[2]
    return np.column_stack([xy, z, roll, pitch, yaw])


def tripod_lengths(t_t: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Tripod leg lengths (N, 3) for tripod transforms T_T (N, 4, 4) (eq 4)."""
    q, _, base = _tripod_consts(geometry)
    return np.linalg.norm(_apply(t_t, q) - base, axis=2)


def tripod_forward(lengths: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY,
                   guess: np.ndarray | None = None, tol: float = 1e-12) -> np.ndarray:
    """Tripod inputs (z, roll, pitch) (N, 3) from leg lengths (N, 3), by
    Newton's method on :func:`tripod_pose` (numerical Jacobian), batched."""
    lengths = np.atleast_2d(lengths)
    x = np.tile([geometry.tripod_home_height, 0.0, 0.0], (len(lengths), 1)) if guess is None else guess.copy()

    def f(v: np.ndarray) -> np.ndarray:
        return tripod_lengths(pose_matrix(tripod_pose(v[:, 0], v[:, 1], v[:, 2], geometry)), geometry)

    for _ in range(50):
        r = f(x) - lengths
        if np.max(np.abs(r)) < tol:
            break
        jac = np.stack([(f(x + h) - f(x - h)) / 2e-7 for h in np.eye(3) * 1e-7], axis=2)
        x = x - np.linalg.solve(jac, r[..., None])[..., 0]
    return x


# --- hexapod ---------------------------------------------------------------------------


def hexapod_lengths(t_a: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Hexapod leg lengths (N, 6) for platform transforms T_A (N, 4, 4) (eq 1)."""
    base, plat = _consts(geometry)[:2]
    return np.linalg.norm(_apply(t_a, plat) - base, axis=2)


def hexapod_matrix(t_a: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """H(X) (N, 6, 6) of eq 11: columns [s_i ; a_i x s_i / r] with s_i the
    unit leg vectors and a_i = R A_i the joints about A's centre (moments
    divided by the platform radius, so the matrix is dimensionless). Its
    transpose maps the platform twist (v, r omega) to the leg rates."""
    g = geometry
    base, plat = _consts(g)[:2]
    a = t_a[:, None, :3, :3] @ plat[None, :, :, None]
    a = a[..., 0]
    legs = a + t_a[:, None, :3, 3] - base
    s = legs / np.linalg.norm(legs, axis=2, keepdims=True)
    return np.concatenate([s, np.cross(a, s) / g.platform_radius], axis=2).transpose(0, 2, 1)


def hexapod_forward(lengths: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY,
                    guess: np.ndarray | None = None, tol: float = 1e-12) -> np.ndarray:
    """Platform A's pose (N, 6) from the six leg lengths (N, 6): Newton's
    method with the analytic Jacobian H^T, batched, from ``guess`` (home)."""
    g = geometry
    lengths = np.atleast_2d(lengths)
    pose = np.tile([0, 0, g.hexapod_home_height, 0, 0, 0], (len(lengths), 1)).astype(float) \
        if guess is None else guess.astype(float).copy()
    for _ in range(50):
        t = pose_matrix(pose)
        r = hexapod_lengths(t, g) - lengths
        if np.max(np.abs(r)) < tol:
            break
        jt = np.swapaxes(hexapod_matrix(t, g), 1, 2)  # dL = H^T [dp; r dphi]
        twist = np.linalg.solve(jt, -r[..., None])[..., 0]
        dphi = twist[:, 3:] / g.platform_radius
        rot = _rotvec(dphi) @ t[:, :3, :3]
        pose = np.column_stack([pose[:, :3] + twist[:, :3], matrix_euler(rot)])
    return pose


def _rotvec(v: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of rotation vectors (N, 3) (Rodrigues)."""
    theta = np.linalg.norm(v, axis=1)[:, None, None]
    k = np.zeros((len(v), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    k = k - np.swapaxes(k, 1, 2)
    safe = np.where(theta > 1e-12, theta, 1.0)
    return np.eye(3) + np.sin(safe) / safe * k + (1 - np.cos(safe)) / safe ** 2 * (k @ k)


def tripod_matrix(t_t: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The tripod's 6x6 wrench matrix (N, 6, 6), in A's frame: three actuation
    wrenches (unit forces along the legs through the spherical joints) and
    three constraint wrenches (unit forces through the spherical joints along
    the revolute axes), moments about E's centre divided by r_te."""
    q, t, base = _tripod_consts(geometry)
    e = np.einsum("nij,kj->nki", t_t[:, :3, :3], q)  # joints about E's centre
    legs = e + t_t[:, None, :3, 3] - base
    s = legs / np.linalg.norm(legs, axis=2, keepdims=True)
    tt = np.broadcast_to(t, s.shape)
    cols = np.concatenate([np.concatenate([s, np.cross(e, s) / geometry.r_te], axis=2),
                           np.concatenate([tt, np.cross(e, tt) / geometry.r_te], axis=2)], axis=1)
    return cols.transpose(0, 2, 1)


# --- the whole robot ---------------------------------------------------------------------


@dataclass(frozen=True)
class HybridState:
    """Everything about a batch of N end-effector poses at split Delta.

    Attributes: ``t_e``, ``t_a`` (base frame) and ``t_t`` (in A's frame)
    transforms (N, 4, 4); ``lengths`` (N, 9): six hexapod legs then three
    tripod legs (m); ``mu_hexapod``, ``mu_tripod`` (N,): the singularity
    measures (1 at home, 0 singular); ``within_limits`` (N,); ``free`` (N,):
    eq 14.
    """

    t_e: np.ndarray
    t_a: np.ndarray
    t_t: np.ndarray
    lengths: np.ndarray
    mu_hexapod: np.ndarray
    mu_tripod: np.ndarray
    within_limits: np.ndarray
    free: np.ndarray


def _sigma_min(m: np.ndarray) -> np.ndarray:
    """The smallest singular value of each square matrix (..., n, n): the
    square root of the smallest eigenvalue of M^T M (LAPACK's symmetric
    eigensolver, about twice as fast as an SVD for a batch of 6x6 matrices;
    it agrees with the SVD to ~eps * sigma_max^2 / sigma_min, 1e-14 here)."""
    gram = np.swapaxes(m, -1, -2) @ m
    return np.sqrt(np.maximum(np.linalg.eigvalsh(gram)[..., 0], 0.0))


@lru_cache(maxsize=8)
def _home_sigmas(g: HybridGeometry) -> tuple[float, float]:
    t_a = pose_matrix(np.array([0, 0, g.hexapod_home_height, 0, 0, 0.0]))
    t_t = pose_matrix(tripod_pose(g.tripod_home_height, 0.0, 0.0, g))
    return float(_sigma_min(hexapod_matrix(t_a, g))[0]), float(_sigma_min(tripod_matrix(t_t, g))[0])


def home_pose(geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """E's pose at home (6,): the stages stacked at their home heights."""
    return np.array([0.0, 0.0, geometry.hexapod_home_height + geometry.tripod_home_height, 0.0, 0.0, 0.0])


def check_pose(p: np.ndarray, name: str = "pose") -> np.ndarray:
    """Validate displacements from home (N, 6) (m, rad): shape and finiteness."""
    arr = np.asarray(p, float)
    arr = arr[None] if arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise ValueError(f"{name} must have shape (6,) or (N, 6): x, y, z (m), roll, pitch, yaw (rad); "
                         f"got {np.shape(p)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got NaN or inf")
    if np.any(np.abs(arr[:, 3:]) > np.pi / 2):
        raise ValueError(f"{name} angles must lie within +-pi/2 rad")
    return arr


def split(p: np.ndarray, delta: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """T_E, T_A, T_T (N, 4, 4) for displacements ``p`` (N, 6) of E from home and
    splits ``delta`` (N,) (module docstring; eqs 3, 19-20)."""
    g = geometry
    t_e = pose_matrix(_consts(g)[3] + p)
    share = 1.0 - delta
    t_t = pose_matrix(tripod_pose(g.tripod_home_height + share * p[:, 2], share * p[:, 3], share * p[:, 4], g))
    inv = np.zeros_like(t_t)  # rigid inverse: [R^T, -R^T p]
    inv[:, :3, :3] = np.swapaxes(t_t[:, :3, :3], 1, 2)
    inv[:, :3, 3] = -np.einsum("nji,nj->ni", t_t[:, :3, :3], t_t[:, :3, 3])
    inv[:, 3, 3] = 1.0
    return t_e, t_e @ inv, t_t


def solve(p: np.ndarray, delta: np.ndarray | float = 0.5, geometry: HybridGeometry = DEFAULT_GEOMETRY,
          validate: bool = True) -> HybridState:
    """Inverse kinematics of all nine actuators and the singularity test (eq 14)
    for displacements ``p`` (m, rad; (6,) or (N, 6)) of E from home at split
    ``delta`` ((N,) or a number in [0, 1])."""
    g = geometry
    p = check_pose(p) if validate else np.atleast_2d(p)
    d = np.broadcast_to(np.asarray(delta, float), (len(p),))
    if validate and (not np.all(np.isfinite(d)) or np.any((d < 0) | (d > 1))):
        raise ValueError(f"delta must lie in [0, 1]; got {delta!r}")
    t_e, t_a, t_t = split(p, d, g)
    return HybridState(t_e, t_a, t_t, *solve_rows(p, d, g))  # lengths, measures and eq 14: one batched path


def within_limits(p: np.ndarray, delta: np.ndarray | float = 0.5,
                  geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Eq 13 alone (all nine legs within limits) for poses (N, 6) at splits
    ``delta``: :func:`solve` without the singularity measures, for quick
    screening (no validation)."""
    g = geometry
    p = np.atleast_2d(p)
    lengths = leg_lengths_rows(p, np.broadcast_to(np.asarray(delta, float), (len(p),)), g)
    return np.all((lengths >= g.l_min) & (lengths <= g.l_max), axis=1)


def is_singularity_free(p: np.ndarray, delta: np.ndarray | float = 0.5,
                        geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Eq 14 for the whole robot: both stages non-singular and all nine legs within limits."""
    return solve(p, delta, geometry).free


def forward(lengths: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY,
            guess_a: np.ndarray | None = None, guess_t: np.ndarray | None = None) -> np.ndarray:
    """E's displacement from home (N, 6) from the nine leg lengths (N, 9):
    hexapod and tripod forward kinematics (numerical), then T_E = T_A T_T."""
    g = geometry
    lengths = np.atleast_2d(lengths)
    pose_a = hexapod_forward(lengths[:, :6], g, guess_a)
    inputs = tripod_forward(lengths[:, 6:], g, guess_t)
    t_t = pose_matrix(tripod_pose(inputs[:, 0], inputs[:, 1], inputs[:, 2], g))
    return _pose_of(pose_matrix(pose_a) @ t_t) - home_pose(g)


# --- one pose in Python floats: the environment's per-step path -------------------------


@lru_cache(maxsize=8)
def _consts_one(g: HybridGeometry) -> tuple:
    base, plat, pinv_t, home = _consts(g)
    return (base.tolist(), plat.tolist(), pinv_t.tolist(), home.tolist(), g.tripod_top.tolist(),
            g.tripod_axes.tolist(), g.tripod_base.tolist(), _home_sigmas(g))


def _euler_one(r: float, p: float, y: float) -> list[list[float]]:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]]


def _mv(m: list[list[float]], v: list[float]) -> list[float]:
    return [m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2], m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]]


def _cross(a: list[float], b: list[float]) -> list[float]:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def solve_one(p: list[float] | np.ndarray, delta: float, geometry: HybridGeometry = DEFAULT_GEOMETRY
              ) -> tuple[list[float], float, float, bool, bool]:
    """:func:`solve` for one pose, in Python floats (no validation): the nine
    lengths (m), the two singularity measures, within limits, free (eq 14).

    The same equations; at N = 1 numpy's per-call overhead makes the batched
    function cost ~400 us, this ~60 us plus the two 6x6 eigenvalue problems. A test keeps
    the two equal to 1e-12.
    """
    g = geometry
    base, plat, pinv_t, home, top, axes, tri_base, (h0, t0) = _consts_one(g)
    x, y, z, roll, pitch, yaw = (float(v) for v in p)
    pe = [home[0] + x, home[1] + y, home[2] + z]
    re = _euler_one(roll, pitch, yaw)
    share = 1.0 - float(delta)
    rt_, pt_ = share * roll, share * pitch
    yt = math.atan2(math.sin(pt_) * math.sin(rt_), math.cos(pt_) + math.cos(rt_))
    rt = _euler_one(rt_, pt_, yt)
    e = [_mv(rt, q) for q in top]  # tripod joints about E's centre, A's frame
    rhs = [-(axes[j][0] * e[j][0] + axes[j][1] * e[j][1] + axes[j][2] * e[j][2]) for j in range(3)]
    ptr = [sum(rhs[j] * pinv_t[j][0] for j in range(3)), sum(rhs[j] * pinv_t[j][1] for j in range(3)),
           g.tripod_home_height + share * z]
    ra = [[a[0] * b[0] + a[1] * b[1] + a[2] * b[2] for b in rt] for a in re]  # R_E R_T^T
    rp = _mv(ra, ptr)
    pa = [pe[0] - rp[0], pe[1] - rp[1], pe[2] - rp[2]]
    lengths, h_cols, t_cols = [], [], []
    inv_r = 1.0 / g.platform_radius
    for i in range(6):
        a = _mv(ra, plat[i])
        leg = [a[0] + pa[0] - base[i][0], a[1] + pa[1] - base[i][1], a[2] + pa[2] - base[i][2]]
        n = math.sqrt(leg[0] ** 2 + leg[1] ** 2 + leg[2] ** 2)
        s = [leg[0] / n, leg[1] / n, leg[2] / n]
        m = _cross(a, s)
        lengths.append(n)
        h_cols.append(s + [m[0] * inv_r, m[1] * inv_r, m[2] * inv_r])
    inv_e = 1.0 / g.r_te
    for j in range(3):
        leg = [e[j][0] + ptr[0] - tri_base[j][0], e[j][1] + ptr[1] - tri_base[j][1], e[j][2] + ptr[2] - tri_base[j][2]]
        n = math.sqrt(leg[0] ** 2 + leg[1] ** 2 + leg[2] ** 2)
        s = [leg[0] / n, leg[1] / n, leg[2] / n]
        m = _cross(e[j], s)
        lengths.append(n)
        t_cols.append(s + [m[0] * inv_e, m[1] * inv_e, m[2] * inv_e])
    for j in range(3):
        m = _cross(e[j], axes[j])
        t_cols.append(list(axes[j]) + [m[0] * inv_e, m[1] * inv_e, m[2] * inv_e])
    sig = _sigma_min(np.array([h_cols, t_cols]))  # transposes: the same singular values
    mu_h, mu_t = float(sig[0]) / h0, float(sig[1]) / t0
    within = all(g.l_min <= v <= g.l_max for v in lengths)
    free = within and mu_h >= g.singularity_threshold and mu_t >= g.singularity_threshold
    return lengths, mu_h, mu_t, within, free


# --- many poses, component-major: the vector environment's and the scenario screens' path ------


def _euler_rows(r: np.ndarray, p: np.ndarray, y: np.ndarray) -> tuple[tuple[np.ndarray, ...], ...]:
    """R = Rz(yaw) Ry(pitch) Rx(roll) as nine (N,) arrays, rows of tuples."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    spr, spc = sp * sr, sp * cr
    return ((cy * cp, cy * spr - sy * cr, cy * spc + sy * sr),
            (sy * cp, sy * spr + cy * cr, sy * spc - cy * sr),
            (-sp, cp * sr, cp * cr))


def _stages_rows(p: np.ndarray, delta: np.ndarray, g: HybridGeometry) -> tuple:
    """The split of eqs 19-20 for poses (N, 6) and splits (N,), component-major:
    R_A (3x3 of (N,)), p_A (3 of (N,)), the tripod's joints about E's centre
    e_j (3x3 of (N,), A's frame) and its origin p_T (3 of (N,))."""
    base, plat, pinv_t, home = _consts(g)
    top, axes, _ = _tripod_consts(g)
    x, y, z, roll, pitch, yaw = np.ascontiguousarray(p.T)
    re = _euler_rows(roll, pitch, yaw)
    share = 1.0 - delta
    rt_, pt_ = share * roll, share * pitch
    rt = _euler_rows(rt_, pt_, np.arctan2(np.sin(pt_) * np.sin(rt_), np.cos(pt_) + np.cos(rt_)))
    e = [[rt[i][0] * q[0] + rt[i][1] * q[1] for i in range(3)] for q in top]  # q_j has z = 0
    rhs = [-(axes[j][0] * e[j][0] + axes[j][1] * e[j][1]) for j in range(3)]  # t_j has z = 0
    p_t = [rhs[0] * pinv_t[0, 0] + rhs[1] * pinv_t[1, 0] + rhs[2] * pinv_t[2, 0],
           rhs[0] * pinv_t[0, 1] + rhs[1] * pinv_t[1, 1] + rhs[2] * pinv_t[2, 1],
           g.tripod_home_height + share * z]
    ra = [[re[i][0] * rt[j][0] + re[i][1] * rt[j][1] + re[i][2] * rt[j][2] for j in range(3)] for i in range(3)]
    pe = (home[0] + x, home[1] + y, home[2] + z)
    p_a = [pe[i] - (ra[i][0] * p_t[0] + ra[i][1] * p_t[1] + ra[i][2] * p_t[2]) for i in range(3)]
    return ra, p_a, e, p_t


def _legs_rows(ra: list, p_a: list, e: list, p_t: list, g: HybridGeometry) -> tuple[list, list, list]:
    """Leg vectors (9 legs x 3 components of (N,)), their lengths (9 of (N,))
    and the hexapod's joints about A's centre a_i (6 x 3 of (N,))."""
    base, plat = _consts(g)[:2]
    tri_base = _tripod_consts(g)[2]
    a = [[ra[i][0] * q[0] + ra[i][1] * q[1] for i in range(3)] for q in plat]  # A_i has z = 0
    legs = [[a[k][i] + p_a[i] - base[k, i] for i in range(3)] for k in range(6)]
    legs += [[e[j][i] + p_t[i] - tri_base[j, i] for i in range(3)] for j in range(3)]
    lengths = [np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) for v in legs]
    return legs, lengths, a


def leg_lengths_rows(p: np.ndarray, delta: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY,
                     chunk: int = 8192) -> np.ndarray:
    """The nine actuator lengths (N, 9) (m; eqs 1, 4) for displacements
    ``p`` (N, 6) of E at splits ``delta`` (N,): :func:`solve`'s lengths,
    written per component and computed ``chunk`` poses at a time (arrays
    that stay in the cache), several times faster for large N."""
    out = np.empty((len(p), 9))
    for lo in range(0, len(p), chunk):
        ra, p_a, e, p_t = _stages_rows(p[lo:lo + chunk], delta[lo:lo + chunk], geometry)
        out[lo:lo + chunk] = np.stack(_legs_rows(ra, p_a, e, p_t, geometry)[1], axis=1)
    return out


def _wrench_rows(legs: list, lengths: list, a: list, e: list, g: HybridGeometry) -> np.ndarray:
    """Both stages' 6x6 matrices for N poses, stacked (2N, 6, 6): the
    hexapod's H^T (rows [s_i, a_i x s_i / r]) then the tripod's wrench
    matrix transposed (rows [s_j, e_j x s_j / r_te], then [t_j, e_j x t_j / r_te]);
    a matrix and its transpose have the same singular values."""
    axes = _tripod_consts(g)[1]
    rows = []
    for k, scale, arm in [(k, 1.0 / g.platform_radius, a[k]) for k in range(6)] + \
            [(6 + j, 1.0 / g.r_te, e[j]) for j in range(3)]:
        s = [c / lengths[k] for c in legs[k]]
        rows += s + [(arm[1] * s[2] - arm[2] * s[1]) * scale, (arm[2] * s[0] - arm[0] * s[2]) * scale,
                     (arm[0] * s[1] - arm[1] * s[0]) * scale]
    n = len(lengths[0])
    zero = np.zeros(n)
    for j in range(3):  # constraint wrenches: t_j has z = 0
        t = axes[j]
        s = [np.full(n, t[0]), np.full(n, t[1]), zero]
        arm, scale = e[j], 1.0 / g.r_te
        rows += s + [(-arm[2] * t[1]) * scale, (arm[2] * t[0]) * scale, (arm[0] * t[1] - arm[1] * t[0]) * scale]
    out = np.stack(rows, axis=-1).reshape(n, 2, 6, 6)
    return out.transpose(1, 0, 2, 3).reshape(2 * n, 6, 6)


def solve_rows(p: np.ndarray, delta: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY, chunk: int = 8192
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`solve` without the transforms, for poses (N, 6) and splits (N,)
    (no validation): the nine lengths (N, 9), both singularity measures (N,),
    within limits and free (eq 14) (N,). The same equations per component,
    ``chunk`` poses at a time; the vector env's step and the scenario checks."""
    g = geometry
    h0, t0 = _home_sigmas(g)
    n = len(p)
    lengths, mu_h, mu_t = np.empty((n, 9)), np.empty(n), np.empty(n)
    for lo in range(0, n, chunk):
        ra, p_a, e, p_t = _stages_rows(p[lo:lo + chunk], delta[lo:lo + chunk], g)
        legs, lens, a = _legs_rows(ra, p_a, e, p_t, g)
        lengths[lo:lo + chunk] = np.stack(lens, axis=1)
        sig = _sigma_min(_wrench_rows(legs, lens, a, e, g))
        m = len(lens[0])
        mu_h[lo:lo + chunk], mu_t[lo:lo + chunk] = sig[:m] / h0, sig[m:] / t0
    within = np.all((lengths >= g.l_min) & (lengths <= g.l_max), axis=1)
    free = within & (mu_h >= g.singularity_threshold) & (mu_t >= g.singularity_threshold)
    return lengths, mu_h, mu_t, within, free
