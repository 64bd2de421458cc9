"""Kinematics of the Cassino Parallel Manipulator (CaPaMan), batched in numpy.

Paper 000 (Carbone, Gomez-Bravo, Selvi, "An experimental validation of
collision-free trajectories for parallel manipulators") plans in the joint
space of CaPaMan, a 3-DOF parallel manipulator whose three legs are
articulated parallelograms. The paper does not print the kinematic model or
the prototype's sizes, so this module follows the model written down in the
project's design notes:

Leg ``k`` sits at angle ``theta_k = 0, 120, 240 deg`` on the fixed plate, at
radius ``r_f``, with radial unit vector ``e_k``. Its parallelogram (crank
length ``a``, frame and coupler length ``c``) moves in a vertical plane whose
horizontal direction is ``u_k = Rz(gamma) e_k``. The connecting bar of length
``h`` stands vertically on the coupler midpoint (the parallelogram keeps it
vertical) and carries a prismatic joint ``s_k`` along ``w_k = z x u_k``, whose
slider holds the ball joint ``H_k`` of the movable plate::

    H_k = r_f e_k + a cos(alpha_k) u_k + s_k w_k + (a sin(alpha_k) + h) z     (M1)

The movable plate has its ball joints at radius ``r_p``: ``H_k = H + R p_k``
with ``p_k = r_p (cos theta_k, sin theta_k, 0)`` in the plate frame (M2).

Direct kinematics is closed form (``forward``):

* heights: ``z . H_k = a sin(alpha_k) + h`` are three linear equations in
  ``H_z`` and the plate-frame components of world ``z`` (the tilt);
* in-plane: ``u_k . H_k = r_f cos(gamma) + a cos(alpha_k)``; writing
  ``R = Rz(psi) R0`` with ``R0`` the minimal tilt, their sum eliminates
  ``H_x, H_y`` (the ``u_k`` sum to zero) and leaves ``A cos psi + B sin psi = C``
  for the yaw ``psi``; the branch continuous with the home pose
  (``|psi| < 90 deg``) is taken, then ``H_x, H_y`` follow linearly.

All sizes are in metres and angles in radians (the paper's 45-135 deg joint
range is converted here). The prototype's dimensions are not in the paper:
the defaults of :class:`CaPaManGeometry` are assumptions, documented as such.
With ``gamma = 0`` the home pose is singular (the yaw equation has a double
root), hence the default ``gamma = 90 deg`` (tangential leg planes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from types import SimpleNamespace

import numpy as np
from numba import njit

from paragym.mechanisms.geometry import PartShape, matrix_to_quat, quat_multiply, quat_to_matrix
from paragym.units import DEG

__all__ = [
    "CaPaManGeometry",
    "CaPaManPose",
    "check_joint_angles",
    "forward",
    "inverse",
    "inverse_tool_tip",
    "jacobian",
    "k_forward",
    "kernel_consts",
    "part_shapes",
    "part_frames",
    "part_table",
    "k_part_frames",
    "crank_trig",
    "swept_part_boxes",
    "tool_tip",
]



@dataclass(frozen=True)
class CaPaManGeometry:
    """Dimensions of the CaPaMan model (SI units: m, rad).

    The paper gives no prototype sizes; every default here is an assumption
    (design notes, "CaPaMan"): ``a = 0.08``, ``h = 0.10``,
    ``r_f = r_p = 0.20``, ``gamma = 90 deg``. The joint range 45-135 deg is the
    paper's (section 4). ``c`` (parallelogram frame/coupler length), the
    tool length and the part cross-sections are drawing and collision sizes,
    also assumed.
    """

    a: float = 0.08  # crank length
    h: float = 0.10  # connecting-bar length
    r_f: float = 0.20  # leg radius on the fixed plate
    r_p: float = 0.20  # ball-joint radius on the movable plate
    gamma: float = 90.0 * DEG  # leg-plane orientation, u_k = Rz(gamma) e_k
    c: float = 0.10  # frame and coupler length of each parallelogram
    tool_length: float = 0.12  # rod hanging from the plate centre
    tool_radius: float = 0.005
    plate_thickness: float = 0.01
    link_width: float = 0.012  # square cross-section of cranks, coupler, bar, rail
    rail_length: float = 0.14  # prismatic rail carried by the connecting bar
    alpha_min: float = 45.0 * DEG
    alpha_max: float = 135.0 * DEG
    leg_angles: tuple[float, float, float] = field(default=(0.0, 120.0 * DEG, 240.0 * DEG))

    @property
    def alpha_home(self) -> np.ndarray:
        """Home configuration (all cranks vertical, 90 deg), shape (3,)."""
        return np.full(3, 90.0 * DEG)

    @property
    def e(self) -> np.ndarray:
        """Radial unit vectors e_k of the legs, shape (3, 3)."""
        t = np.asarray(self.leg_angles)
        return np.stack([np.cos(t), np.sin(t), np.zeros(3)], axis=1)

    @property
    def u(self) -> np.ndarray:
        """In-plane horizontal directions u_k = Rz(gamma) e_k, shape (3, 3)."""
        t = np.asarray(self.leg_angles) + self.gamma
        return np.stack([np.cos(t), np.sin(t), np.zeros(3)], axis=1)

    @property
    def w(self) -> np.ndarray:
        """Slider directions w_k = z x u_k, shape (3, 3)."""
        return np.cross(np.array([0.0, 0.0, 1.0]), self.u)

    @property
    def plate_points(self) -> np.ndarray:
        """Ball joints p_k in the plate frame, shape (3, 3)."""
        return self.r_p * self.e


DEFAULT_GEOMETRY = CaPaManGeometry()


@lru_cache(maxsize=32)
def _consts(g: CaPaManGeometry) -> SimpleNamespace:
    """Geometry-derived constant arrays, computed once per geometry."""
    th = np.asarray(g.leg_angles)
    beta = th + g.gamma
    return SimpleNamespace(
        e=g.e, u=g.u, w=g.w, plate_points=g.plate_points,
        # heights: (n_x, n_y) = z_k @ tilt_map  (least squares of the three height equations)
        tilt_map=(2.0 / (3.0 * g.r_p)) * np.stack([np.cos(th), np.sin(th)], axis=1),
        cos_t=np.cos(th), sin_t=np.sin(th),
        cos_b=np.cos(beta), sin_b=np.sin(beta),
        u_xy=(2.0 / 3.0) * g.u[:, :2],
        c_off=g.r_f * np.cos(g.gamma),
    )


@dataclass(frozen=True)
class CaPaManPose:
    """Result of the direct kinematics for a batch of N configurations.

    Attributes (world frame, metres, rad):
        position: plate centre H, shape (N, 3).
        rotation: plate orientation R, shape (N, 3, 3).
        quaternion: the same orientation as (x, y, z, w), shape (N, 4).
        yaw: psi of R = Rz(psi) R0 (R0 the minimal tilt), shape (N,).
        geometry: the dimensions it was computed with.
        tip: the tool tip H - L_tool R z, shape (N, 3).
    """

    position: np.ndarray
    rotation: np.ndarray
    quaternion: np.ndarray
    yaw: np.ndarray
    geometry: CaPaManGeometry
    tip: np.ndarray

    @property
    def ball_joints(self) -> np.ndarray:
        """H_k = H + R p_k, shape (N, 3 legs, 3)."""
        return self.position[:, None, :] + np.swapaxes(
            self.rotation @ self.geometry.plate_points.T, 1, 2)

    @property
    def sliders(self) -> np.ndarray:
        """Prismatic displacements s_k = w_k . (H_k - r_f e_k), shape (N, 3), m."""
        g = self.geometry
        return np.sum((self.ball_joints - g.r_f * g.e) * g.w, axis=2)


def check_joint_angles(alpha: np.ndarray, geometry: CaPaManGeometry = DEFAULT_GEOMETRY,
                       name: str = "alpha") -> np.ndarray:
    """Validate crank angles: shape (3,) or (N, 3), finite, inside the limits.

    Returns a float array of shape (N, 3). Raises ``ValueError`` naming the
    argument and the allowed range (rad; 45-135 deg by default).
    """
    arr = np.asarray(alpha, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (3,) or (N, 3); got {np.shape(alpha)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got NaN or inf")
    tol = 1e-9
    bad = (arr < geometry.alpha_min - tol) | (arr > geometry.alpha_max + tol)
    if np.any(bad):
        worst = arr[bad][0]
        raise ValueError(
            f"{name} out of the joint range [{geometry.alpha_min:.6f}, {geometry.alpha_max:.6f}] rad "
            f"({np.degrees(geometry.alpha_min):.0f}-{np.degrees(geometry.alpha_max):.0f} deg); "
            f"got {worst:.6f} rad ({np.degrees(worst):.2f} deg)"
        )
    return arr


@lru_cache(maxsize=32)
def kernel_consts(g: CaPaManGeometry) -> np.ndarray:
    """The geometry as :func:`k_forward` takes it (read-only): a, h, r_p,
    c_off, L_tool, then per leg k (rows 5 + 8 k ..): tilt map (2), u_xy (2),
    cos theta_k, sin theta_k, cos beta_k, sin beta_k."""
    k = _consts(g)
    legs = np.column_stack([k.tilt_map, k.u_xy, k.cos_t, k.sin_t, k.cos_b, k.sin_b])
    out = np.concatenate([[g.a, g.h, g.r_p, float(k.c_off), g.tool_length], legs.ravel()])
    out.setflags(write=False)
    return out


@njit(cache=True, error_model="numpy")
def k_forward(a1, a2, a3, c):
    """Closed-form direct kinematics of one configuration (equations (M1)-(M2)
    of the module doc): the plate centre H (hx, hy, hz), its orientation as
    an (x, y, z, w) quaternion, the yaw psi (the branch continuous with home,
    cos psi > 0 side), the tool tip H - L_tool R z, and whether the
    configuration is assemblable (a real yaw exists)."""
    a, h, r_p, c_off, length = c[0], c[1], c[2], c[3], c[4]
    z1, z2, z3 = a * math.sin(a1) + h, a * math.sin(a2) + h, a * math.sin(a3) + h
    cs = (c_off + a * math.cos(a1), c_off + a * math.cos(a2), c_off + a * math.cos(a3))
    csum = 3 * c_off + a * (math.cos(a1) + math.cos(a2) + math.cos(a3))
    # heights: H_z + r_p (cos th_k n_x + sin th_k n_y) = z_k with n = R^T z (least squares)
    nx = z1 * c[5] + z2 * c[13] + z3 * c[21]
    ny = z1 * c[6] + z2 * c[14] + z3 * c[22]
    nz = math.sqrt(1.0 - nx * nx - ny * ny)
    # R0, the rotation about a horizontal axis with R0 n = z (Rodrigues, written out)
    f = 1.0 / (1.0 + nz)
    r00, r01, r11 = 1.0 - f * nx * nx, -f * nx * ny, 1.0 - f * ny * ny
    coef_c, coef_s = np.empty(3), np.empty(3)  # in-plane: u_k . H + r_p u_k . Rz(psi) R0 e_k = c_k
    for j in range(3):
        ct, st, cb, sb = c[9 + 8 * j], c[10 + 8 * j], c[11 + 8 * j], c[12 + 8 * j]
        qx, qy = r00 * ct + r01 * st, r01 * ct + r11 * st
        coef_c[j] = qx * cb + qy * sb
        coef_s[j] = qx * sb - qy * cb
    big_a = r_p * (coef_c[0] + coef_c[1] + coef_c[2])
    big_b = r_p * (coef_s[0] + coef_s[1] + coef_s[2])
    ratio = csum / math.hypot(big_a, big_b)
    if not abs(ratio) <= 1.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, False
    # two roots base -/+ spread; the one with the larger cos(psi) is the home branch
    base, spread = math.atan2(big_b, big_a), math.acos(ratio)
    psi = base - spread if math.cos(base - spread) >= math.cos(base + spread) else base + spread
    if abs(psi) > math.pi:
        psi = math.atan2(math.sin(psi), math.cos(psi))
    cp, sp = math.cos(psi), math.sin(psi)
    hx = hy = 0.0  # sum_k u_k u_k^T = 3/2 I in the plane and sum_k resid_k = 0: exact solution
    for j in range(3):
        r = cs[j] - r_p * (coef_c[j] * cp + coef_s[j] * sp)
        hx += r * c[7 + 8 * j]
        hy += r * c[8 + 8 * j]
    hz = (z1 + z2 + z3) / 3.0
    # orientation Rz(psi) R0: yaw (0, 0, sz, cz) times the tilt (ny, -nx, 0) / (2 ch), ch = sqrt((1 + nz) / 2)
    ch = math.sqrt(0.5 * (1.0 + nz))
    tx, ty = ny / (2 * ch), -nx / (2 * ch)
    sz, cz = math.sin(psi / 2), math.cos(psi / 2)
    x, y, z, w = cz * tx - sz * ty, cz * ty + sz * tx, sz * ch, cz * ch
    return (hx, hy, hz, x, y, z, w, psi, hx - length * 2 * (x * z + y * w), hy - length * 2 * (y * z - x * w),
            hz - length * (1 - 2 * (x * x + y * y)), True)


@njit(cache=True, error_model="numpy")
def _forward_all(alpha, c, position, quat, yaw, tip, ok):
    for i in range(alpha.shape[0]):
        (position[i, 0], position[i, 1], position[i, 2], quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3], yaw[i],
         tip[i, 0], tip[i, 1], tip[i, 2], ok[i]) = k_forward(alpha[i, 0], alpha[i, 1], alpha[i, 2], c)


def forward(alpha: np.ndarray, geometry: CaPaManGeometry = DEFAULT_GEOMETRY,
            validate: bool = True) -> CaPaManPose:
    """Closed-form direct kinematics: crank angles -> plate pose (:func:`k_forward`).

    Args:
        alpha: crank angles alpha_1..3 in rad, shape (3,) or (N, 3).
        geometry: the mechanism's dimensions.
        validate: check shape, finiteness and joint limits (turn off only for
            inputs already checked).

    Returns:
        CaPaManPose with batch size N. Raises ValueError where no real plate
        yaw exists (the configuration is not assemblable).
    """
    g = geometry
    al = check_joint_angles(alpha, g) if validate else np.atleast_2d(np.asarray(alpha, float))
    al = np.ascontiguousarray(al, float)
    n = len(al)
    position, quat, yaw, tip, ok = np.empty((n, 3)), np.empty((n, 4)), np.empty(n), np.empty((n, 3)), \
        np.empty(n, bool)
    _forward_all(al, kernel_consts(g), position, quat, yaw, tip, ok)
    if not ok.all():
        raise ValueError("alpha gives no real plate yaw: the configuration is not assemblable")
    return CaPaManPose(position, quat_to_matrix(quat), quat, yaw, g, tip)


def tool_tip(pose: CaPaManPose, geometry: CaPaManGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """World position of the tool tip, shape (N, 3): H - L_tool * (R z), as
    :func:`k_forward` computed it with the pose's geometry."""
    return pose.tip


