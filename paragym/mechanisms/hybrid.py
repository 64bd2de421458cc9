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

The equations are written once, as kernels compiled by numba: the stage
split (:func:`_stages`), the tripod's parasitic motion (:func:`_tripod_stage`)
and the legs with their rows of eq 11's matrices (:func:`_legs`). Every array
function here (``solve``, ``solve_rows``, ``split``, ``hexapod_matrix``, ...)
loops them over N, and the env's step calls the same loop, so one robot and
4096 run the same code. The smallest singular values are the square roots of
the smallest eigenvalues of M^T M, found by cyclic Jacobi rotations
(:func:`paragym.mechanisms.geometry.k_jacobi_lanes`) rather than LAPACK: OpenBLAS, under LAPACK, picks
its kernels per CPU, and its eigenvalues differed in the last bits between
CPUs; the rotations use +, *, / and sqrt only, the same bits
everywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit

from paragym.mechanisms.geometry import euler_matrix, k_jacobi_lanes, matrix_euler
from paragym.units import DEG

__all__ = [
    "LEGS_ONLY", "MEASURES", "HybridGeometry", "HybridState", "euler_matrix", "forward", "hexapod_forward",
    "hexapod_lengths", "hexapod_matrix", "is_singularity_free", "k_measure", "k_solve", "k_solve_pair", "kernel_consts",
    "pose_matrix", "solve", "split", "tripod_forward", "tripod_lengths", "tripod_pose", "within_limits",
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

#: :func:`k_solve`'s ``measures`` for a kernel that calls it, typed as numba types a variable (``bool``): a literal
#: ``True`` would compile k_solve a second time, apart from the calls that pass a variable
MEASURES, LEGS_ONLY = np.bool_(True), np.bool_(False)


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


# --- the equations, once: numba kernels ---------------------------------------------------


@njit(cache=True, error_model="numpy")
def _euler(r, p, y, out):
    """R = Rz(y) Ry(p) Rx(r) into ``out`` (3, 3)."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    out[0, 0], out[0, 1], out[0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    out[1, 0], out[1, 1], out[1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    out[2, 0], out[2, 1], out[2, 2] = -sp, cp * sr, cp * cr


@njit(cache=True, error_model="numpy")
def _tripod_stage(z, roll, pitch, top, axes, pinv_t, rt, pt):
    """The tripod's rotation R_T (into ``rt``) and origin p_T (into ``pt``), A's
    frame, from its inputs. Summing the three plane constraints
    ``t_j . (p + R q_j) = 0`` removes p (the t_j sum to zero) and, for joints
    120 deg apart, leaves ``R_10 = R_01``: the parasitic yaw
    ``tan(yaw) = sin(pitch) sin(roll) / (cos(pitch) + cos(roll))``; the
    parasitic x, y then follow from the (linear, consistent) constraints
    through the pseudo-inverse of the axes' xy (``pinv_t``, (3, 2))."""
    yaw = math.atan2(math.sin(pitch) * math.sin(roll), math.cos(pitch) + math.cos(roll))
    _euler(roll, pitch, yaw, rt)
    rhs = np.empty(3)
    for j in range(3):
        e0 = rt[0, 0] * top[j, 0] + rt[0, 1] * top[j, 1] + rt[0, 2] * top[j, 2]
        e1 = rt[1, 0] * top[j, 0] + rt[1, 1] * top[j, 1] + rt[1, 2] * top[j, 2]
        e2 = rt[2, 0] * top[j, 0] + rt[2, 1] * top[j, 1] + rt[2, 2] * top[j, 2]
        rhs[j] = -(axes[j, 0] * e0 + axes[j, 1] * e1 + axes[j, 2] * e2)
    for c in range(2):
        pt[c] = rhs[0] * pinv_t[0, c] + rhs[1] * pinv_t[1, c] + rhs[2] * pinv_t[2, c]
    pt[2] = z
    return yaw


@njit(cache=True, error_model="numpy")
def _stages(pose, delta, top, axes, pinv_t, home, tripod_home, re, rt, pt, ra, pa):
    """The split of eqs 3, 19-20 for E's displacement ``pose`` (6,) at split
    ``delta``: the tripod takes (1 - delta) of z, roll, pitch (R_T, p_T in
    ``rt``, ``pt``); the hexapod the rest, T_A = T_E T_T^-1 (R_A = R_E R_T^T in
    ``ra``, p_A in ``pa``), so that E's pose is met exactly. ``re``: R_E."""
    _euler(pose[3], pose[4], pose[5], re)
    share = 1.0 - delta
    _tripod_stage(tripod_home + share * pose[2], share * pose[3], share * pose[4], top, axes, pinv_t, rt, pt)
    for i in range(3):
        for j in range(3):
            ra[i, j] = re[i, 0] * rt[j, 0] + re[i, 1] * rt[j, 1] + re[i, 2] * rt[j, 2]
    for i in range(3):
        pa[i] = home[i] + pose[i] - (ra[i, 0] * pt[0] + ra[i, 1] * pt[1] + ra[i, 2] * pt[2])


@njit(cache=True, error_model="numpy")
def _legs(r, pos, joints, bases, inv_scale, lengths, rows, first):
    """Legs from ``joints`` (K, 3) on a frame at (R ``r``, ``pos``) to fixed
    ``bases`` (K, 3) (eqs 1, 4): their lengths into ``lengths[first:first+K]``
    and the rows [s, (R q) x s * inv_scale] of eq 11's matrix (transposed; s
    the unit leg) into ``rows[first:first+K]``."""
    for i in range(joints.shape[0]):
        a0 = r[0, 0] * joints[i, 0] + r[0, 1] * joints[i, 1] + r[0, 2] * joints[i, 2]
        a1 = r[1, 0] * joints[i, 0] + r[1, 1] * joints[i, 1] + r[1, 2] * joints[i, 2]
        a2 = r[2, 0] * joints[i, 0] + r[2, 1] * joints[i, 1] + r[2, 2] * joints[i, 2]
        l0, l1, l2 = a0 + pos[0] - bases[i, 0], a1 + pos[1] - bases[i, 1], a2 + pos[2] - bases[i, 2]
        n = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2)
        s0, s1, s2 = l0 / n, l1 / n, l2 / n
        lengths[first + i] = n
        rows[first + i, 0], rows[first + i, 1], rows[first + i, 2] = s0, s1, s2
        rows[first + i, 3] = (a1 * s2 - a2 * s1) * inv_scale
        rows[first + i, 4] = (a2 * s0 - a0 * s2) * inv_scale
        rows[first + i, 5] = (a0 * s1 - a1 * s0) * inv_scale


