"""Kinematics of the 2-dof Orthoglide (2PRR) assisted by a 1-dof table (paper 003).

Paper 003 (Moreno, Pamanes, Wenger, Chablat, "Global optimization of
performance of a 2PRR parallel manipulator for cooperative tasks"): two
sliders, A on the fixed x axis (rho2) and B on the fixed y axis (rho3), carry
links AC = BC = L = 1 m that meet at the tool point C; a table translating
along the direction theta1 (rho1) carries the work-piece. In the table frame
the tool moves with velocity ``t_dot = J rho_dot``, ``J = A^-1 B`` (eqs 1-6):

    A = [r4^T ; r5^T],  B = [[-r4 . d, r4_x, 0], [-r5 . d, 0, r5_y]]

with r4 = (C - A)/L, r5 = (C - B)/L unit link vectors and d the table's unit
direction (the table moving by +d moves C by -d relative to it).
kappa(J) = sigma_max / sigma_min (eq 8). The sliders' working mode has C to
the upper right of both (r4_x > 0, r5_y > 0).

The paper does not give theta1 or the sliders' origins. kappa depends on C's
position in the fixed frame only (through r4, r5) and on theta1; with a
table on one axis the exactly isotropic poses are isolated points
(:func:`isotropic_point`). The defaults come from a brute-force search over
theta1 (5 deg steps) and the table's origin (0.1 m steps) for the lowest
pointwise-best kappa along the paper's circle with the table inside its
travel: theta1 = 45 deg, table origin (0.0707, -0.3536) m, which gives a
pointwise-optimal kappa of at most 1.108 (mean 1.063); the sliders' origins
(-1.2 m on each axis) then keep rho2 and rho3 inside [0, 1.5] m for the
three cases of the paper.

SI units (m, rad). Every function takes N configurations at once: joint
values rho (N, 3), or a table position rho1 (N,) with table-frame points
(N, 2). The equations are written once, as scalar kernels compiled by numba
(``k_*``): the array functions here loop them over N, and the tasks' step
kernels call them per robot, so that one robot and 4096 run the same code.
:func:`kappa` also compiles for complex input (the complex-step gradient).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit
from scipy.optimize import minimize

__all__ = ["OrthoglideGeometry", "check_joints", "fixed_point", "forward", "inverse", "isotropic_point",
           "jacobian", "jacobian_at", "k_forward", "k_inverse", "k_jacobian", "k_least_norm", "kappa", "kappa_at",
           "kappa_gradient", "least_norm", "null_direction", "params", "singularity", "within_limits"]


@dataclass(frozen=True)
class OrthoglideGeometry:
    """Sizes and the choices the paper leaves open (m, rad; see the module docstring)."""

    link: float = 1.0
    theta1: float = math.radians(45.0)  # table direction (module docstring)
    table_origin: tuple[float, float] = (0.0707, -0.3536)  # table frame origin at rho1 = 0, fixed frame
    slider2_origin: float = -1.2  # A = (slider2_origin + rho2, 0)
    slider3_origin: float = -1.2  # B = (0, slider3_origin + rho3)
    rho_min: tuple[float, float, float] = (-1.0, 0.0, 0.0)
    rho_max: tuple[float, float, float] = (1.0, 1.5, 1.5)

    @property
    def direction(self) -> np.ndarray:
        """Unit direction d of the table."""
        return np.array([math.cos(self.theta1), math.sin(self.theta1)])


DEFAULT_GEOMETRY = OrthoglideGeometry()


def check_joints(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY, name: str = "rho") -> np.ndarray:
    """Validate joint values (3,) or (N, 3): finite and inside the limits."""
    arr = np.atleast_2d(np.asarray(rho, float))
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (3,) or (N, 3); got {np.shape(rho)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    lo, hi = np.array(geometry.rho_min), np.array(geometry.rho_max)
    if np.any(arr < lo - 1e-12) or np.any(arr > hi + 1e-12):
        raise ValueError(f"{name} outside the limits rho1 in [-1, 1] m, rho2 and rho3 in [0, 1.5] m")
    return arr


@lru_cache(maxsize=8)
def params(geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The geometry as the kernels take it: [L, table origin x, y, d_x, d_y,
    slider 2 origin, slider 3 origin] (read-only)."""
    g = geometry
    out = np.array([g.link, *g.table_origin, math.cos(g.theta1), math.sin(g.theta1), g.slider2_origin,
                    g.slider3_origin])
    out.setflags(write=False)
    return out