def inverse(position: np.ndarray, rotation: np.ndarray,
            geometry: CaPaManGeometry = DEFAULT_GEOMETRY, tol: float = 1e-7
            ) -> tuple[np.ndarray, np.ndarray]:
    """Inverse kinematics: plate pose -> (crank angles alpha, sliders s).

    A 3-DOF robot reaches only a 3-dimensional set of the 6-D poses; a pose
    off that set (a crank circle missed by more than ``tol`` metres) raises
    ``ValueError``, as does one needing a crank angle outside the limits.

    Args:
        position: plate centre H, shape (3,) or (N, 3), m.
        rotation: plate orientation, shape (3, 3) or (N, 3, 3).

    Returns:
        alpha (N, 3) rad and s (N, 3) m, from (M1) solved leg by leg:
        ``alpha_k = atan2(z.H_k - h, u_k.H_k - r_f cos gamma)``.
    """
    g = geometry
    pos = np.atleast_2d(np.asarray(position, float))
    rot = np.asarray(rotation, float)
    rot = rot[None] if rot.ndim == 2 else rot
    if pos.shape[-1] != 3 or rot.shape[-2:] != (3, 3) or len(pos) != len(rot):
        raise ValueError(f"position must be (N, 3) and rotation (N, 3, 3); got {pos.shape} and {rot.shape}")
    if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(rot))):
        raise ValueError("position and rotation must be finite")
    ball = pos[:, None, :] + np.einsum("nij,kj->nki", rot, g.plate_points)
    d = np.einsum("nki,ki->nk", ball, g.u) - g.r_f * np.cos(g.gamma)
    z = ball[..., 2] - g.h
    miss = np.abs(np.hypot(d, z) - g.a)
    if np.any(miss > tol):
        raise ValueError(
            f"pose not reachable: a ball joint lies {miss.max():.3g} m off its crank circle "
            "(CaPaMan has 3 DOF; only poses produced by its legs are reachable)")
    alpha = np.arctan2(z, d)
    check_joint_angles(alpha, g, name="alpha (from the pose)")
    s = np.einsum("nki,ki->nk", ball - g.r_f * g.e[None], g.w)
    return alpha, s