@njit(cache=True, error_model="numpy")
def _constraints(rt, top, axes, inv_e, rows):
    """The tripod's constraint wrenches (forces through the spherical joints
    along the revolute axes t_j) as rows [t_j, e_j x t_j * inv_e] 3-5 of ``rows``."""
    for j in range(3):
        e0 = rt[0, 0] * top[j, 0] + rt[0, 1] * top[j, 1] + rt[0, 2] * top[j, 2]
        e1 = rt[1, 0] * top[j, 0] + rt[1, 1] * top[j, 1] + rt[1, 2] * top[j, 2]
        e2 = rt[2, 0] * top[j, 0] + rt[2, 1] * top[j, 1] + rt[2, 2] * top[j, 2]
        t0, t1, t2 = axes[j, 0], axes[j, 1], axes[j, 2]
        rows[3 + j, 0], rows[3 + j, 1], rows[3 + j, 2] = t0, t1, t2
        rows[3 + j, 3], rows[3 + j, 4], rows[3 + j, 5] = ((e1 * t2 - e2 * t1) * inv_e, (e2 * t0 - e0 * t2) * inv_e,
                                                          (e0 * t1 - e1 * t0) * inv_e)


@njit(cache=True, error_model="numpy")
def _sigma_mins(mats, out):
    """The smallest singular values of the 6x6 matrices ``mats`` (L, 6, 6) into ``out`` (L,): the square
    roots of the smallest eigenvalues of their M^T M, all found at once by Jacobi rotations
    (:func:`paragym.mechanisms.geometry.k_jacobi_lanes`)."""
    lanes = mats.shape[0]
    gram = np.empty((lanes, 6, 6))
    for lane in range(lanes):
        rows = mats[lane]
        for a in range(6):
            for b in range(6):
                acc = 0.0
                for r in range(6):
                    acc += rows[r, a] * rows[r, b]
                gram[lane, a, b] = acc
    k_jacobi_lanes(gram, np.empty((1, 0, 0)), lanes)
    for lane in range(lanes):
        low = gram[lane, 0, 0]
        for i in range(1, 6):
            low = min(low, gram[lane, i, i])
        out[lane] = math.sqrt(max(low, 0.0))


