"""Kinematics of the sensory-redundant mobile tripod (paper 004).

Paper 004 (Shoval and Shoham, "Sensory redundant parallel mobile
mechanism"): three drive units on the ground, each joined by a spherical
joint to a leg of fixed length r; each leg joins the upper plate (an
equilateral triangle of edge p) by a revolute joint whose encoder reads
eta_i. In the plate frame U-V-W (eqs 1-3)::

    D_i = (p / sqrt 3 + r cos eta_i) (cos alpha_i, sin alpha_i, 0) + (0, 0, -r sin eta_i)

so each leg moves in the vertical plane through the plate's centre and its
vertex, eta measured down from the plate's plane. Consistent forms of what
the paper prints (tested):

* alpha_i = pi/2 + (i + 1) 2 pi / 3 places the vertices at -30, 90 and
  210 deg, 120 deg apart (the printed ``cos alpha_ii`` of eq 1 is cos alpha_i);
* eq 4: l_i = |D_(i-1) - D_(i+1)|, the distance between the two units other
  than i (eq 5 the same from odometry);
* relocating a faulty unit k (section 3): it lies at distance l_(k+1) from
  D_(k-1) and l_(k-1) from D_(k+1) — the full inter-unit distances, not the
  halves l/2 the paper prints (tested: only the full distances put it back).

Forward kinematics from the three units' positions solves eq 4 = eq 5 for
eta (Newton, from the last eta so the branch stays continuous) and places
the plate by the rigid fit of its frame's D_i(eta) onto the world's
(Kabsch). Defaults: the paper's example, r = p = 5 ft = 1.524 m. SI units.

The equations are written once, as numba kernels (eqs 1-5 and the solve for
eta, :func:`k_eta`); the array functions loop them over N, and the drive
simulation calls them per robot, so that one robot and 4096 run the same code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit

from paragym.mechanisms.geometry import k_jacobi

__all__ = ["FOOT", "TripodGeometry", "distances", "eta", "forward", "inverse", "k_eta", "kernel_consts",
           "plate_fit", "plate_frame_units", "relocate"]

FOOT = 0.3048
#: Newton's iterations for eta (from the last sample's it converges in 3-5); a configuration that has not
#: converged by then is out of the legs' reach and gets the least-squares reading
NEWTON_ITERATIONS = 15


@dataclass(frozen=True)
class TripodGeometry:
    """Leg length r and plate edge p (m): the paper's example, 5 ft each."""

    r: float = 5 * FOOT
    p: float = 5 * FOOT

    def __post_init__(self) -> None:
        if not (self.r > 0 and self.p > 0):
            raise ValueError(f"r and p must be positive lengths; got r = {self.r}, p = {self.p}")

    @property
    def alphas(self) -> np.ndarray:
        """alpha_i = pi/2 + (i + 1) 2 pi / 3 for i = 1, 2, 3 (rad)."""
        return np.array([math.pi / 2 + (i + 1) * 2 * math.pi / 3 for i in (1, 2, 3)])


DEFAULT_GEOMETRY = TripodGeometry()


@lru_cache(maxsize=8)
def kernel_consts(g: TripodGeometry) -> np.ndarray:
    """The geometry as the kernels take it: cos alpha_i (3), sin alpha_i (3), p / sqrt 3, r (read-only)."""
    out = np.array([*(math.cos(a) for a in g.alphas), *(math.sin(a) for a in g.alphas), g.p / math.sqrt(3), g.r])
    out.setflags(write=False)
    return out


# --- the equations, once: numba kernels ---------------------------------------------------------


@njit(cache=True, error_model="numpy")
def k_unit(e, i, c):
    """D_i in the plate frame (eqs 1-3) at encoder angle e: (x, y, z)."""
    q = c[6] + c[7] * math.cos(e)
    return q * c[i], q * c[3 + i], -c[7] * math.sin(e)


@njit(cache=True, error_model="numpy")
def k_distances(units):
    """Eqs 4, 5: l_i = |D_(i-1) - D_(i+1)| for units (3, 3): (l_0, l_1, l_2)."""
    (u0x, u0y, u0z), (u1x, u1y, u1z), (u2x, u2y, u2z) = units[0], units[1], units[2]
    return (math.sqrt((u2x - u1x) ** 2 + (u2y - u1y) ** 2 + (u2z - u1z) ** 2),
            math.sqrt((u0x - u2x) ** 2 + (u0y - u2y) ** 2 + (u0z - u2z) ** 2),
            math.sqrt((u1x - u0x) ** 2 + (u1y - u0y) ** 2 + (u1z - u0z) ** 2))


