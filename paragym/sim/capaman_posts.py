"""The CaPaMan's parts as capsules against capsule posts: the exact clearance of N robots at once.

The collision test of the CaPaMan's difficulty ladder (:mod:`paragym.tasks.capaman`). Every moving part but
the plate is replaced by the capsule that holds it: a link of square cross-section ``w`` by the capsule on
its axis of radius ``w / sqrt(2)`` (its corners touch it) and the same length, the tool rod by the capsule of
its own radius on its axis (5 mm more below the tip). The obstacles are vertical capsules
(:class:`~paragym.sim.obstacles.Capsule`), so every distance is the one between two segments less two radii,
in closed form (Ericson, *Real-Time Collision Detection*, 5.1.9): no grid, no sampling. The model is
conservative: where it says free, PyBullet's boxes and cylinders are free too.

The plate is left out, and :func:`plate_floor` says when that is exact: a post whose top is at least the
clearance cap below the lowest point the plate can reach is farther than the cap from it in every pose, and
the clearance is capped (the ladder's scenarios are checked for it).

:func:`post_clearance` places the parts with the closed-form kinematics
(:func:`paragym.mechanisms.capaman.k_forward`, :func:`~paragym.mechanisms.capaman.k_part_frames`) in one
compiled loop over the configurations: on every core numba has from :data:`PARALLEL_FROM` of them on, and
shared among paragym's worker threads from :data:`paragym.kernels.SPLIT_MIN_ROWS` on (:func:`_share`). A part
no post comes within the cap of in any pose (:func:`parts_in_reach`), or whose capsule's bounding box is farther
from a post's than the best distance so far, is skipped (exact: the answer is capped).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from numba import njit, prange

from paragym.kernels import concurrently, shares
from paragym.mechanisms import capaman

__all__ = ["PARALLEL_FROM", "POST_FIELDS", "forward_table", "k_post_clearance", "kernel_constants", "part_capsules",
           "parts_in_reach", "plate_floor", "post_ceiling", "post_clearance", "segment_distance"]

#: a post as the kernels take it: x, y, the segment's lower and upper z, the radius (m)
POST_FIELDS = ("x", "y", "z_low", "z_high", "radius")
#: from this many configurations on, :func:`post_clearance` runs on every core numba has: only grids of the
#: joint range (:func:`paragym.tasks.capaman.solvable`); a native env's batch, smaller, is shared among worker
#: threads that wait without spinning (:func:`paragym.kernels.shares`), so that the serial code between the
#: kernels, its resets, does not wait on numba's spinning workers
PARALLEL_FROM = 16384


@lru_cache(maxsize=8)
def part_capsules(geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Radius and half length (m) of the capsule of each of the 16 parts the test reads, in the order of
    :func:`paragym.mechanisms.capaman.part_shapes` without the plate (the 15 leg parts, then the tool), and
    how far (m) a leg part's capsule reaches from its root ``c0`` of :func:`~paragym.mechanisms.capaman.part_table`
    in any pose (``|c1| + |c2| + half + radius``; the tool's is not used)."""
    radius, half = [], []
    for shape in capaman.part_shapes(geometry):
        if shape.name == "plate":
            continue
        if shape.kind == "box":
            radius.append(math.hypot(shape.half_extents[0], shape.half_extents[1]))
            half.append(shape.half_extents[2])
        else:
            radius.append(shape.radius)
            half.append(shape.length / 2)
    c0, c1, c2 = capaman.part_table(geometry)[:3]
    bound = np.append(np.linalg.norm(c1, axis=1) + np.linalg.norm(c2, axis=1), 0.0) + np.array(half) + np.array(radius)
    return np.array(radius), np.array(half), bound


@lru_cache(maxsize=8)
def plate_floor(geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, points_per_axis: int = 31) -> float:
    """The lowest point (m) the movable plate reaches over the joint range, less 1 mm: the least over a
    ``points_per_axis``^3 grid of the joint range of the plate's bottom rim, ``H_z - (t / 2) n_z - r_p
    sqrt(1 - n_z^2)`` (n: its normal), the rim's height changing by less than 1 mm between grid nodes."""
    g = geometry
    axis = np.linspace(g.alpha_min, g.alpha_max, points_per_axis)
    alpha = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    pose = capaman.forward(alpha, g, validate=False)
    nz = pose.rotation[:, 2, 2]
    rim = pose.position[:, 2] - g.plate_thickness / 2 * nz - g.r_p * np.sqrt(np.maximum(1.0 - nz * nz, 0.0))
    return float(rim.min()) - 0.001