@njit(cache=True, error_model="numpy")
def k_solve(pose, delta, base, plat, top, axes, tri_base, pinv_t, home, sc, measures, lengths, work):
    """One pose (6,) of E at split ``delta``: the nine leg lengths into
    ``lengths`` (9,) and, if ``measures``, the two singularity measures
    (sigma_min over its home value ``sc[3]``, ``sc[4]``), returned (else 0).
    ``work``: (5, 6, 6) scratch; afterwards R_A is work[0, :3, :3], p_A
    work[0, 3, :3], R_T work[1, :3, :3], p_T work[1, 3, :3]. ``sc``: tripod home
    height, 1 / platform radius, 1 / r_te, the home sigmas."""
    ra, pa, rt, pt, re = work[0, :3, :3], work[0, 3, :3], work[1, :3, :3], work[1, 3, :3], work[2, :3, :3]
    _stages(pose, delta, top, axes, pinv_t, home, sc[0], re, rt, pt, ra, pa)
    return k_measure(ra, pa, rt, pt, base, plat, top, axes, tri_base, sc, measures, lengths, work)


@njit(cache=True, error_model="numpy")
def k_solve_pair(pose, other, delta, base, plat, top, axes, tri_base, pinv_t, home, sc, lengths, other_lengths,
                 work):
    """:func:`k_solve` of two poses (6,) at one split ``delta``, with measures: their legs into ``lengths`` and
    ``other_lengths`` (9,), and the four measures (``pose``'s hexapod and tripod, then ``other``'s), returned.
    The four smallest singular values are found in one call of Jacobi rotations, each exactly as alone, so the
    numbers are :func:`k_solve`'s, bit for bit. ``work``: (7, 6, 6) scratch."""
    ra, pa, rt, pt, re = work[0, :3, :3], work[0, 3, :3], work[1, :3, :3], work[1, 3, :3], work[2, :3, :3]
    _stages(pose, delta, top, axes, pinv_t, home, sc[0], re, rt, pt, ra, pa)
    _rows(ra, pa, rt, pt, base, plat, top, axes, tri_base, sc, lengths, work[3], work[4], MEASURES)
    _stages(other, delta, top, axes, pinv_t, home, sc[0], re, rt, pt, ra, pa)
    _rows(ra, pa, rt, pt, base, plat, top, axes, tri_base, sc, other_lengths, work[5], work[6], MEASURES)
    sigma = np.empty(4)
    _sigma_mins(work[3:7], sigma)
    return sigma[0] / sc[3], sigma[1] / sc[4], sigma[2] / sc[3], sigma[3] / sc[4]