@njit(cache=True, error_model="numpy")
def _lengths(e0, e1, e2, c):
    """Eq 4 at encoder angles e: the distances (l_0, l_1, l_2), row i between
    units i - 1 and i + 1, and the nonzero entries of their Jacobian: d l_i /
    d eta at unit i - 1 (a_i) and at unit i + 1 (b_i)."""
    r = c[7]
    s0, s1, s2, c0, c1, c2 = math.sin(e0), math.sin(e1), math.sin(e2), math.cos(e0), math.cos(e1), math.cos(e2)
    q0, q1, q2 = c[6] + r * c0, c[6] + r * c1, c[6] + r * c2
    d0x, d0y, d0z, d1x, d1y, d1z = q0 * c[0], q0 * c[3], -r * s0, q1 * c[1], q1 * c[4], -r * s1
    d2x, d2y, d2z = q2 * c[2], q2 * c[5], -r * s2
    # d/d eta_k of unit k's position
    g0x, g0y, g0z, g1x, g1y, g1z = -r * s0 * c[0], -r * s0 * c[3], -r * c0, -r * s1 * c[1], -r * s1 * c[4], -r * c1
    g2x, g2y, g2z = -r * s2 * c[2], -r * s2 * c[5], -r * c2
    f0x, f0y, f0z = d2x - d1x, d2y - d1y, d2z - d1z  # row 0: prev = 2, next = 1
    f1x, f1y, f1z = d0x - d2x, d0y - d2y, d0z - d2z  # row 1: prev = 0, next = 2
    f2x, f2y, f2z = d1x - d0x, d1y - d0y, d1z - d0z  # row 2: prev = 1, next = 0
    l0 = math.sqrt(f0x * f0x + f0y * f0y + f0z * f0z)
    l1 = math.sqrt(f1x * f1x + f1y * f1y + f1z * f1z)
    l2 = math.sqrt(f2x * f2x + f2y * f2y + f2z * f2z)
    a0 = (f0x * g2x + f0y * g2y + f0z * g2z) / l0
    b0 = -(f0x * g1x + f0y * g1y + f0z * g1z) / l0
    a1 = (f1x * g0x + f1y * g0y + f1z * g0z) / l1
    b1 = -(f1x * g2x + f1y * g2y + f1z * g2z) / l1
    a2 = (f2x * g1x + f2y * g1y + f2z * g1z) / l2
    b2 = -(f2x * g0x + f2y * g0y + f2z * g0z) / l2
    return l0, l1, l2, a0, a1, a2, b0, b1, b2


@njit(cache=True, error_model="numpy")
def _jacobian(a0, a1, a2, b0, b1, b2, jac):
    """The 3x3 Jacobian of eq 4 (zero diagonal) into ``jac``."""
    jac[0, 0], jac[0, 1], jac[0, 2] = 0.0, b0, a0
    jac[1, 0], jac[1, 1], jac[1, 2] = a1, 0.0, b1
    jac[2, 0], jac[2, 1], jac[2, 2] = b2, a2, 0.0


@njit(cache=True, error_model="numpy")
def _solve3(a, b):
    """x with a x = b for a 3x3 system: LU with partial pivoting (as LAPACK's
    dgesv factors), written out so that the kernel needs no LAPACK (it
    compiles in a fraction of the time). ``a`` is overwritten."""
    x = b.copy()
    for k in range(2):
        p = k
        for i in range(k + 1, 3):
            if abs(a[i, k]) > abs(a[p, k]):
                p = i
        if p != k:
            for j in range(3):
                a[k, j], a[p, j] = a[p, j], a[k, j]
            x[k], x[p] = x[p], x[k]
        r = 1.0 / a[k, k]
        for i in range(k + 1, 3):
            a[i, k] *= r
            for j in range(k + 1, 3):
                a[i, j] -= a[i, k] * a[k, j]
    x[1] -= a[1, 0] * x[0]
    x[2] -= a[2, 0] * x[0] + a[2, 1] * x[1]
    x[2] /= a[2, 2]
    x[1] = (x[1] - a[1, 2] * x[2]) / a[1, 1]
    x[0] = (x[0] - a[0, 1] * x[1] - a[0, 2] * x[2]) / a[0, 0]
    return x