def post_ceiling(geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, cap: float = 0.05) -> float:
    """The highest a post's top may reach (m) for the plate to be left out exactly: ``cap`` below
    :func:`plate_floor`."""
    return plate_floor(geometry) - cap


def parts_in_reach(posts: np.ndarray, counts: np.ndarray,
                   geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, cap: float = 0.05) -> np.ndarray:
    """Which of the 16 parts of :func:`part_capsules` some post of each robot (``posts`` (N, K, 5), ``counts``
    (N,)) may come within ``cap`` of, in any pose (N, 16): a leg part's capsule stays within ``|c1| + |c2| +
    half + radius`` of its root ``c0`` (:func:`paragym.mechanisms.capaman.part_table`), so a post farther than
    that plus the cap from the root never counts; the tool is always in reach. The clearance is capped at
    ``cap``, so skipping the others changes no answer."""
    bound = part_capsules(geometry)[2]
    out = np.ones((len(posts), len(bound)), np.bool_)
    _reach(posts, np.ascontiguousarray(counts, np.int64), capaman.part_table(geometry)[0], bound, float(cap), out)
    return out


@njit(cache=True, error_model="numpy")
def _reach(posts, counts, c0, bound, cap, out):
    """:func:`parts_in_reach` into ``out`` (N, 16), whose last column (the tool) stays True."""
    for i in range(posts.shape[0]):
        for j in range(c0.shape[0]):
            near = False
            for k in range(counts[i]):
                dx, dy = posts[i, k, 0] - c0[j, 0], posts[i, k, 1] - c0[j, 1]
                dz = max(posts[i, k, 2] - c0[j, 2], c0[j, 2] - posts[i, k, 3], 0.0)
                near = near or math.sqrt(dx * dx + dy * dy + dz * dz) - posts[i, k, 4] < bound[j] + cap
            out[i, j] = near


@njit(cache=True, error_model="numpy", inline="always")
def segment_distance(p0, p1, q0, q1):
    """The distance (m) between the segments p0-p1 and q0-q1 (3-tuples): Ericson's closest points of two
    segments, degenerate ones included."""
    d1 = (p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2])
    d2 = (q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2])
    r = (p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2])
    a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]
    e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]
    f = d2[0] * r[0] + d2[1] * r[1] + d2[2] * r[2]
    eps = 1e-18
    if a <= eps and e <= eps:
        s = t = 0.0
    elif a <= eps:
        s, t = 0.0, min(max(f / e, 0.0), 1.0)
    else:
        c = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2]
        if e <= eps:
            s, t = min(max(-c / a, 0.0), 1.0), 0.0
        else:
            b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > eps else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                s, t = min(max(-c / a, 0.0), 1.0), 0.0
            elif t > 1.0:
                s, t = min(max((b - c) / a, 0.0), 1.0), 1.0
    x = (p0[0] + d1[0] * s) - (q0[0] + d2[0] * t)
    y = (p0[1] + d1[1] * s) - (q0[1] + d2[1] * t)
    z = (p0[2] + d1[2] * s) - (q0[2] + d2[2] * t)
    return math.sqrt(x * x + y * y + z * z)