@njit(cache=True, error_model="numpy")
def _rows(ra, pa, rt, pt, base, plat, top, axes, tri_base, sc, lengths, h, t, measures):
    """The nine leg lengths into ``lengths`` (9,) (eqs 1, 4), and eq 11's matrices (transposed) of the
    hexapod into ``h`` and of the tripod into ``t`` (6, 6): its legs' rows, and its constraints' if
    ``measures``."""
    _legs(ra, pa, plat, base, sc[1], lengths, h, 0)
    _legs(rt, pt, top, tri_base, sc[2], lengths[6:], t, 0)
    if measures:
        _constraints(rt, top, axes, sc[2], t)


@njit(cache=True, error_model="numpy")
def k_measure(ra, pa, rt, pt, base, plat, top, axes, tri_base, sc, measures, lengths, work):
    """The robot with its stages at (R_A ``ra``, p_A ``pa``) in the base frame
    and (R_T ``rt``, p_T ``pt``) in A's frame, wherever they come from (the
    split of :func:`k_solve`, or a simulation): the nine leg lengths into
    ``lengths`` (9,) (eqs 1, 4) and, if ``measures``, the two singularity
    measures (eq 11's matrices; sigma_min over its home value), returned."""
    _rows(ra, pa, rt, pt, base, plat, top, axes, tri_base, sc, lengths, work[3], work[4], measures)
    if not measures:
        return 0.0, 0.0
    sigma = np.empty(2)
    _sigma_mins(work[3:5], sigma)
    return sigma[0] / sc[3], sigma[1] / sc[4]


@njit(cache=True, error_model="numpy")
def _solve_all(p, delta, consts, measures, lengths, mu_h, mu_t, ra_out, pa_out, rt_out, pt_out):
    """:func:`k_solve` for every pose p[i] at split delta[i] (``consts``: :func:`kernel_consts`); the stages'
    rotations and origins into the ``*_out`` arrays when they have N rows."""
    base, plat, top, axes, tri_base, pinv_t, home, sc = consts
    work = np.empty((5, 6, 6))
    keep = ra_out.shape[0] == p.shape[0]
    for i in range(p.shape[0]):
        mu_h[i], mu_t[i] = k_solve(p[i], delta[i], base, plat, top, axes, tri_base, pinv_t, home, sc, measures,
                                   lengths[i], work)
        if keep:  # by element: numba compiles an array copied into a slice with a shape check (seconds of compile)
            for a in range(3):
                pa_out[i, a], pt_out[i, a] = work[0, 3, a], work[1, 3, a]
                for b in range(3):
                    ra_out[i, a, b], rt_out[i, a, b] = work[0, a, b], work[1, a, b]


@njit(cache=True, error_model="numpy")
def _stage_all(r, pos, joints, bases, inv_scale, constraint_top, constraint_axes, lengths, mats):
    """Legs of one stage for transforms (R ``r[i]``, ``pos[i]``): lengths (N, K)
    and eq 11's matrices transposed (N, 6, 6) (rows of constraints too when
    ``constraint_top`` has rows: the tripod)."""
    for i in range(r.shape[0]):
        _legs(r[i], pos[i], joints, bases, inv_scale, lengths[i], mats[i], 0)
        if constraint_top.shape[0]:
            _constraints(r[i], constraint_top, constraint_axes, inv_scale, mats[i])


@njit(cache=True, error_model="numpy")
def _tripod_all(z, roll, pitch, top, axes, pinv_t, out):
    rt, pt = np.empty((4, 4))[:3, :3], np.empty(3)  # a view, as :func:`_stages` passes: one _tripod_stage compiled
    for i in range(z.shape[0]):
        yaw = _tripod_stage(z[i], roll[i], pitch[i], top, axes, pinv_t, rt, pt)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = pt[0], pt[1], z[i], roll[i], pitch[i], yaw