def jacobian(alpha: np.ndarray, geometry: CaPaManGeometry = DEFAULT_GEOMETRY,
             validate: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Velocity Jacobians at alpha (rad, (3,) or (N, 3)).

    Differentiating (M1)-(M2) with plate twist (v, omega) gives, per leg,
    ``z.(v + omega x r_k) = a cos(alpha_k) dalpha_k`` and
    ``u_k.(v + omega x r_k) = -a sin(alpha_k) dalpha_k`` with r_k = R p_k: a
    6x6 system A [v; omega] = B dalpha (the parallel manipulator's two
    Jacobians).

    Returns:
        J_plate (N, 6, 3): [v_H; omega] per unit crank rate (m/rad, 1).
        J_tip (N, 3, 3): tool-tip velocity per unit crank rate (m/rad).
    """
    g = geometry
    al = check_joint_angles(alpha, g) if validate else np.atleast_2d(np.asarray(alpha, float))
    pose = forward(al, g, validate=False)
    n = len(al)
    r = pose.ball_joints - pose.position[:, None, :]  # (N, 3, 3)
    zvec = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (n, 3, 3))
    uvec = np.broadcast_to(g.u, (n, 3, 3))
    a_mat = np.empty((n, 6, 6))
    a_mat[:, 0:3, 0:3] = zvec
    a_mat[:, 0:3, 3:6] = np.cross(r, zvec)
    a_mat[:, 3:6, 0:3] = uvec
    a_mat[:, 3:6, 3:6] = np.cross(r, uvec)
    b_mat = np.zeros((n, 6, 3))
    idx = np.arange(3)
    b_mat[:, idx, idx] = g.a * np.cos(al)
    b_mat[:, 3 + idx, idx] = -g.a * np.sin(al)
    j_plate = np.linalg.solve(a_mat, b_mat)
    t = -g.tool_length * pose.rotation[:, :, 2]  # H -> tip, (N, 3)
    j_v, j_w = j_plate[:, :3], j_plate[:, 3:]
    j_tip = j_v + np.cross(j_w, t[:, :, None], axisa=1, axisb=1, axisc=1)
    return j_plate, j_tip


def inverse_tool_tip(tip: np.ndarray, geometry: CaPaManGeometry = DEFAULT_GEOMETRY,
                     alpha0: np.ndarray | None = None, tol: float = 1e-6,
                     max_iter: int = 100) -> np.ndarray:
    """Crank angles that put the tool tip at ``tip`` (m, (3,) or (N, 3)).

    The tip map is not one-to-one over the joint range (a crank at alpha and
    at 180 deg - alpha gives the same height), so damped Newton iterations
    with the analytic Jacobian start from ``alpha0`` (default: home) and from
    the eight corners of {65, 115} deg^3, all targets and starts at once; of
    the converged solutions inside the range, the one nearest ``alpha0`` is
    returned. ``tol`` (m) is the accepted tip residual; near the tip map's
    singular surfaces Newton converges slowly, hence 1 micrometre by default.
    Raises ``ValueError`` if a target is not reached.
    """
    g = geometry
    target = np.atleast_2d(np.asarray(tip, float))
    if target.ndim != 2 or target.shape[1] != 3 or not np.all(np.isfinite(target)):
        raise ValueError(f"tip must be finite with shape (3,) or (N, 3); got {np.shape(tip)}")
    ref = np.broadcast_to(g.alpha_home if alpha0 is None else np.asarray(alpha0, float),
                          target.shape)
    corners = np.array(np.meshgrid(*[[65 * DEG, 115 * DEG]] * 3, indexing="ij")).reshape(3, -1).T
    n, m = len(target), 1 + len(corners)
    starts = np.concatenate([ref[:, None], np.broadcast_to(corners, (n, m - 1, 3))], axis=1)
    al = starts.reshape(-1, 3).copy()
    goal = np.repeat(target, m, axis=0)
    lo, hi = g.alpha_min - 5 * DEG, g.alpha_max + 5 * DEG
    for _ in range(max_iter):
        err = goal - tool_tip(forward(al, g, validate=False), g)
        if np.max(np.abs(err)) < 1e-3 * tol:
            break
        _, j_tip = jacobian(al, g, validate=False)
        step = _solve_damped(j_tip, err)
        al = np.clip(al + np.clip(step, -10 * DEG, 10 * DEG), lo, hi)
    res = np.linalg.norm(goal - tool_tip(forward(al, g, validate=False), g), axis=1)
    inside = (al >= g.alpha_min - 1e-9).all(axis=1) & (al <= g.alpha_max + 1e-9).all(axis=1)
    ok = ((res < tol) & inside).reshape(n, m)
    if not ok.any(axis=1).all():
        worst = res.reshape(n, m).min(axis=1).max()
        raise ValueError(f"tool tip target not reachable inside the joint range: residual {worst:.3g} m")
    dist = np.linalg.norm(al.reshape(n, m, 3) - ref[:, None], axis=2)
    best = np.argmin(np.where(ok, dist, np.inf), axis=1)
    return np.clip(al.reshape(n, m, 3)[np.arange(n), best], g.alpha_min, g.alpha_max)


def _solve_damped(jac: np.ndarray, err: np.ndarray, damping: float = 1e-6) -> np.ndarray:
    """Levenberg-Marquardt step (J^T J + l I)^-1 J^T e, batched over the first axis."""
    jt = np.swapaxes(jac, 1, 2)
    lhs = jt @ jac + damping * np.eye(jac.shape[2])
    return np.linalg.solve(lhs, (jt @ err[..., None]))[..., 0]


# --- parts: every link as a box or cylinder, for drawing and collision -------------


def part_shapes(geometry: CaPaManGeometry = DEFAULT_GEOMETRY) -> tuple[PartShape, ...]:
    """The 17 parts: per leg two cranks, coupler, connecting bar, slider rail;
    then the movable plate and the tool rod. Order matches :func:`part_frames`."""
    g = geometry
    hw = g.link_width / 2
    parts: list[PartShape] = []
    for k in range(1, 4):
        parts += [
            PartShape(f"leg{k}_crank_a", "box", (hw, hw, g.a / 2)),
            PartShape(f"leg{k}_crank_b", "box", (hw, hw, g.a / 2)),
            PartShape(f"leg{k}_coupler", "box", (hw, hw, g.c / 2)),
            PartShape(f"leg{k}_bar", "box", (hw, hw, g.h / 2)),
            PartShape(f"leg{k}_rail", "box", (hw, hw, g.rail_length / 2)),
        ]
    parts.append(PartShape("plate", "cylinder", radius=g.r_p, length=g.plate_thickness))
    parts.append(PartShape("tool", "cylinder", radius=g.tool_radius, length=g.tool_length))
    return tuple(parts)


def _frame(z_axis: np.ndarray, x_hint: np.ndarray) -> np.ndarray:
    """Rotation matrix with columns (x, y, z): z given, x = x_hint orthogonalised."""
    x = x_hint - np.dot(x_hint, z_axis) * z_axis
    x = x / np.linalg.norm(x)
    return np.column_stack([x, np.cross(z_axis, x), z_axis])


@lru_cache(maxsize=32)
def _leg_part_table(g: CaPaManGeometry) -> SimpleNamespace:
    """Affine description of the 15 leg parts in their crank angle.

    A leg part's centre is ``c0 + c1 cos(alpha_k) + c2 sin(alpha_k)``; a crank's
    frame is ``Rot(w_k, -alpha_k) F0`` (F0 = columns w_k, z, u_k), so its
    quaternion is ``qc cos(alpha_k/2) + qs sin(alpha_k/2)``; coupler, bar and
    rail keep a constant orientation (qs = 0 and the half angle forced to 0).
    """
    zhat = np.array([0.0, 0.0, 1.0])
    c0, c1, c2, qc, qs, leg, crank = [], [], [], [], [], [], []
    for k in range(3):
        e, u, w = g.e[k], g.u[k], g.w[k]
        root, half_c = g.r_f * e, (g.c / 2) * u
        q_f0 = matrix_to_quat(np.column_stack([w, zhat, u]))
        q_turn = quat_multiply(np.append(-w, 0.0), q_f0)  # d/d(sin(alpha/2)) of the crank
        for sign in (-1.0, 1.0):  # cranks a and b
            c0.append(root + sign * half_c)
            c1.append((g.a / 2) * u)
            c2.append((g.a / 2) * zhat)
            qc.append(q_f0)
            qs.append(q_turn)
            crank.append(True)
        for offset, rot in ((0.0, _frame(u, w)), (g.h / 2, _frame(zhat, u)), (g.h, _frame(w, u))):
            c0.append(root + offset * zhat)  # coupler, bar, rail
            c1.append(g.a * u)
            c2.append(g.a * zhat)
            qc.append(matrix_to_quat(rot))
            qs.append(np.zeros(4))
            crank.append(False)
        leg += [k] * 5
    return SimpleNamespace(c0=np.array(c0), c1=np.array(c1), c2=np.array(c2), qc=np.array(qc),
                           qs=np.array(qs), leg=np.array(leg), crank=np.array(crank, float))


@lru_cache(maxsize=32)
def part_table(g: CaPaManGeometry) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                            np.ndarray, np.float64]:
    """The leg parts' affine table (:func:`_leg_part_table`) as :func:`k_part_frames` takes it: c0, c1, c2
    (15, 3) m, qc, qs (15, 4), the leg of each part (15,) and whether it is a crank (15,); and L_tool / 2 (m)."""
    t = _leg_part_table(g)
    return (t.c0, t.c1, t.c2, t.qc, t.qs, t.leg.astype(np.int64), t.crank.astype(np.bool_),
            np.float64(g.tool_length / 2))


@njit(cache=True, error_model="numpy", inline="always")
def k_part_frames(trig, position, quat, c0, c1, c2, qc, qs, leg, crank, tool_half, centres, quats):
    """Centres (17, 3) and quaternions (17, 4) of every part at one configuration, written into
    ``centres`` and ``quats``: ``trig`` (4, 3) holds cos alpha_k, sin alpha_k, cos alpha_k/2, sin alpha_k/2;
    ``position`` and ``quat`` are the plate's pose (:func:`k_forward`); the rest is :func:`part_table`."""
    for j in range(leg.shape[0]):
        k = leg[j]
        c, s = trig[0, k], trig[1, k]
        hc, hs = (trig[2, k], trig[3, k]) if crank[j] else (1.0, 0.0)
        for d in range(3):
            centres[j, d] = c0[j, d] + c1[j, d] * c + c2[j, d] * s
        for d in range(4):
            quats[j, d] = qc[j, d] * hc + qs[j, d] * hs
    plate, tool = leg.shape[0], leg.shape[0] + 1
    x, y, z, w = quat[0], quat[1], quat[2], quat[3]
    axis = (2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y))  # R z, as quat_to_matrix has it
    for d in range(3):
        centres[plate, d] = position[d]
        centres[tool, d] = position[d] - tool_half * axis[d]
    for d in range(4):
        quats[plate, d] = quat[d]
        quats[tool, d] = quat[d]


