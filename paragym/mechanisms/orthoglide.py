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

SI units (m, rad). Batched functions take rho (N, 3) and table-frame points
(N, 2); the ``*_one`` functions are the per-step path in Python floats.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.optimize import minimize

__all__ = ["OrthoglideGeometry", "check_joints", "fixed_point", "forward", "inverse", "inverse_one",
           "isotropic_point", "jacobian", "jacobian_one", "kappa", "kappa_gradient", "least_norm_one",
           "null_direction", "singularity", "within_limits"]


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


def fixed_point(rho1: np.ndarray, p: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """C in the fixed frame (N, 2) for table positions rho1 (N,) and table-frame points p (N, 2)."""
    return np.asarray(geometry.table_origin) + np.asarray(rho1)[..., None] * geometry.direction + np.asarray(p)


def inverse(rho1: np.ndarray, p: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
            ) -> tuple[np.ndarray, np.ndarray]:
    """rho (N, 3) putting C on table point p (N, 2) with the table at rho1 (N,),
    in the working mode, and whether that is possible (N,). The working mode:
    C to the right of A and above B, and det A = r4 x r5 > 0 (the branch of
    the isotropic pose; det A = 0 is the parallel singularity between the
    branches). Joint limits are checked apart, by :func:`within_limits`."""
    g = geometry
    c = fixed_point(rho1, p, g)
    cx, cy = c[..., 0], c[..., 1]
    sx, sy = np.sqrt(np.clip(g.link ** 2 - cy ** 2, 0, None)), np.sqrt(np.clip(g.link ** 2 - cx ** 2, 0, None))
    # working mode: C right of A and above B (r4_x, r5_y > 0) with det A = r4 x r5 = sx sy - cy cx > 0
    ok = (np.abs(cy) < g.link) & (np.abs(cx) < g.link) & (sx * sy - cy * cx > 0)
    rho2 = cx - sx - g.slider2_origin
    rho3 = cy - sy - g.slider3_origin
    return np.stack([np.broadcast_to(rho1, rho2.shape), rho2, rho3], axis=-1), ok


def within_limits(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Whether each rho (N, 3) is inside the joint limits."""
    return np.all((rho >= np.array(geometry.rho_min)) & (rho <= np.array(geometry.rho_max)), axis=-1)


def _links(rho: np.ndarray, g: OrthoglideGeometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """C (N, 2) and unit link vectors r4, r5 (N, 2) from rho (working mode)."""
    a = np.stack([g.slider2_origin + rho[..., 1], np.zeros_like(rho[..., 1])], -1)
    b = np.stack([np.zeros_like(rho[..., 2]), g.slider3_origin + rho[..., 2]], -1)
    m = 0.5 * (a + b)
    half = b - a
    dist = np.sqrt(half[..., 0] ** 2 + half[..., 1] ** 2)
    h = np.sqrt(g.link ** 2 - (dist / 2) ** 2 + 0j) if np.iscomplexobj(rho) else \
        np.sqrt(np.clip(g.link ** 2 - (dist / 2) ** 2, 0, None))
    perp = np.stack([half[..., 1], -half[..., 0]], -1) / dist[..., None]
    c = m + h[..., None] * perp
    other = m - h[..., None] * perp
    # the working mode: det A = r4 x r5 > 0 (see inverse)
    u, v = c - a, c - b
    mode = np.real(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]) > 0
    c = np.where(mode[..., None], c, other)
    return c, (c - a) / g.link, (c - b) / g.link


def forward(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """The tool point in the table frame (N, 2) from rho (N, 3)."""
    c, _, _ = _links(np.atleast_2d(rho), geometry)
    return c - fixed_point(np.atleast_2d(rho)[:, 0], np.zeros(2), geometry)


def jacobian(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A (N, 2, 2), B (N, 2, 3) and J = A^-1 B (N, 2, 3) at rho (N, 3) (eqs 1-3, 6)."""
    rho = np.atleast_2d(rho)
    _, r4, r5 = _links(rho, geometry)
    d = geometry.direction
    a = np.stack([r4, r5], axis=-2)
    zero = np.zeros_like(r4[..., 0])
    b = np.stack([np.stack([-(r4 @ d), r4[..., 0], zero], -1), np.stack([-(r5 @ d), zero, r5[..., 1]], -1)], -2)
    det = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    a_inv = np.stack([np.stack([a[..., 1, 1], -a[..., 0, 1]], -1), np.stack([-a[..., 1, 0], a[..., 0, 0]], -1)],
                     -2) / det[..., None, None]
    return a, b, a_inv @ b


def kappa(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """kappa(J) = sigma_max / sigma_min (eq 8) at rho (N, 3), from the
    eigenvalues of J J^T in closed form (works on complex input, for the
    complex-step derivative)."""
    _, _, j = jacobian(rho, geometry)
    m = j @ np.swapaxes(j, -1, -2)
    tr, det = m[..., 0, 0] + m[..., 1, 1], m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
    disc = np.sqrt((tr / 2) ** 2 - det + 0j) if np.iscomplexobj(m) else np.sqrt(np.clip((tr / 2) ** 2 - det, 0, None))
    return np.sqrt((tr / 2 + disc) / (tr / 2 - disc))


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
    """Unit vector n (N, 3) spanning the null space of J; the projector of
    eq 5 is ``I - J^+ J = n n^T``. Oriented so that the table's rate n_1 >= 0."""
    _, _, j = jacobian(rho, geometry)
    n = np.cross(j[..., 0, :], j[..., 1, :])
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    return n * np.where(n[..., :1] < 0, -1.0, 1.0)


def singularity(rho: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY, tol: float = 1e-3
                ) -> tuple[np.ndarray, np.ndarray]:
    """(parallel, serial) singularity flags (N,) (section 3.2): A singular when
    the links are parallel; B loses rank when r4 is orthogonal to the slider 2
    axis or r5 to the slider 3 axis."""
    with np.errstate(divide="ignore", invalid="ignore"):  # J itself is undefined at the parallel singularity
        a, _, _ = jacobian(rho, geometry)
    det = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    return np.abs(det) < tol, (np.abs(a[..., 0, 0]) < tol) | (np.abs(a[..., 1, 1]) < tol)


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


# --- one configuration in Python floats: the environment's per-step path -----------------


def inverse_one(rho1: float, px: float, py: float, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
                ) -> tuple[float, float, bool]:
    """:func:`inverse` for one point: (rho2, rho3, reachable)."""
    g = geometry
    d = _dir_one(g)
    cx = g.table_origin[0] + rho1 * d[0] + px
    cy = g.table_origin[1] + rho1 * d[1] + py
    if abs(cx) >= g.link or abs(cy) >= g.link:
        return math.nan, math.nan, False
    sx, sy = math.sqrt(g.link ** 2 - cy * cy), math.sqrt(g.link ** 2 - cx * cx)
    return cx - sx - g.slider2_origin, cy - sy - g.slider3_origin, sx * sy - cy * cx > 0


@lru_cache(maxsize=8)
def _dir_one(g: OrthoglideGeometry) -> tuple[float, float]:
    return math.cos(g.theta1), math.sin(g.theta1)


def jacobian_one(rho1: float, px: float, py: float, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
                 ) -> tuple[list[float], list[float], float, list[float]]:
    """J's two rows, kappa and the null direction n (n_1 >= 0) for the tool on
    table point (px, py) with the table at rho1 (working mode), in floats.
    The same equations as :func:`jacobian`, :func:`kappa`, :func:`null_direction`."""
    g = geometry
    d0, d1 = _dir_one(g)
    cx = g.table_origin[0] + rho1 * d0 + px
    cy = g.table_origin[1] + rho1 * d1 + py
    sx, sy = math.sqrt(g.link ** 2 - cy * cy), math.sqrt(g.link ** 2 - cx * cx)
    r4x, r4y = sx / g.link, cy / g.link  # C - A with A = (cx - sx, 0)
    r5x, r5y = cx / g.link, sy / g.link  # C - B with B = (0, cy - sy)
    b = [[-(r4x * d0 + r4y * d1), r4x, 0.0], [-(r5x * d0 + r5y * d1), 0.0, r5y]]
    det = r4x * r5y - r4y * r5x
    inv = [[r5y / det, -r4y / det], [-r5x / det, r4x / det]]
    j0 = [inv[0][0] * b[0][k] + inv[0][1] * b[1][k] for k in range(3)]
    j1 = [inv[1][0] * b[0][k] + inv[1][1] * b[1][k] for k in range(3)]
    m00 = j0[0] * j0[0] + j0[1] * j0[1] + j0[2] * j0[2]
    m11 = j1[0] * j1[0] + j1[1] * j1[1] + j1[2] * j1[2]
    m01 = j0[0] * j1[0] + j0[1] * j1[1] + j0[2] * j1[2]
    half = 0.5 * (m00 + m11)
    disc = math.sqrt(max(half * half - (m00 * m11 - m01 * m01), 0.0))
    kap = math.sqrt((half + disc) / (half - disc)) if half - disc > 0 else math.inf
    n = [j0[1] * j1[2] - j0[2] * j1[1], j0[2] * j1[0] - j0[0] * j1[2], j0[0] * j1[1] - j0[1] * j1[0]]
    norm = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2) * (-1.0 if n[0] < 0 else 1.0)
    return j0, j1, kap, [n[0] / norm, n[1] / norm, n[2] / norm]


def least_norm_one(j0: list[float], j1: list[float], tx: float, ty: float) -> list[float]:
    """J^+ t_dot = J^T (J J^T)^-1 t_dot for one configuration (eq 5's first term)."""
    m00 = j0[0] * j0[0] + j0[1] * j0[1] + j0[2] * j0[2]
    m11 = j1[0] * j1[0] + j1[1] * j1[1] + j1[2] * j1[2]
    m01 = j0[0] * j1[0] + j0[1] * j1[1] + j0[2] * j1[2]
    det = m00 * m11 - m01 * m01
    w0, w1 = (m11 * tx - m01 * ty) / det, (m00 * ty - m01 * tx) / det
    return [j0[k] * w0 + j1[k] * w1 for k in range(3)]


# --- many configurations, the same float formulas: the vector environment's per-step path ---


def inverse_rows(rho1: np.ndarray, px: np.ndarray, py: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`inverse_one` for arrays (N,): (rho2, rho3, reachable); NaN where out of reach."""
    g = geometry
    d0, d1 = _dir_one(g)
    cx = g.table_origin[0] + rho1 * d0 + px
    cy = g.table_origin[1] + rho1 * d1 + py
    inside = (np.abs(cx) < g.link) & (np.abs(cy) < g.link)
    with np.errstate(invalid="ignore"):
        sx, sy = np.sqrt(g.link ** 2 - cy * cy), np.sqrt(g.link ** 2 - cx * cx)
    r2 = np.where(inside, cx - sx - g.slider2_origin, np.nan)
    r3 = np.where(inside, cy - sy - g.slider3_origin, np.nan)
    return r2, r3, inside & (sx * sy - cy * cx > 0)


def _jacobian_rows(rho1: np.ndarray, px: np.ndarray, py: np.ndarray, g: OrthoglideGeometry) -> np.ndarray:
    """J (2, 3, N), component-major (each ``j[r, c]`` a contiguous (N,) array):
    the float formulas of :func:`jacobian_one`."""
    d0, d1 = _dir_one(g)
    cx = g.table_origin[0] + rho1 * d0 + px
    cy = g.table_origin[1] + rho1 * d1 + py
    with np.errstate(invalid="ignore", divide="ignore"):
        sx, sy = np.sqrt(g.link ** 2 - cy * cy), np.sqrt(g.link ** 2 - cx * cx)
        r4x, r4y = sx / g.link, cy / g.link
        r5x, r5y = cx / g.link, sy / g.link
        b00, b10 = -(r4x * d0 + r4y * d1), -(r5x * d0 + r5y * d1)
        det = r4x * r5y - r4y * r5x
        i00, i01, i10, i11 = r5y / det, -r4y / det, -r5x / det, r4x / det
        return np.array([[i00 * b00 + i01 * b10, i00 * r4x, i01 * r5y],
                         [i10 * b00 + i11 * b10, i10 * r4x, i11 * r5y]])


def _gram(j: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """J J^T's entries m00, m11, m01 (N,) from J (2, 3, N), summed as :func:`least_norm_one` sums."""
    (a0, a1, a2), (b0, b1, b2) = j
    return a0 * a0 + a1 * a1 + a2 * a2, b0 * b0 + b1 * b1 + b2 * b2, a0 * b0 + a1 * b1 + a2 * b2


def _kappa_of(j: np.ndarray) -> np.ndarray:
    """kappa (N,) of J (2, 3, N): the eigenvalues of J J^T in closed form (inf where singular)."""
    m00, m11, m01 = _gram(j)
    with np.errstate(invalid="ignore", divide="ignore"):
        half = 0.5 * (m00 + m11)
        disc = np.sqrt(np.maximum(half * half - (m00 * m11 - m01 * m01), 0.0))
        return np.where(half - disc > 0, np.sqrt((half + disc) / (half - disc)), np.inf)


def kappa_rows(rho1: np.ndarray, px: np.ndarray, py: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
               ) -> np.ndarray:
    """The kappa of :func:`jacobian_rows` alone (N,), for sweeps."""
    return _kappa_of(_jacobian_rows(rho1, px, py, geometry))


def jacobian_rows(rho1: np.ndarray, px: np.ndarray, py: np.ndarray, geometry: OrthoglideGeometry = DEFAULT_GEOMETRY
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`jacobian_one` for arrays (N,), component-major: J (2, 3, N),
    kappa (N,) (inf where J J^T is singular) and n (3, N). Rows out of reach
    give NaN. (Component-major because sums over an axis of three are slow
    in numpy; written out they also keep :func:`jacobian_one`'s order.)"""
    j = _jacobian_rows(rho1, px, py, geometry)
    (a0, a1, a2), (b0, b1, b2) = j
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
        norm = np.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        norm[n[0] < 0] *= -1.0
        n /= norm
    return j, _kappa_of(j), n


def least_norm_rows(j: np.ndarray, tx: np.ndarray, ty: np.ndarray) -> np.ndarray:
    """:func:`least_norm_one` for arrays: J^+ t_dot (3, N) from J (2, 3, N)."""
    m00, m11, m01 = _gram(j)
    det = m00 * m11 - m01 * m01
    w0, w1 = (m11 * tx - m01 * ty) / det, (m00 * ty - m01 * tx) / det
    return j[0] * w0 + j[1] * w1