def _pinv_t(a: np.ndarray) -> np.ndarray:
    """The transposed pseudo-inverse A (A^T A)^-1 (3, 2) of a full-rank (3, 2) matrix, in closed form: LAPACK's
    SVD (numpy's ``pinv``) gives CPU-dependent last bits (:mod:`paragym.machine`)."""
    a = np.asarray(a, float).tolist()
    p, q, r = (sum(row[i] * row[j] for row in a) for i, j in ((0, 0), (0, 1), (1, 1)))
    det = p * r - q * q
    inv = np.array([[r / det, -q / det], [-q / det, p / det]])
    return np.array([[a[i][0] * inv[0, j] + a[i][1] * inv[1, j] for j in range(2)] for i in range(3)])


@lru_cache(maxsize=8)
def kernel_consts(g: HybridGeometry) -> tuple[np.ndarray, ...]:
    """The geometry as the kernels take it (read-only): B_i, A_i, q_j, t_j,
    the tripod's revolute joints, pinv of the axes' xy, E's home pose, and
    [tripod home height, 1 / platform radius, 1 / r_te, home sigma_min of
    the hexapod, of the tripod]."""
    arrays = [np.ascontiguousarray(a, float) for a in (g.base_joints, g.platform_joints, g.tripod_top,
                                                       g.tripod_axes, g.tripod_base,
                                                       _pinv_t(g.tripod_axes[:, :2]), home_pose(g))]
    raw = np.array([g.tripod_home_height, 1.0 / g.platform_radius, 1.0 / g.r_te, 1.0, 1.0])
    for a in (*arrays, raw):  # read-only before the first call too: numba compiles one signature, not two
        a.setflags(write=False)
    mu_h, mu_t = np.empty(1), np.empty(1)
    none = np.empty((0, 3, 3))
    _solve_all(np.zeros((1, 6)), np.full(1, 0.5), (*arrays, raw), True, np.empty((1, 9)), mu_h, mu_t,
               none, none[:, 0], none, none[:, 0])  # home: p = 0, any split
    sc = np.array([*raw[:3], mu_h[0], mu_t[0]])
    sc.setflags(write=False)
    return (*arrays, sc)


def _home_sigmas(g: HybridGeometry) -> tuple[float, float]:
    """sigma_min of the hexapod's and the tripod's matrices at home."""
    sc = kernel_consts(g)[-1]
    return float(sc[3]), float(sc[4])


def _run(p: np.ndarray, delta: np.ndarray, g: HybridGeometry, measures: bool, keep: bool) -> tuple[np.ndarray, ...]:
    p = np.ascontiguousarray(np.atleast_2d(p), float)
    n = len(p)
    d = np.empty(n)  # writable whatever ``delta`` is: one kernel signature
    d[:] = delta
    lengths, mu_h, mu_t = np.empty((n, 9)), np.empty(n), np.empty(n)
    m = n if keep else 0
    ra, pa, rt, pt = np.empty((m, 3, 3)), np.empty((m, 3)), np.empty((m, 3, 3)), np.empty((m, 3))
    _solve_all(p, d, kernel_consts(g), measures, lengths, mu_h, mu_t, ra, pa, rt, pt)
    return lengths, mu_h, mu_t, ra, pa, rt, pt


def _transform(r: np.ndarray, pos: np.ndarray) -> np.ndarray:
    t = np.zeros((len(r), 4, 4))
    t[:, :3, :3], t[:, :3, 3], t[:, 3, 3] = r, pos, 1.0
    return t