@njit(cache=True, error_model="numpy")
def k_post_clearance(a1, a2, a3, f, posts, count, reach, model, cap, tip):
    """The clearance (m, capped at ``cap``) of one configuration from ``count`` posts (K, 5: x, y, z_low, z_high,
    radius) and the part (an index of :func:`part_capsules`, -1 when every part is farther than the cap)
    nearest them; the tool tip is written into ``tip`` (3,). ``f``: :func:`capaman.k_forward` of the
    configuration; ``model``: :func:`kernel_constants` of the geometry. A part whose ``reach`` (16,) is False
    (:func:`parts_in_reach`) is not placed."""
    _, c0, c1, c2, qc, qs, leg, crank, tool_half, radius, half = model
    tip[0], tip[1], tip[2] = f[8], f[9], f[10]
    n_parts = radius.shape[0]
    best, part = cap, -1
    trig = False
    for j in range(n_parts):  # the part's centre and axis as k_part_frames places them, without arrays
        if not reach[j]:  # no post comes within the cap of this part in any pose (parts_in_reach)
            continue
        if j < n_parts - 1:
            if not trig:
                cosines = (math.cos(a1), math.cos(a2), math.cos(a3))
                sines = (math.sin(a1), math.sin(a2), math.sin(a3))
                halves = ((math.cos(0.5 * a1), math.sin(0.5 * a1)), (math.cos(0.5 * a2), math.sin(0.5 * a2)),
                          (math.cos(0.5 * a3), math.sin(0.5 * a3)))
                trig = True
            k = leg[j]
            cc, ss = cosines[k], sines[k]
            hc, hs = halves[k] if crank[j] else (1.0, 0.0)
            cx = c0[j, 0] + c1[j, 0] * cc + c2[j, 0] * ss
            cy = c0[j, 1] + c1[j, 1] * cc + c2[j, 1] * ss
            cz = c0[j, 2] + c1[j, 2] * cc + c2[j, 2] * ss
            x, y = qc[j, 0] * hc + qs[j, 0] * hs, qc[j, 1] * hc + qs[j, 1] * hs
            z, w = qc[j, 2] * hc + qs[j, 2] * hs, qc[j, 3] * hc + qs[j, 3] * hs
        else:  # the tool hangs from the plate's centre along its normal
            x, y, z, w = f[3], f[4], f[5], f[6]
        ax, ay, az = 2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)
        if j == n_parts - 1:
            cx, cy, cz = f[0] - tool_half * ax, f[1] - tool_half * ay, f[2] - tool_half * az
        h = half[j]
        p0 = (cx - h * ax, cy - h * ay, cz - h * az)
        p1 = (cx + h * ax, cy + h * ay, cz + h * az)
        extent = radius[j] + best
        lo0, hi0 = min(p0[0], p1[0]) - extent, max(p0[0], p1[0]) + extent
        lo1, hi1 = min(p0[1], p1[1]) - extent, max(p0[1], p1[1]) + extent
        lo2, hi2 = min(p0[2], p1[2]) - extent, max(p0[2], p1[2]) + extent
        for k in range(count):
            r = posts[k, 4]
            if (posts[k, 0] + r < lo0 or posts[k, 0] - r > hi0 or posts[k, 1] + r < lo1 or posts[k, 1] - r > hi1
                    or posts[k, 3] + r < lo2 or posts[k, 2] - r > hi2):
                continue  # the bounding boxes are farther apart than the best so far
            q0 = (posts[k, 0], posts[k, 1], posts[k, 2])
            q1 = (posts[k, 0], posts[k, 1], posts[k, 3])
            d = segment_distance(p0, p1, q0, q1) - radius[j] - r
            if d < best:
                best, part = d, j
    return best, part


@njit(cache=True, error_model="numpy", inline="always")
def _one(i, alpha, poses, rows, posts, counts, reach, model, cap, out, part, tip):
    """Configuration ``i`` of :func:`post_clearance`: its pose from ``poses`` when they are given (a row of
    :func:`k_forward`'s numbers, the flag as 1.0), else :func:`k_forward`."""
    if poses.shape[0]:
        r = poses[i]
        f = (r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], r[10], r[11] > 0.5)
    else:
        f = capaman.k_forward(alpha[i, 0], alpha[i, 1], alpha[i, 2], model[0])
    out[i], part[i] = k_post_clearance(alpha[i, 0], alpha[i, 1], alpha[i, 2], f, posts[rows[i]], counts[rows[i]],
                                       reach[rows[i]], model, cap, tip[i])


@njit(cache=True, error_model="numpy")
def _serial(alpha, poses, rows, posts, counts, reach, model, cap, out, part, tip):
    for i in range(alpha.shape[0]):
        _one(i, alpha, poses, rows, posts, counts, reach, model, cap, out, part, tip)


