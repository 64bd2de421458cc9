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
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["FOOT", "TripodGeometry", "distances", "forward", "inverse", "plate_frame_units", "relocate"]

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


def plate_frame_units(eta: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Drive units D_i in the plate frame (N, 3, 3) from encoder angles eta (N, 3), rad (eqs 1-3)."""
    g = geometry
    eta = np.atleast_2d(eta)
    a = g.alphas
    reach = g.p / math.sqrt(3) + g.r * np.cos(eta)
    return np.stack([reach * np.cos(a), reach * np.sin(a), -g.r * np.sin(eta)], axis=-1)


def distances(units: np.ndarray) -> np.ndarray:
    """l_i = |D_(i-1) - D_(i+1)| (eqs 4, 5) for units (N, 3, 3): (N, 3)."""
    units = np.atleast_3d(units) if units.ndim == 2 else units
    return np.linalg.norm(np.roll(units, 1, axis=-2) - np.roll(units, -1, axis=-2), axis=-1)


def _kabsch(local: np.ndarray, world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R (N, 3, 3), t (N, 3) with world ~ R local + t (least squares, proper rotations)."""
    lc, wc = local.mean(axis=1), world.mean(axis=1)
    h = np.swapaxes(local - lc[:, None], 1, 2) @ (world - wc[:, None])
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(np.swapaxes(vt, 1, 2) @ np.swapaxes(u, 1, 2)))
    fix = np.ones((len(d), 3))
    fix[:, 2] = d
    rot = np.swapaxes(vt, 1, 2) @ (fix[:, :, None] * np.swapaxes(u, 1, 2))
    return rot, wc - np.einsum("nij,nj->ni", rot, lc)