@njit(cache=True, error_model="numpy")
def _eta_least_squares(t0, t1, t2, eta, c, iterations, out):
    """The eta whose eq-4 distances come closest to (t0, t1, t2) in least
    squares, by Levenberg's method from ``eta`` (3,), into ``out``: what the
    encoders read when the units stand farther apart, or closer, than the
    legs can reach (the drive simulation moves the units independently, so a
    push or a slip can do that; Newton's method has no root there and wanders
    off). Stops when the gradient is below 1e-12 or an accepted step below
    1e-9 rad (the encoders' noise is 1 deg), or after ``iterations``.
    Levenberg's damping is lam times the mean curvature (one direction may
    have almost none, which Marquardt's per-direction scaling would let run
    away)."""
    e = eta.copy()
    jac = np.empty((3, 3))
    res, new_res, grad = np.empty(3), np.empty(3), np.empty(3)
    l0, l1, l2, a0, a1, a2, b0, b1, b2 = _lengths(e[0], e[1], e[2], c)
    res[0], res[1], res[2] = l0 - t0, l1 - t1, l2 - t2
    _jacobian(a0, a1, a2, b0, b1, b2, jac)
    cost = res[0] * res[0] + res[1] * res[1] + res[2] * res[2]
    lam = 1e-3
    system = np.empty((3, 3))
    for _ in range(iterations):
        for j in range(3):
            grad[j] = jac[0, j] * res[0] + jac[1, j] * res[1] + jac[2, j] * res[2]
        if max(abs(grad[0]), abs(grad[1]), abs(grad[2])) < 1e-12:  # at its minimum
            break
        for i in range(3):
            for j in range(3):
                system[i, j] = jac[0, i] * jac[0, j] + jac[1, i] * jac[1, j] + jac[2, i] * jac[2, j]
        size = (system[0, 0] + system[1, 1] + system[2, 2]) / 3.0 + 1e-12
        for i in range(3):
            system[i, i] += lam * size
        step = -_solve3(system, grad)
        l0, l1, l2, a0, a1, a2, b0, b1, b2 = _lengths(e[0] + step[0], e[1] + step[1], e[2] + step[2], c)
        new_res[0], new_res[1], new_res[2] = l0 - t0, l1 - t1, l2 - t2
        new_cost = new_res[0] * new_res[0] + new_res[1] * new_res[1] + new_res[2] * new_res[2]
        if new_cost < cost:
            e += step
            _jacobian(a0, a1, a2, b0, b1, b2, jac)
            res[0], res[1], res[2] = new_res[0], new_res[1], new_res[2]  # by element: see the end
            cost = new_cost
            lam *= 0.1
            if max(abs(step[0]), abs(step[1]), abs(step[2])) < 1e-9:  # an accepted step this small: converged
                break
        else:
            lam *= 10.0
    # by element: numba compiles an array copied into a slice with a shape check that costs seconds of compile
    out[0], out[1], out[2] = e[0], e[1], e[2]


@njit(cache=True, error_model="numpy")
def k_eta(units, eta0, c, iterations, tol, out):
    """eta (into ``out`` (3,)) with eq 4 = eq 5 for the units (3, 3): Newton's
    method from ``eta0`` with the analytic Jacobian and Cramer's rule, each
    iteration first checking the residual against ``tol``; when no exact eta
    exists (not converged in ``iterations``), the least-squares reading
    (:func:`_eta_least_squares`, 30 iterations). Returns whether Newton converged."""
    t0, t1, t2 = k_distances(units)
    e0, e1, e2 = eta0[0], eta0[1], eta0[2]
    for _ in range(iterations):
        l0, l1, l2, j02, j10, j21, j01, j12, j20 = _lengths(e0, e1, e2, c)
        r0, r1, r2 = l0 - t0, l1 - t1, l2 - t2
        if max(abs(r0), abs(r1), abs(r2)) < tol:
            out[0], out[1], out[2] = e0, e1, e2
            return True
        # Cramer's rule with a zero diagonal
        det = -j01 * (-j12 * j20) + j02 * (j10 * j21)
        e0 -= ((-j12 * j21) * r0 + (j02 * j21) * r1 + (j01 * j12) * r2) / det
        e1 -= ((j12 * j20) * r0 + (-j02 * j20) * r1 + (j02 * j10) * r2) / det
        e2 -= ((j10 * j21) * r0 + (j01 * j20) * r1 + (-j01 * j10) * r2) / det
    _eta_least_squares(t0, t1, t2, eta0, c, 30, out)
    return False