@njit(cache=True, error_model="numpy", nogil=True)
def _share(alpha, poses, rows, posts, counts, reach, model, cap, out, part, tip):
    """:func:`_serial` with the GIL released: one thread's share of a batch (a single env's call keeps the GIL,
    whose release and return cost it a microsecond)."""
    _serial(alpha, poses, rows, posts, counts, reach, model, cap, out, part, tip)


@njit(cache=True, error_model="numpy", parallel=True)
def _parallel(alpha, poses, rows, posts, counts, reach, model, cap, out, part, tip):
    for i in prange(alpha.shape[0]):
        _one(i, alpha, poses, rows, posts, counts, reach, model, cap, out, part, tip)


@njit(cache=True, error_model="numpy")
def _poses(alpha, consts, out):
    for i in range(alpha.shape[0]):
        (out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5], out[i, 6], out[i, 7], out[i, 8], out[i, 9],
         out[i, 10], ok) = capaman.k_forward(alpha[i, 0], alpha[i, 1], alpha[i, 2], consts)
        out[i, 11] = 1.0 if ok else 0.0


def forward_table(alpha: np.ndarray, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY) -> np.ndarray:
    """:func:`paragym.mechanisms.capaman.k_forward`'s numbers of configurations ``alpha`` (M, 3) as (M, 12) (the
    flag as 1.0): the ``poses`` of :func:`post_clearance` for configurations asked about again and again."""
    al = np.ascontiguousarray(np.atleast_2d(alpha), np.float64)
    out = np.empty((len(al), 12))
    _poses(al, capaman.kernel_consts(geometry), out)
    return out


_NO_POSES = np.empty((0, 12))


@lru_cache(maxsize=8)
def kernel_constants(geometry: capaman.CaPaManGeometry) -> tuple[Any, ...]:
    """The geometry as :func:`k_post_clearance` takes it (its ``model``), gathered once: :func:`capaman.kernel_consts`,
    :func:`capaman.part_table` and :func:`part_capsules`' radii and half lengths, in that order."""
    return (capaman.kernel_consts(geometry), *capaman.part_table(geometry), *part_capsules(geometry)[:2])


def post_clearance(alpha: np.ndarray, posts: np.ndarray, counts: np.ndarray, rows: np.ndarray | None = None,
                   geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, cap: float = 0.05,
                   reach: np.ndarray | None = None, poses: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The clearance (m, M; capped at ``cap``, negative inside), the nearest part (M; an index of
    :func:`part_capsules`, -1 beyond the cap) and the tool tip (M, 3) of configurations ``alpha`` (M, 3, rad)
    among the posts of robots ``rows`` (default 0..M-1): ``posts`` (N, K, 5) as :data:`POST_FIELDS`, of which
    robot i has ``counts[i]``; ``reach`` (N, 16): :func:`parts_in_reach` of every robot, when the caller keeps
    it; ``poses``: :func:`forward_table` of ``alpha``, when the caller keeps it. Each configuration's answer is
    computed on its own (the same floats on one thread or many, with or without ``poses``)."""
    al = np.ascontiguousarray(np.atleast_2d(alpha), np.float64)
    m = len(al)
    rows = np.arange(m) if rows is None else np.ascontiguousarray(rows, np.int64)
    out, part, tip = np.empty(m), np.empty(m, np.int64), np.empty((m, 3))
    if reach is None:
        reach = parts_in_reach(posts, counts, geometry, cap)
    poses = _NO_POSES if poses is None else poses
    model = kernel_constants(geometry)
    parts = None if m >= PARALLEL_FROM else shares(m)
    if parts is None:
        kernel = _parallel if m >= PARALLEL_FROM else _serial
        kernel(al, poses, rows, posts, counts, reach, model, float(cap), out, part, tip)
        return out, part, tip
    # a native env's batch: shared among worker threads that wait without spinning (paragym.kernels.shares)
    calls = [(al[lo:hi], poses[lo:hi] if len(poses) else poses, rows[lo:hi], posts, counts, reach, model, float(cap),
              out[lo:hi], part[lo:hi], tip[lo:hi]) for lo, hi in parts]
    concurrently(_share, calls)
    return out, part, tip