def fixed_point(rho1: np.ndarray, p: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """C in the fixed frame (N, 2) for table positions rho1 (N,) and table-frame points p (N, 2)."""
    return np.asarray(geometry.table_origin) + np.asarray(rho1)[..., None] * geometry.direction + np.asarray(p)


def within_limits(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Whether each rho (N, 3) is inside the joint limits."""
    return np.all((rho >= np.array(geometry.rho_min)) & (rho <= np.array(geometry.rho_max)), axis=-1)


# --- the equations, once: scalar kernels (float, and complex where the complex step needs it) -------


@njit(cache=True, error_model="numpy")
def k_inverse(rho1: float, px: float, py: float, p: np.ndarray) -> tuple[float, float, bool]:
    """Sliders (rho2, rho3) putting C on table point (px, py) with the table
    at rho1, and whether that is the working mode: C right of A and above B
    (r4_x, r5_y > 0) with det A = r4 x r5 = sx sy - cy cx > 0 (the branch of
    the isotropic pose; det A = 0 is the parallel singularity between the
    branches). NaN when C is out of the links' reach."""
    link = p[0]
    cx = p[1] + rho1 * p[3] + px
    cy = p[2] + rho1 * p[4] + py
    if not (abs(cx) < link and abs(cy) < link):
        return math.nan, math.nan, False
    sx, sy = math.sqrt(link * link - cy * cy), math.sqrt(link * link - cx * cx)
    return cx - sx - p[5], cy - sy - p[6], sx * sy - cy * cx > 0


@njit(cache=True, error_model="numpy")
def _j_of_links(r4x, r4y, r5x, r5y, d0, d1):  # float or complex (numba compiles each)
    """J = A^-1 B (eqs 1-6) from the unit link vectors r4, r5 and the table
    direction d, written out: A = [r4; r5], B = [[-r4.d, r4x, 0], [-r5.d, 0, r5y]]."""
    b00, b10 = -(r4x * d0 + r4y * d1), -(r5x * d0 + r5y * d1)
    det = r4x * r5y - r4y * r5x
    i00, i01, i10, i11 = r5y / det, -r4y / det, -r5x / det, r4x / det
    return i00 * b00 + i01 * b10, i00 * r4x, i01 * r5y, i10 * b00 + i11 * b10, i10 * r4x, i11 * r5y


@njit(cache=True, error_model="numpy")
def _kappa_of(j0, j1, j2, j3, j4, j5):
    """kappa(J) = sigma_max / sigma_min (eq 8) from J's rows (j0 j1 j2; j3 j4
    j5): the eigenvalues of J J^T in closed form; inf where J J^T is singular."""
    m00 = j0 * j0 + j1 * j1 + j2 * j2
    m11 = j3 * j3 + j4 * j4 + j5 * j5
    m01 = j0 * j3 + j1 * j4 + j2 * j5
    half = 0.5 * (m00 + m11)
    q = half * half - (m00 * m11 - m01 * m01)
    if q.real < 0:
        q = q - q  # a zero of q's type
    disc = np.sqrt(q)
    if (half - disc).real > 0:
        return np.sqrt((half + disc) / (half - disc))
    return (half - half) + math.inf


@njit(cache=True, error_model="numpy")
def _null_of(j0, j1, j2, j3, j4, j5):
    """The unit null vector n = J's two rows crossed, oriented with n_1 >= 0
    (the projector of eq 5 is I - J^+ J = n n^T)."""
    n0, n1, n2 = j1 * j5 - j2 * j4, j2 * j3 - j0 * j5, j0 * j4 - j1 * j3
    norm = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if n0.real < 0:
        norm = -norm
    return n0 / norm, n1 / norm, n2 / norm


@njit(cache=True, error_model="numpy")
def k_jacobian(rho1: float, px: float, py: float, p: np.ndarray):
    """J's six entries (row-major), kappa and n's three at the tool on table
    point (px, py) with the table at rho1 (working mode): the links from the
    inverse solution, r4 = (sx, cy) / L and r5 = (cx, sy) / L."""
    link = p[0]
    cx = p[1] + rho1 * p[3] + px
    cy = p[2] + rho1 * p[4] + py
    sx, sy = math.sqrt(link * link - cy * cy), math.sqrt(link * link - cx * cx)
    j0, j1, j2, j3, j4, j5 = _j_of_links(sx / link, cy / link, cx / link, sy / link, p[3], p[4])
    n0, n1, n2 = _null_of(j0, j1, j2, j3, j4, j5)
    return j0, j1, j2, j3, j4, j5, _kappa_of(j0, j1, j2, j3, j4, j5), n0, n1, n2


@njit(cache=True, error_model="numpy")
def k_least_norm(j0: float, j1: float, j2: float, j3: float, j4: float, j5: float, tx: float, ty: float
                 ) -> tuple[float, float, float]:
    """J^+ t_dot = J^T (J J^T)^-1 t_dot (eq 5's first term)."""
    m00 = j0 * j0 + j1 * j1 + j2 * j2
    m11 = j3 * j3 + j4 * j4 + j5 * j5
    m01 = j0 * j3 + j1 * j4 + j2 * j5
    det = m00 * m11 - m01 * m01
    w0, w1 = (m11 * tx - m01 * ty) / det, (m00 * ty - m01 * tx) / det
    return j0 * w0 + j3 * w1, j1 * w0 + j4 * w1, j2 * w0 + j5 * w1


@njit(cache=True, error_model="numpy")
def k_null_space_step(rho1: float, j: tuple[float, ...], n0: float, t: tuple[float, float], z: float, h: float,
                      point: tuple[float, float], p: np.ndarray) -> tuple[float, float, float]:
    """One step of eq 5 over ``h`` s: the table integrated along ``rho_dot_1 = (J^+ t_dot)_1 + z n_1`` (J's six
    entries ``j`` and n's first entry n0 where the step starts, t_dot = ``t`` (tx, ty) m/s, z the null-space
    rate in m/s), the sliders then by the inverse kinematics at the next path point ``point`` (px, py): the
    joints (m) that track the path exactly (NaN where the point is out of reach)."""
    j0, j1, j2, j3, j4, j5 = j
    tx, ty = t
    px, py = point
    t0, _, _ = k_least_norm(j0, j1, j2, j3, j4, j5, tx, ty)
    r1 = rho1 + h * (t0 + z * n0)
    r2, r3, _ = k_inverse(r1, px, py, p)
    return r1, r2, r3


@njit(cache=True, error_model="numpy")
def _links(rho1, rho2, rho3, p):
    """C (fixed frame) and the unit links r4 = (C - A) / L, r5 = (C - B) / L
    from the joints: the two circles of radius L about A = (s2 + rho2, 0) and
    B = (0, s3 + rho3) meet in two points; the working mode's has det A > 0."""
    link = p[0]
    ax, by = p[5] + rho2, p[6] + rho3
    mx, my = 0.5 * ax, 0.5 * by
    hx, hy = -ax, by  # B - A
    dist = np.sqrt(hx * hx + hy * hy)
    q = link * link - (dist / 2) * (dist / 2)
    if q.real < 0:
        q = q - q
    h = np.sqrt(q)
    ux, uy = hy / dist, -hx / dist
    cx, cy = mx + h * ux, my + h * uy
    if ((cx - ax) * (cy - by) - cy * cx).real <= 0:  # (C - A) x (C - B) <= 0: the other intersection
        cx, cy = mx - h * ux, my - h * uy
    return cx, cy, (cx - ax) / link, cy / link, cx / link, (cy - by) / link


@njit(cache=True, error_model="numpy")
def k_forward(rho1: float, rho2: float, rho3: float, p: np.ndarray) -> tuple[float, float]:
    """The tool point in the table frame from the joints."""
    cx, cy, _, _, _, _ = _links(rho1, rho2, rho3, p)
    return cx - (p[1] + rho1 * p[3]), cy - (p[2] + rho1 * p[4])


# --- the array functions: the kernels looped over N ------------------------------------------


@njit(cache=True, error_model="numpy")
def _inverse_all(rho1, px, py, p, out, ok):
    for i in range(len(rho1)):
        out[i, 0] = rho1[i]
        out[i, 1], out[i, 2], ok[i] = k_inverse(rho1[i], px[i], py[i], p)


@njit(cache=True, error_model="numpy")
def _at_point_all(rho1, px, py, p, j, kap, n):
    for i in range(len(rho1)):
        j[i, 0], j[i, 1], j[i, 2], j[i, 3], j[i, 4], j[i, 5], kap[i], n[i, 0], n[i, 1], n[i, 2] = \
            k_jacobian(rho1[i], px[i], py[i], p)


@njit(cache=True, error_model="numpy")
def _kappa_at_all(rho1, px, py, p, kap):
    for i in range(len(rho1)):
        kap[i] = k_jacobian(rho1[i], px[i], py[i], p)[6]


@njit(cache=True, error_model="numpy")
def _at_joints_all(rho, p, links, j, kap, n):
    """C, r4, r5 (N, 6), J (N, 6), kappa (N,) and n (N, 3) from joints (N, 3): float or complex."""
    for i in range(rho.shape[0]):
        cx, cy, r4x, r4y, r5x, r5y = _links(rho[i, 0], rho[i, 1], rho[i, 2], p)
        links[i, 0], links[i, 1], links[i, 2], links[i, 3], links[i, 4], links[i, 5] = cx, cy, r4x, r4y, r5x, r5y
        j0, j1, j2, j3, j4, j5 = _j_of_links(r4x, r4y, r5x, r5y, p[3], p[4])
        j[i, 0], j[i, 1], j[i, 2], j[i, 3], j[i, 4], j[i, 5] = j0, j1, j2, j3, j4, j5
        kap[i] = _kappa_of(j0, j1, j2, j3, j4, j5)
        n[i, 0], n[i, 1], n[i, 2] = _null_of(j0, j1, j2, j3, j4, j5)


@njit(cache=True, error_model="numpy")
def _least_norm_all(j, t, out):
    for i in range(j.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = k_least_norm(j[i, 0], j[i, 1], j[i, 2], j[i, 3], j[i, 4], j[i, 5],
                                                       t[i, 0], t[i, 1])


def _rows(*arrays: np.ndarray, dtype: type = float) -> list[np.ndarray]:
    """The arguments as contiguous 1-D arrays of one length (broadcast)."""
    return [np.ascontiguousarray(a, dtype) for a in np.broadcast_arrays(*(np.ravel(x) for x in arrays))]


def _at_joints(rho: np.ndarray, g: OrthoglideGeometry) -> tuple[np.ndarray, ...]:
    rho = np.ascontiguousarray(np.atleast_2d(rho))
    kind = complex if np.iscomplexobj(rho) else float
    rho = rho.astype(kind, copy=False)
    n = len(rho)
    links, j, kap, nv = np.empty((n, 6), kind), np.empty((n, 6), kind), np.empty(n, kind), np.empty((n, 3), kind)
    with np.errstate(all="ignore"):
        _at_joints_all(rho, params(g), links, j, kap, nv)
    return links, j.reshape(n, 2, 3), kap, nv


def inverse(rho1: np.ndarray, p: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
            ) -> tuple[np.ndarray, np.ndarray]:
    """rho (N, 3) putting C on table points p (N, 2) with the table at rho1
    (N,), in the working mode, and whether that is possible (N,) (NaN where
    C is out of reach; :func:`k_inverse`). Joint limits are checked apart, by
    :func:`within_limits`."""
    pts = np.asarray(p, float).reshape(-1, 2)
    r1, px, py = _rows(rho1, pts[:, 0], pts[:, 1])
    out, ok = np.empty((len(r1), 3)), np.empty(len(r1), bool)
    _inverse_all(r1, px, py, params(geometry), out, ok)
    return out, ok


def forward(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The tool point in the table frame (N, 2) from rho (N, 3)."""
    links, _, _, _ = _at_joints(rho, geometry)
    return links[:, :2] - fixed_point(np.atleast_2d(rho)[:, 0], np.zeros(2), geometry)


def jacobian(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A (N, 2, 2), B (N, 2, 3) and J = A^-1 B (N, 2, 3) at rho (N, 3) (eqs 1-3, 6)."""
    links, j, _, _ = _at_joints(rho, geometry)
    r4, r5 = links[:, 2:4], links[:, 4:6]
    d = geometry.direction
    zero = np.zeros(len(links))
    b = np.stack([np.stack([-(r4 @ d), r4[:, 0], zero], -1), np.stack([-(r5 @ d), zero, r5[:, 1]], -1)], -2)
    return np.stack([r4, r5], axis=-2), b, j


def kappa(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """kappa(J) (eq 8) at rho (N, 3); complex input gives the complex step."""
    return _at_joints(rho, geometry)[2]


def kappa_gradient(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY, h: float = 1e-20
                   ) -> np.ndarray:
    """d kappa / d rho (N, 3) by the complex step (exact to rounding)."""
    rho = np.atleast_2d(rho).astype(complex)
    out = np.empty(rho.shape)
    for k in range(3):  # three directions, each for the whole batch
        step = rho.copy()
        step[:, k] += 1j * h
        out[:, k] = kappa(step, geometry).imag / h
    return out


def null_direction(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Unit vector n (N, 3) spanning the null space of J, n_1 >= 0; the
    projector of eq 5 is ``I - J^+ J = n n^T``."""
    return _at_joints(rho, geometry)[3]


def jacobian_at(rho1: np.ndarray, px: np.ndarray, py: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """J (N, 2, 3), kappa (N,) and n (N, 3) for the tool on table points
    (px, py) (N,) with the table at rho1 (N,) (:func:`k_jacobian`): the
    env's parametrisation, where the path point is known."""
    r1, x, y = _rows(rho1, px, py)
    j, kap, n = np.empty((len(r1), 6)), np.empty(len(r1)), np.empty((len(r1), 3))
    with np.errstate(all="ignore"):
        _at_point_all(r1, x, y, params(geometry), j, kap, n)
    return j.reshape(-1, 2, 3), kap, n


def kappa_at(rho1: np.ndarray, px: np.ndarray, py: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
             ) -> np.ndarray:
    """The kappa of :func:`jacobian_at` alone (N,), for sweeps."""
    r1, x, y = _rows(rho1, px, py)
    kap = np.empty(len(r1))
    _kappa_at_all(r1, x, y, params(geometry), kap)
    return kap


def least_norm(j: np.ndarray, t: np.ndarray) -> np.ndarray:
    """J^+ t_dot (N, 3) for J (N, 2, 3) and task rates t_dot (N, 2) (:func:`k_least_norm`)."""
    jj = np.ascontiguousarray(np.reshape(j, (-1, 6)), float)
    tt = np.ascontiguousarray(np.broadcast_to(np.reshape(t, (-1, 2)), (len(jj), 2)), float)
    out = np.empty((len(jj), 3))
    _least_norm_all(jj, tt, out)
    return out


def singularity(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY, tol: float = 1e-3
                ) -> tuple[np.ndarray, np.ndarray]:
    """(parallel, serial) singularity flags (N,) (section 3.2): A singular when
    the links are parallel; B loses rank when r4 is orthogonal to the slider 2
    axis or r5 to the slider 3 axis."""
    links, _, _, _ = _at_joints(rho, geometry)
    r4x, r4y, r5x, r5y = links[:, 2], links[:, 3], links[:, 4], links[:, 5]
    return np.abs(r4x * r5y - r4y * r5x) < tol, (np.abs(r4x) < tol) | (np.abs(r5y) < tol)


@lru_cache(maxsize=8)
def isotropic_point(geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> tuple[float, float]:
    """The fixed-frame tool position C* where kappa(J) = 1 (J J^T proportional
    to the identity) nearest the fixed frame's origin: minima of kappa over C
    from a grid, polished by Nelder-Mead (kappa has a cone-shaped minimum
    there, so a derivative-free method suits it)."""
    g = geometry
    origin = np.asarray(g.table_origin)

    def k_at(c: np.ndarray) -> np.ndarray:
        rho, ok = inverse(np.zeros(len(c)), c - origin, g)
        with np.errstate(divide="ignore", invalid="ignore"):
            k = kappa(rho, g)
        return np.where(ok & np.isfinite(k), k, np.inf)

    x = np.linspace(-0.98, 0.98, 197)
    grid = np.stack(np.meshgrid(x, x), -1).reshape(-1, 2)
    k = k_at(grid)
    found = []
    for c0 in grid[np.argsort(k)[:40]]:  # polish the lowest grid points; keep the exact minima
        sol = minimize(lambda c: float(k_at(c[None])[0]), c0, method="Nelder-Mead",
                       options={"xatol": 1e-13, "fatol": 1e-15, "maxiter": 4000})
        if sol.fun - 1.0 < 1e-9:
            found.append(sol.x)
    if not found:
        raise ValueError("no isotropic pose in reach for this geometry")
    best = min(found, key=lambda c: float(np.hypot(*c)))  # the one nearest the fixed frame's origin
    return float(best[0]), float(best[1])