@njit(cache=True, error_model="numpy")
def k_singled_out(eta, estimate, c, tolerance):
    """The paper's single-fault reading of eq 4 against eq 5: the distances l_i of the units at encoder angles
    ``eta`` (3,) (eqs 1-4) against those of the ``estimate`` (3, 3) (eq 5). One unit is faulty when exactly the
    two distances through it differ by more than ``tolerance`` (m): the one distance that agrees is the one that
    leaves it out. Its index, else -1 (the lowest index among equal differences)."""
    units = np.empty((3, 3))
    for i in range(3):
        units[i, 0], units[i, 1], units[i, 2] = k_unit(eta[i], i, c)
    t0, t1, t2 = k_distances(units)
    e0, e1, e2 = k_distances(estimate)
    d = (abs(e0 - t0), abs(e1 - t1), abs(e2 - t2))
    low = 0  # the smallest difference, then the second smallest (a stable order of the three)
    for i in (1, 2):
        if d[i] < d[low]:
            low = i
    second = -1
    for i in range(3):
        if i != low and (second < 0 or d[i] < d[second]):
            second = i
    return low if d[second] > tolerance and d[low] < tolerance else -1


@njit(cache=True, error_model="numpy")
def _eta_all(units, eta0, c, iterations, tol, out, converged):
    for i in range(units.shape[0]):
        converged[i] = k_eta(units[i], eta0[i], c, iterations, tol, out[i])


@njit(cache=True, error_model="numpy")
def _units_all(eta, c, out):
    for n in range(eta.shape[0]):
        for i in range(3):
            out[n, i, 0], out[n, i, 1], out[n, i, 2] = k_unit(eta[n, i], i, c)


@njit(cache=True, error_model="numpy")
def _distances_all(units, out):
    for n in range(units.shape[0]):
        out[n, 0], out[n, 1], out[n, 2] = k_distances(units[n])