def crank_trig(alpha: np.ndarray) -> np.ndarray:
    """cos alpha, sin alpha, cos alpha/2, sin alpha/2 of configurations (N, 3), as (N, 4, 3) (numpy's
    ufuncs, so that every caller gets the same floats)."""
    return np.stack([np.cos(alpha), np.sin(alpha), np.cos(0.5 * alpha), np.sin(0.5 * alpha)], axis=1)


@njit(cache=True, error_model="numpy")
def _part_frames_all(trig, position, quat, c0, c1, c2, qc, qs, leg, crank, tool_half, centres, quats):
    for i in range(trig.shape[0]):
        k_part_frames(trig[i], position[i], quat[i], c0, c1, c2, qc, qs, leg, crank, tool_half, centres[i],
                      quats[i])


def part_frames(alpha: np.ndarray, geometry: CaPaManGeometry = DEFAULT_GEOMETRY,
                pose: CaPaManPose | None = None, validate: bool = True
                ) -> tuple[np.ndarray, np.ndarray]:
    """Centres (N, 17, 3) and (x, y, z, w) quaternions (N, 17, 4) of every part.

    Order of :func:`part_shapes`. Each part's local z runs along its long axis
    (cranks along cos(alpha) u_k + sin(alpha) z, coupler along u_k, bar along
    z, rail along w_k, plate and tool along the plate normal R z). ``pose``
    may be passed when the direct kinematics is already known. One compiled
    loop (:func:`k_part_frames`), which the grid's clearance kernel also runs.
    """
    g = geometry
    al = check_joint_angles(alpha, g) if validate else np.atleast_2d(np.asarray(alpha, float))
    al = np.ascontiguousarray(al, float)
    if pose is None:
        pose = forward(al, g, validate=False)
    n, table = len(al), part_table(g)
    parts = len(_leg_part_table(g).leg) + 2  # the leg parts (cached table), the plate and the tool
    centres, quats = np.empty((n, parts, 3)), np.empty((n, parts, 4))
    _part_frames_all(crank_trig(al), np.ascontiguousarray(pose.position), np.ascontiguousarray(pose.quaternion),
                     *table, centres, quats)
    return centres, quats