def forward(units: np.ndarray, eta0: np.ndarray | None = None, geometry: TripodGeometry = DEFAULT_GEOMETRY,
            tol: float = 1e-13) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plate pose and eta from the units' world positions (N, 3, 3).

    Solves eq 4 = eq 5 for eta by Newton's method from ``eta0`` (default
    45 deg; pass the last eta to stay on its branch), then fits the plate.
    Returns eta (N, 3), the plate's rotation (N, 3, 3) and centre (N, 3).
    Raises ValueError if the distances cannot be met (legs too short).
    """
    units = np.asarray(units, float)
    units = units[None] if units.ndim == 2 else units
    target = distances(units)
    eta = np.full((len(units), 3), math.radians(45.0)) if eta0 is None else np.atleast_2d(eta0).astype(float)
    g = geometry
    a = g.alphas
    radial = np.stack([np.cos(a), np.sin(a), np.zeros(3)], axis=1)
    for _ in range(60):
        d = plate_frame_units(eta, g)
        r = distances(d) - target
        if np.max(np.abs(r)) < tol:
            break
        # analytic Jacobian: l_i = |D_(i-1) - D_(i+1)|, dD_j/deta_j = -r sin(eta_j) e_j - r cos(eta_j) w
        dd = -g.r * (np.sin(eta)[..., None] * radial + np.cos(eta)[..., None] * np.array([0.0, 0.0, 1.0]))
        diff = np.roll(d, 1, axis=-2) - np.roll(d, -1, axis=-2)  # D_(i-1) - D_(i+1)
        unit = diff / np.linalg.norm(diff, axis=-1, keepdims=True)
        jac = np.zeros(eta.shape + (3,))
        for i in range(3):  # l_i touches units i-1 (+) and i+1 (-)
            jac[:, i, (i - 1) % 3] = np.sum(unit[:, i] * dd[:, (i - 1) % 3], axis=-1)
            jac[:, i, (i + 1) % 3] = -np.sum(unit[:, i] * dd[:, (i + 1) % 3], axis=-1)
        eta = eta - np.linalg.solve(jac, r[..., None])[..., 0]
    if np.max(np.abs(distances(plate_frame_units(eta, geometry)) - target)) > 1e-9:
        raise ValueError("the units' distances cannot be met by legs of this length (forward kinematics)")
    rot, centre = _kabsch(plate_frame_units(eta, geometry), units)
    return eta, rot, centre


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


def relocate(units: np.ndarray, faulty: int, target: np.ndarray) -> np.ndarray:
    """The paper's correction (section 3): unit ``faulty`` (0-based) moved to
    the intersection of the circles, in the ground plane, about the other two
    units with radii the encoder distances ``target`` (eq 4's l, (3,)); of the
    two intersections the one nearer its odometric position. Units (3, 3)."""
    k = faulty
    i, j = (k - 1) % 3, (k + 1) % 3
    ri, rj = target[j], target[i]  # |D_k - D_i| is l_j (the distance opposite unit j), and vice versa
    pi_, pj = units[i, :2], units[j, :2]
    d = float(np.linalg.norm(pj - pi_))
    ri = math.sqrt(max(ri * ri - (units[k, 2] - units[i, 2]) ** 2, 0.0))
    rj = math.sqrt(max(rj * rj - (units[k, 2] - units[j, 2]) ** 2, 0.0))
    along = (ri * ri - rj * rj + d * d) / (2 * d)
    h = math.sqrt(max(ri * ri - along * along, 0.0))
    base = pi_ + along * (pj - pi_) / d
    perp = np.array([-(pj - pi_)[1], (pj - pi_)[0]]) / d
    candidates = [base + h * perp, base - h * perp]
    best = min(candidates, key=lambda c: float(np.linalg.norm(c - units[k, :2])))
    out = units.copy()
    out[k, :2] = best
    return out


def eta_one(units: np.ndarray, eta0: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY,
            tol: float = 1e-13) -> np.ndarray:
    """The eta of :func:`forward` for one configuration, in Python floats:
    Newton's method on eq 4 = eq 5 with the analytic Jacobian and Cramer's
    rule (the per-sample path of the drive simulation; tested equal). Row i
    of the residual is the distance between units i - 1 and i + 1."""
    ca0, ca1, ca2, sa0, sa1, sa2, base, r = _eta_consts(geometry)
    (u0x, u0y, u0z), (u1x, u1y, u1z), (u2x, u2y, u2z) = np.asarray(units, float).tolist()
    t0 = math.sqrt((u2x - u1x) ** 2 + (u2y - u1y) ** 2 + (u2z - u1z) ** 2)  # units 2 and 1
    t1 = math.sqrt((u0x - u2x) ** 2 + (u0y - u2y) ** 2 + (u0z - u2z) ** 2)  # units 0 and 2
    t2 = math.sqrt((u1x - u0x) ** 2 + (u1y - u0y) ** 2 + (u1z - u0z) ** 2)  # units 1 and 0
    e0, e1, e2 = (float(e) for e in eta0)
    for _ in range(NEWTON_ITERATIONS):
        s0, s1, s2, c0, c1, c2 = math.sin(e0), math.sin(e1), math.sin(e2), math.cos(e0), math.cos(e1), math.cos(e2)
        q0, q1, q2 = base + r * c0, base + r * c1, base + r * c2
        d0x, d0y, d0z, d1x, d1y, d1z = q0 * ca0, q0 * sa0, -r * s0, q1 * ca1, q1 * sa1, -r * s1
        d2x, d2y, d2z = q2 * ca2, q2 * sa2, -r * s2
        # d/d eta_k of unit k's position
        g0x, g0y, g0z, g1x, g1y, g1z = -r * s0 * ca0, -r * s0 * sa0, -r * c0, -r * s1 * ca1, -r * s1 * sa1, -r * c1
        g2x, g2y, g2z = -r * s2 * ca2, -r * s2 * sa2, -r * c2
        f0x, f0y, f0z = d2x - d1x, d2y - d1y, d2z - d1z  # row 0: prev = 2, next = 1
        f1x, f1y, f1z = d0x - d2x, d0y - d2y, d0z - d2z  # row 1: prev = 0, next = 2
        f2x, f2y, f2z = d1x - d0x, d1y - d0y, d1z - d0z  # row 2: prev = 1, next = 0
        l0 = math.sqrt(f0x * f0x + f0y * f0y + f0z * f0z)
        l1 = math.sqrt(f1x * f1x + f1y * f1y + f1z * f1z)
        l2 = math.sqrt(f2x * f2x + f2y * f2y + f2z * f2z)
        r0, r1, r2 = l0 - t0, l1 - t1, l2 - t2
        if max(abs(r0), abs(r1), abs(r2)) < tol:
            break
        j02 = (f0x * g2x + f0y * g2y + f0z * g2z) / l0
        j01 = -(f0x * g1x + f0y * g1y + f0z * g1z) / l0
        j10 = (f1x * g0x + f1y * g0y + f1z * g0z) / l1
        j12 = -(f1x * g2x + f1y * g2y + f1z * g2z) / l1
        j21 = (f2x * g1x + f2y * g1y + f2z * g1z) / l2
        j20 = -(f2x * g0x + f2y * g0y + f2z * g0z) / l2
        # Cramer's rule with a zero diagonal
        det = -j01 * (-j12 * j20) + j02 * (j10 * j21)
        e0 -= ((-j12 * j21) * r0 + (j02 * j21) * r1 + (j01 * j12) * r2) / det
        e1 -= ((j12 * j20) * r0 + (-j02 * j20) * r1 + (j02 * j10) * r2) / det
        e2 -= ((j10 * j21) * r0 + (j01 * j20) * r1 + (-j01 * j10) * r2) / det
    else:  # no exact eta: the units stand where the legs cannot reach
        return _eta_least_squares(np.array([[t0, t1, t2]]), np.asarray(eta0, float)[None], geometry)[0]
    return np.array([e0, e1, e2])


def _eta_least_squares(target: np.ndarray, eta0: np.ndarray, geometry: TripodGeometry,
                       iterations: int = 30) -> np.ndarray:
    """The eta (M, 3) whose eq-4 distances come closest to ``target`` (M, 3)
    in least squares, by Levenberg's method from ``eta0`` (M, 3), all rows
    at once: what the encoders read when the units stand farther apart, or
    closer, than the legs can reach (the drive simulation moves the units
    independently, so a push or a slip can do that). Newton's method has no
    root to find there and wanders off; :func:`eta_one` and :func:`eta_rows`
    both end here instead, so that they still agree. A row stops when its
    gradient is below 1e-12 or an accepted step below 1e-9 rad (the encoders'
    noise is 1 deg; or after ``iterations``), and then stays as it is."""
    prev, nxt, rows3 = np.array([2, 0, 1]), np.array([1, 2, 0]), np.arange(3)

    def residual(eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        length, a, b = _distance_rows(eta, geometry)
        jac = np.zeros(eta.shape + (3,))
        jac[:, rows3, prev], jac[:, rows3, nxt] = a, b
        return length - target, jac

    eta = np.array(eta0, float)
    res, jac = residual(eta)
    cost = np.sum(res * res, axis=1)
    lam = np.full(len(eta), 1e-3)
    eye = np.eye(3)
    live = np.ones(len(eta), bool)  # rows still moving; a row that stops stays put (its answer is its own)
    for _ in range(iterations):
        jtj = np.swapaxes(jac, 1, 2) @ jac
        grad = np.einsum("nij,ni->nj", jac, res)
        live &= np.abs(grad).max(axis=1) >= 1e-12  # at its minimum
        if not live.any():
            break
        # Levenberg's damping, lam times the mean curvature (one direction may have almost none, which
        # Marquardt's per-direction scaling would let run away)
        size = np.trace(jtj, axis1=1, axis2=2) / 3.0 + 1e-12
        step = -np.linalg.solve(jtj + (lam * size)[:, None, None] * eye, grad[..., None])[..., 0]
        new_res, new_jac = residual(eta + step)
        new_cost = np.sum(new_res * new_res, axis=1)
        better = live & (new_cost < cost)
        eta = np.where(better[:, None], eta + step, eta)
        res, jac = np.where(better[:, None], new_res, res), np.where(better[:, None, None], new_jac, jac)
        cost = np.where(better, new_cost, cost)
        lam = np.where(better, lam * 0.1, lam * 10.0)
        live &= ~(better & (np.abs(step).max(axis=1) < 1e-9))  # an accepted step this small: converged
    return eta


@lru_cache(maxsize=8)
def _eta_consts(g: TripodGeometry) -> tuple[float, ...]:
    ca = [math.cos(a) for a in g.alphas]
    sa = [math.sin(a) for a in g.alphas]
    return (*ca, *sa, g.p / math.sqrt(3), g.r)


def distances_one(units: np.ndarray) -> list[float]:
    """:func:`distances` for one configuration (3, 3), in Python floats."""
    u = np.asarray(units, float).tolist()
    return [math.dist(u[(i - 1) % 3], u[(i + 1) % 3]) for i in range(3)]


def encoder_distances_one(eta: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY) -> list[float]:
    """Eq 4 for one set of encoder angles: the inter-unit distances, in Python floats."""
    g = geometry
    base = g.p / math.sqrt(3)
    pts = [((base + g.r * math.cos(e)) * math.cos(a), (base + g.r * math.cos(e)) * math.sin(a), -g.r * math.sin(e))
           for e, a in zip(eta, g.alphas, strict=True)]
    return [math.dist(pts[(i - 1) % 3], pts[(i + 1) % 3]) for i in range(3)]


def _distance_rows(eta: np.ndarray, g: TripodGeometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eq 4 for encoder angles (M, 3): the distances (M, 3), row i between
    units i - 1 and i + 1, and the nonzero entries of their Jacobian, d
    length_i / d eta at unit i - 1 (a) and at unit i + 1 (b) (M, 3 each).
    Coordinates as separate arrays: sums over an axis of three are slow in
    numpy, and written out they keep :func:`eta_one`'s order."""
    ca, sa = np.cos(np.asarray(g.alphas)), np.sin(np.asarray(g.alphas))
    base, r = g.p / math.sqrt(3), g.r
    prev, nxt = np.array([2, 0, 1]), np.array([1, 2, 0])
    se, ce = np.sin(eta), np.cos(eta)
    reach = base + r * ce
    dx, dy, dz = reach * ca, reach * sa, -r * se
    ex, ey, ez = -r * se * ca, -r * se * sa, -r * ce  # d/d eta_k of unit k's joint
    fx, fy, fz = dx[:, prev] - dx[:, nxt], dy[:, prev] - dy[:, nxt], dz[:, prev] - dz[:, nxt]
    length = np.sqrt(fx * fx + fy * fy + fz * fz)
    a = (fx * ex[:, prev] + fy * ey[:, prev] + fz * ez[:, prev]) / length
    b = -(fx * ex[:, nxt] + fy * ey[:, nxt] + fz * ez[:, nxt]) / length
    return length, a, b


def eta_rows(units: np.ndarray, eta0: np.ndarray, geometry: TripodGeometry = DEFAULT_GEOMETRY,
             tol: float = 1e-13) -> np.ndarray:
    """:func:`eta_one` for N configurations (N, 3, 3) from guesses (N, 3): the
    same Newton iteration (:func:`_distance_rows`), each row stopping where
    :func:`eta_one` would."""
    prev, nxt = np.array([2, 0, 1]), np.array([1, 2, 0])  # (i - 1) % 3 and (i + 1) % 3
    u = units[:, prev] - units[:, nxt]
    target = np.sqrt(u[..., 0] * u[..., 0] + u[..., 1] * u[..., 1] + u[..., 2] * u[..., 2])
    eta = np.array(eta0, float)
    active = np.arange(len(eta))
    for _ in range(NEWTON_ITERATIONS):
        e = eta[active]
        length, a, b = _distance_rows(e, geometry)
        res = length - target[active]
        done = np.maximum(np.maximum(np.abs(res[:, 0]), np.abs(res[:, 1])), np.abs(res[:, 2])) < tol
        if done.all():
            break
        if done.any():  # carry on with the rows still moving (no copies while all of them are)
            keep = ~done
            e, res, a, b, active = e[keep], res[keep], a[keep], b[keep], active[keep]
        j00, j01, j02 = 0.0, b[:, 0], a[:, 0]
        j10, j11, j12 = a[:, 1], 0.0, b[:, 1]
        j20, j21, j22 = b[:, 2], a[:, 2], 0.0
        det = j00 * (j11 * j22 - j12 * j21) - j01 * (j10 * j22 - j12 * j20) + j02 * (j10 * j21 - j11 * j20)
        r0, r1, r2 = res[:, 0], res[:, 1], res[:, 2]
        step = np.stack([(j11 * j22 - j12 * j21) * r0 + (j02 * j21 - j01 * j22) * r1 + (j01 * j12 - j02 * j11) * r2,
                         (j12 * j20 - j10 * j22) * r0 + (j00 * j22 - j02 * j20) * r1 + (j02 * j10 - j00 * j12) * r2,
                         (j10 * j21 - j11 * j20) * r0 + (j01 * j20 - j00 * j21) * r1 + (j00 * j11 - j01 * j10) * r2],
                        -1)
        eta[active] = e - step / det[:, None]
    else:  # the rows without an exact eta (rare): as eta_one, the least-squares reading
        eta[active] = _eta_least_squares(target[active], np.asarray(eta0, float)[active], geometry)
    return eta