def plate_frame_units(eta: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Drive units D_i in the plate frame (N, 3, 3) from encoder angles eta (N, 3), rad (eqs 1-3)."""
    eta = np.ascontiguousarray(np.atleast_2d(eta), float)
    out = np.empty((len(eta), 3, 3))
    _units_all(eta, kernel_consts(geometry), out)
    return out


def distances(units: np.ndarray) -> np.ndarray:
    """l_i = |D_(i-1) - D_(i+1)| (eqs 4, 5) for units (N, 3, 3) or (3, 3): (N, 3)."""
    units = np.ascontiguousarray(np.asarray(units, float).reshape(-1, 3, 3))
    out = np.empty((len(units), 3))
    _distances_all(units, out)
    return out


def eta(units: np.ndarray, eta0: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY,
        iterations: int = NEWTON_ITERATIONS, tol: float = 1e-13) -> tuple[np.ndarray, np.ndarray]:
    """eta (N, 3) with eq 4 = eq 5 for units (N, 3, 3), from guesses (N, 3)
    (:func:`k_eta`), and whether Newton's method converged (N,) (else the
    least-squares reading)."""
    units = np.ascontiguousarray(np.asarray(units, float).reshape(-1, 3, 3))
    # a writable copy: the drive simulation's k_eta takes writable guesses, and a read-only one is another compile
    eta0 = np.array(np.broadcast_to(np.asarray(eta0, float).reshape(-1, 3), (len(units), 3)), order="C")
    out, converged = np.empty((len(units), 3)), np.empty(len(units), bool)
    _eta_all(units, eta0, kernel_consts(geometry), iterations, tol, out, converged)
    return out, converged


@njit(cache=True, error_model="numpy")
def _k_fit(local, world, rot, shift):
    """The rigid motion that best places the points ``local`` (N, K, 3) onto ``world`` (N, K, 3), least
    squares, into ``rot`` (N, 3, 3) and ``shift`` (N, 3): Horn's closed form (J. Opt. Soc. Am. A 4, 1987): the
    rotation is the unit quaternion of the largest eigenvalue of the 4x4 matrix built from the centred
    points' cross-covariance, found by Jacobi rotations (:func:`paragym.mechanisms.geometry.k_jacobi`). The
    same least-squares rotation as Kabsch's SVD, without LAPACK, whose last bits depend on the CPU."""
    k = local.shape[1]
    s = np.empty((3, 3))
    m = np.empty((4, 4))
    vec = np.empty((4, 4))
    lc, wc = np.empty(3), np.empty(3)
    for n in range(local.shape[0]):
        for a in range(3):
            lc[a], wc[a] = 0.0, 0.0
            for j in range(k):
                lc[a] += local[n, j, a]
                wc[a] += world[n, j, a]
            lc[a] /= k
            wc[a] /= k
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for j in range(k):
                    acc += (local[n, j, a] - lc[a]) * (world[n, j, b] - wc[b])
                s[a, b] = acc
        sxx, sxy, sxz = s[0, 0], s[0, 1], s[0, 2]
        syx, syy, syz = s[1, 0], s[1, 1], s[1, 2]
        szx, szy, szz = s[2, 0], s[2, 1], s[2, 2]
        m[0, 0], m[0, 1], m[0, 2], m[0, 3] = sxx + syy + szz, syz - szy, szx - sxz, sxy - syx
        m[1, 1], m[1, 2], m[1, 3] = sxx - syy - szz, sxy + syx, szx + sxz
        m[2, 2], m[2, 3] = -sxx + syy - szz, syz + szy
        m[3, 3] = -sxx - syy + szz
        for a in range(4):
            for b in range(a):
                m[a, b] = m[b, a]
        k_jacobi(m, vec)
        best = 0
        for a in range(1, 4):
            if m[a, a] > m[best, best]:
                best = a
        w, x, y, z = vec[0, best], vec[1, best], vec[2, best], vec[3, best]
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / norm, x / norm, y / norm, z / norm
        r = rot[n]
        r[0, 0], r[0, 1], r[0, 2] = w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)
        r[1, 0], r[1, 1], r[1, 2] = 2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)
        r[2, 0], r[2, 1], r[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z
        for a in range(3):
            shift[n, a] = wc[a] - (r[a, 0] * lc[0] + r[a, 1] * lc[1] + r[a, 2] * lc[2])


def _kabsch(local: np.ndarray, world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R (N, 3, 3), t (N, 3) with world ~ R local + t (least squares, proper rotations; :func:`_k_fit`)."""
    local, world = np.ascontiguousarray(local, float), np.ascontiguousarray(world, float)
    rot, shift = np.empty((len(local), 3, 3)), np.empty((len(local), 3))
    _k_fit(local, world, rot, shift)
    return rot, shift


def plate_fit(units: np.ndarray, eta: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY
              ) -> tuple[np.ndarray, np.ndarray]:
    """The plate's rotation (N, 3, 3) and centre (N, 3) that best place its
    frame's units at ``eta`` (N, 3) (eqs 1-3) onto ``units`` (N, 3, 3), in the
    least-squares sense (Kabsch): defined for any units, consistent with the
    legs or not (an estimate's, say)."""
    units = np.asarray(units, float)
    units = units[None] if units.ndim == 2 else units
    return _kabsch(plate_frame_units(np.atleast_2d(eta), geometry), units)


def forward(units: np.ndarray, eta0: np.ndarray | None = None, geometry: TripodGeometry = DEFAULT_GEOMETRY,
            tol: float = 1e-13) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plate pose and eta from the units' world positions (N, 3, 3).

    Solves eq 4 = eq 5 for eta (:func:`k_eta`, up to 60 Newton iterations)
    from ``eta0`` (default 45 deg; pass the last eta to stay on its branch),
    then fits the plate. Returns eta (N, 3), the plate's rotation (N, 3, 3)
    and centre (N, 3). Raises ValueError if the distances cannot be met
    (legs too short).
    """
    units = np.asarray(units, float)
    units = units[None] if units.ndim == 2 else units
    guess = np.full((len(units), 3), math.radians(45.0)) if eta0 is None else eta0
    solved, _ = eta(units, guess, geometry, iterations=60, tol=tol)
    local = plate_frame_units(solved, geometry)
    if np.max(np.abs(distances(local) - distances(units))) > 1e-9:
        raise ValueError("the units' distances cannot be met by legs of this length (forward kinematics)")
    rot, centre = _kabsch(local, units)
    return solved, rot, centre


def inverse(rotation: np.ndarray, centre: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY,
            ground: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """eta (N, 3) and the units' world positions (N, 3, 3) for a plate pose
    (rotation (N, 3, 3), centre (N, 3)) with the units on the plane z = ground.
    Each leg's eta solves ``c_z + (p/sqrt 3 + r cos eta) e_z - r sin eta n_z = ground``
    (e the vertex's radial direction, n the plate normal, in the world), the
    root with the leg below the plate and pointing outward (eta in (0, pi/2])."""
    g = geometry
    rot = np.asarray(rotation, float).reshape(-1, 3, 3)
    centre = np.asarray(centre, float).reshape(-1, 3)
    a = g.alphas
    radial = np.stack([np.cos(a), np.sin(a), np.zeros(3)], axis=1)
    e = np.einsum("nij,kj->nki", rot, radial)  # (N, 3, 3)
    nz = rot[:, 2, 2][:, None]
    c = centre[:, 2:3] + g.p / math.sqrt(3) * e[..., 2] - ground  # A cos(eta) + B sin(eta) = -c / r
    amp, phase = np.hypot(e[..., 2], -nz), np.arctan2(-nz, e[..., 2])
    ratio = -c / (g.r * amp)
    if np.any(np.abs(ratio) > 1):
        raise ValueError("the plate is too high (or too tilted) for legs of this length to reach the ground")
    eta = phase + np.arccos(ratio)
    eta = np.where(eta > np.pi, eta - 2 * np.pi, eta)
    eta = np.where((eta < 0) | (eta > np.pi / 2 + 1e-9), phase - np.arccos(ratio), eta)
    units = np.einsum("nij,nkj->nki", rot, plate_frame_units(eta, g)) + centre[:, None]
    return eta, units


@njit(cache=True, error_model="numpy")
def k_relocate(units, faulty, target):
    """The paper's correction (section 3) for one unit: where unit ``faulty``
    must stand, in the ground plane, for its distances to the other two units
    of ``units`` (3, 3) to be the encoder distances ``target`` (eq 4's l, (3,)):
    the intersection of the circles about them, of the two the one nearer its
    current position. Returns (x, y)."""
    k = faulty
    i, j = (k + 2) % 3, (k + 1) % 3
    ri, rj = target[j], target[i]  # |D_k - D_i| is l_j (the distance opposite unit j), and vice versa
    px, py, qx, qy = units[i, 0], units[i, 1], units[j, 0], units[j, 1]
    d = math.hypot(qx - px, qy - py)
    ri = math.sqrt(max(ri * ri - (units[k, 2] - units[i, 2]) ** 2, 0.0))
    rj = math.sqrt(max(rj * rj - (units[k, 2] - units[j, 2]) ** 2, 0.0))
    along = (ri * ri - rj * rj + d * d) / (2 * d)
    h = math.sqrt(max(ri * ri - along * along, 0.0))
    bx, by = px + along * (qx - px) / d, py + along * (qy - py) / d
    nx, ny = -(qy - py) / d, (qx - px) / d
    ax, ay = bx + h * nx, by + h * ny
    cx, cy = bx - h * nx, by - h * ny
    if math.hypot(cx - units[k, 0], cy - units[k, 1]) < math.hypot(ax - units[k, 0], ay - units[k, 1]):
        return cx, cy
    return ax, ay


def relocate(units: np.ndarray, faulty: int, target: np.ndarray) -> np.ndarray:
    """The paper's correction (section 3): unit ``faulty`` (0-based) moved to
    the intersection of the circles, in the ground plane, about the other two
    units with radii the encoder distances ``target`` (eq 4's l, (3,)); of the
    two intersections the one nearer its odometric position
    (:func:`k_relocate`). Units (3, 3)."""
    out = np.array(units, float)
    out[faulty, :2] = k_relocate(np.ascontiguousarray(out), int(faulty), np.ascontiguousarray(target, float))
    return out