@lru_cache(maxsize=8)
def swept_part_boxes(geometry: CaPaManGeometry = DEFAULT_GEOMETRY, samples_per_axis: int = 7
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Boxes (lower and upper corners, (17, 3), m) that hold each part over the whole joint range.

    Each part's world bounding box is taken at a grid of ``samples_per_axis``^3
    configurations and the union is grown by the largest change of a box
    corner between neighbouring samples (a margin for what happens between
    samples; the tests check it against dense sampling).
    """
    g = geometry
    axis = np.linspace(g.alpha_min, g.alpha_max, samples_per_axis)
    alpha = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    centres, quats = part_frames(alpha, g, validate=False)
    half = np.array([s.half_extents if s.kind == "box" else (s.radius, s.radius, s.length / 2)
                     for s in part_shapes(g)])
    extent = np.abs(quat_to_matrix(quats)) @ half[..., None]  # world AABB half sizes
    lo_s, hi_s = centres - extent[..., 0], centres + extent[..., 0]  # (samples, parts, 3)
    cube = (samples_per_axis,) * 3 + lo_s.shape[1:]
    # Margin per part: the largest change of a box corner between neighbouring samples.
    step = np.max([np.abs(np.diff(b.reshape(cube), axis=ax)).max(axis=(0, 1, 2, 4))
                   for b in (lo_s, hi_s) for ax in range(3)], axis=0)
    return lo_s.min(axis=0) - step[:, None], hi_s.max(axis=0) + step[:, None]