def tripod_pose(z: np.ndarray, roll: np.ndarray, pitch: np.ndarray,
                geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The tripod's full pose (N, 6) in A's frame from its three inputs, with
    its parasitic x, y and yaw (:func:`_tripod_stage`)."""
    _, _, top, axes, _, pinv_t, _, _ = kernel_consts(geometry)
    z, roll, pitch = (np.ascontiguousarray(v, float) for v in
                      np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, float)) for v in (z, roll, pitch))))
    out = np.empty((len(z), 6))
    _tripod_all(z, roll, pitch, top, axes, pinv_t, out)
    return out


def _stage(t: np.ndarray, geometry: HybridGeometry, tripod: bool) -> tuple[np.ndarray, np.ndarray]:
    base, plat, top, axes, tri_base, _, _, sc = kernel_consts(geometry)
    t = np.atleast_3d(t).reshape(-1, 4, 4)
    r, pos = np.ascontiguousarray(t[:, :3, :3]), np.ascontiguousarray(t[:, :3, 3])
    k = 3 if tripod else 6
    lengths, mats = np.empty((len(t), k)), np.empty((len(t), 6, 6))
    if tripod:
        _stage_all(r, pos, top, tri_base, sc[2], top, axes, lengths, mats)
    else:
        _stage_all(r, pos, plat, base, sc[1], np.empty((0, 3)), np.empty((0, 3)), lengths, mats)
    return lengths, mats.transpose(0, 2, 1)


def tripod_lengths(t_t: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Tripod leg lengths (N, 3) for tripod transforms T_T (N, 4, 4) (eq 4)."""
    return _stage(t_t, geometry, True)[0]


def tripod_matrix(t_t: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The tripod's 6x6 wrench matrix (N, 6, 6), in A's frame: three actuation
    wrenches (unit forces along the legs through the spherical joints) and
    three constraint wrenches (unit forces through the spherical joints along
    the revolute axes), moments about E's centre divided by r_te."""
    return _stage(t_t, geometry, True)[1]


def hexapod_lengths(t_a: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Hexapod leg lengths (N, 6) for platform transforms T_A (N, 4, 4) (eq 1)."""
    return _stage(t_a, geometry, False)[0]


def hexapod_matrix(t_a: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """H(X) (N, 6, 6) of eq 11: columns [s_i ; a_i x s_i / r] with s_i the
    unit leg vectors and a_i = R A_i the joints about A's centre (moments
    divided by the platform radius, so the matrix is dimensionless). Its
    transpose maps the platform twist (v, r omega) to the leg rates."""
    return _stage(t_a, geometry, False)[1]


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
    splits ``delta`` (N,) (module docstring; eqs 3, 19-20; :func:`_stages`)."""
    p = np.atleast_2d(p)
    _, _, _, ra, pa, rt, pt = _run(p, delta, geometry, False, True)
    return pose_matrix(home_pose(geometry) + p), _transform(ra, pa), _transform(rt, pt)


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
    lengths, mu_h, mu_t, ra, pa, rt, pt = _run(p, d, g, True, True)
    within, free = _verdict(lengths, mu_h, mu_t, g)
    return HybridState(pose_matrix(home_pose(g) + p), _transform(ra, pa), _transform(rt, pt), lengths, mu_h, mu_t,
                       within, free)


def _verdict(lengths: np.ndarray, mu_h: np.ndarray, mu_t: np.ndarray, g: HybridGeometry
             ) -> tuple[np.ndarray, np.ndarray]:
    """Eq 13 (all nine legs within limits) and eq 14 (and both measures at
    least the threshold)."""
    within = np.all((lengths >= g.l_min) & (lengths <= g.l_max), axis=1)
    return within, within & (mu_h >= g.singularity_threshold) & (mu_t >= g.singularity_threshold)


def solve_rows(p: np.ndarray, delta: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`solve` without the transforms, for poses (N, 6) and splits (N,)
    (no validation): the nine lengths (N, 9), both singularity measures (N,),
    within limits and free (eq 14) (N,)."""
    lengths, mu_h, mu_t, *_ = _run(p, delta, geometry, True, False)
    return (lengths, mu_h, mu_t, *_verdict(lengths, mu_h, mu_t, geometry))


def leg_lengths_rows(p: np.ndarray, delta: np.ndarray, geometry: HybridGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The nine actuator lengths (N, 9) (m; eqs 1, 4) for displacements ``p``
    (N, 6) of E at splits ``delta`` (N,): :func:`solve`'s lengths alone."""
    return _run(p, delta, geometry, False, False)[0]


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
