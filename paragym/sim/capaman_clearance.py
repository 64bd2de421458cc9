"""Paper 000's grid as signed distances: how far each CaPaMan part is from the obstacles, for N robots at once.

:func:`signed_distances` turns the occupancy of :mod:`paragym.sim.capaman_grid`
into a signed distance field (m, capped); :class:`DistanceGrids` holds one per
robot; :func:`grid_clearance` reads it at the cluster points of eq 2, placed by
the closed-form kinematics, in compiled loops over robots and blocks of
points. No PyBullet: this is the native vector env's collision test.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numba import njit, prange

from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import k_quat_to_matrix
from paragym.sim.capaman_grid import ClusterPoints, _groups, _mask_bounds, _occupied, _prisms
from paragym.sim.obstacles import Obstacle

__all__ = ["DistanceGrids", "grid_clearance", "signed_distances"]


def signed_distances(obstacles: Sequence[Obstacle], resolution: float = 0.005, cap: float = 0.05,
                     unit: float = 0.0005) -> tuple[np.ndarray, np.ndarray]:
    """Psi (eq 1) with the distance of every cell to the other kind: for a
    free cell, the distance between its centre and the nearest occupied
    cell's, less half a cell (> 0); for an occupied cell, minus the distance
    to the nearest free cell's centre, plus half a cell (< 0). In steps of
    ``unit`` (m) as int8, capped at +-``cap``; so a value is negative exactly
    where eq 2 counts a collision. Returns the values and the grid's origin
    (m); the grid reaches ``cap`` beyond the obstacles."""
    from scipy import ndimage

    if cap / unit > 127:
        raise ValueError(f"cap / unit must fit int8 (<= 127); got {cap / unit:g}")
    if not obstacles:
        return np.full((1, 1, 1), round(cap / unit), np.int8), np.zeros(3)
    origin, shape, prisms = _prisms(obstacles, resolution, cap + 2 * resolution)
    # outside: the squared distance (cells) to a prism is the squared distance in (x, y) to its mask plus that
    # in z to its interval, and to the union the least of those; integers, so the same figures as a distance
    # transform of the whole grid, at the cost of one in two dimensions per obstacle
    occ = _occupied(shape, prisms)
    dxy2 = np.empty((len(prisms), shape[0], shape[1]), np.int64)
    z_range = np.empty((len(prisms), 2), np.int64)
    for j, (plane, column) in enumerate(prisms):
        near = ndimage.distance_transform_edt(~plane, return_distances=False, return_indices=True)
        dxy2[j] = (near[0] - np.arange(shape[0])[:, None]) ** 2 + (near[1] - np.arange(shape[1])[None, :]) ** 2
        z = np.flatnonzero(column)
        z_range[j] = z[0], z[-1]
    # inside: only over the occupied cells' box grown by one cell, whose outer layer is free, so no occupied
    # cell has a nearer free cell beyond it (exact; the grid is mostly free space)
    inside = np.zeros(occ.shape)
    if occ.any():
        first, last = _mask_bounds(occ)
        box = tuple(slice(max(int(a) - 1, 0), int(b) + 2) for a, b in zip(first, last, strict=True))
        inside[box] = ndimage.distance_transform_edt(occ[box])
    return _signed_kernel(dxy2, z_range, occ, inside, resolution, unit, round(cap / unit)), origin


@njit(cache=True)
def _signed_kernel(dxy2: np.ndarray, z_range: np.ndarray, occ: np.ndarray, inside: np.ndarray, resolution: float,
                   unit: float, cap: int) -> np.ndarray:
    """The int8 values of :func:`signed_distances` from each prism's squared distance (cells) in (x, y)
    ``dxy2`` (P, nx, ny) and its z interval ``z_range`` (P, 2), Psi ``occ`` and the occupied cells' distance
    (cells) to the nearest free one ``inside``: per cell, the least squared distance to a prism
    (``dxy2 + dz^2``, integers), its root in m less half a cell, or minus ``inside`` in m plus half a cell
    where occupied; rounded to ``unit`` (half to even) and clipped to +-``cap`` units."""
    nx, ny, nz = occ.shape
    out = np.empty((nx, ny, nz), np.int8)
    half = resolution / 2
    for x in range(nx):
        for y in range(ny):
            for z in range(nz):
                if occ[x, y, z]:
                    d = -(inside[x, y, z] * resolution - half)
                else:
                    d2 = np.iinfo(np.int64).max
                    for j in range(dxy2.shape[0]):
                        dz = max(max(z_range[j, 0] - z, z - z_range[j, 1]), 0)
                        d2 = min(d2, dxy2[j, x, y] + dz * dz)
                    d = np.sqrt(np.float64(d2)) * resolution - half
                out[x, y, z] = np.int8(min(max(np.rint(d / unit), -cap), cap))
    return out


class DistanceGrids:
    """The signed-distance grids of N robots' scenes in one flat buffer (one
    slot per robot, as big as the largest grid so far).

    Every grid reaches ``cap`` beyond its obstacles (:func:`signed_distances`),
    so its outermost cells hold the cap, as does everything beyond it: a
    point outside a grid reads the nearest border cell (clipped indices, no
    mask; the tests check the borders)."""

    def __init__(self, n: int, resolution: float = 0.005, cap: float = 0.05, unit: float = 0.0005) -> None:
        self.n, self.resolution, self.cap, self.unit = n, resolution, cap, unit
        self.origin = np.zeros((n, 3))
        self.shape = np.ones((n, 3), np.int64)
        self.slot = 1
        self.values = np.full(n, round(cap / unit), np.int8)
        # the box (m) of the cells below the cap, grown by a hundredth of a cell; empty: lo > hi
        self.active_lo, self.active_hi = np.full((n, 3), np.inf), np.full((n, 3), -np.inf)

    def set(self, i: int, obstacles: Sequence[Obstacle]) -> None:
        """Robot ``i``'s scene becomes ``obstacles``."""
        values, origin = signed_distances(obstacles, self.resolution, self.cap, self.unit)
        if values.size > self.slot:  # grow every slot (rare: the first resets set the size)
            old, old_slot = self.values, self.slot
            self.slot = int(values.size * 1.25)
            self.values = np.full(self.n * self.slot, round(self.cap / self.unit), np.int8)
            for j in range(self.n):
                self.values[j * self.slot:j * self.slot + old_slot] = old[j * old_slot:(j + 1) * old_slot]
        self.values[i * self.slot:i * self.slot + values.size] = values.ravel()
        self.origin[i], self.shape[i] = origin, values.shape
        below = values < round(self.cap / self.unit)
        if below.any():
            first, last = _mask_bounds(below)
            pad = 0.01 * self.resolution
            self.active_lo[i] = origin + first * self.resolution - pad
            self.active_hi[i] = origin + (last + 1) * self.resolution + pad
        else:
            self.active_lo[i], self.active_hi[i] = np.inf, -np.inf


def grid_clearance(alpha: np.ndarray, grids: DistanceGrids, clusters: ClusterPoints,
                   geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, rows: np.ndarray | None = None,
                   pose: capaman.CaPaManPose | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The clearance (m, N) of robots at crank angles ``alpha`` (N, 3) from
    their grids (``rows`` of ``grids``, default all; a row may repeat, as
    when one robot is probed at several configurations: give them one after
    the other, so that its grid is still in the cache): the smallest signed
    distance at any cluster point (negative: a collision by eq 2), and the
    part (N,) that holds that point (the lowest index on a tie; -1 when every
    point reads the cap). ``pose``: the direct kinematics at ``alpha``, when
    the caller has it.

    One numba kernel over the configurations (:func:`_clearance_one`),
    which places the parts (:func:`paragym.mechanisms.capaman.k_part_frames`)
    and reads the grid; from :data:`PARALLEL_FROM` configurations on it runs
    on every core numba has (``numba.set_num_threads`` limits them). The
    points are grouped in small blocks (:func:`_blocks`); a part whose
    bounding sphere misses a robot's grid box reads the cap there and is
    skipped, and so is a block whose own sphere misses it. The culling and
    the cells are computed in float32, each configuration on its own, so
    that an answer does not depend on the others in the batch nor on the
    threads; the values are those of paragym 0.9.0's vectorised numpy pass
    bit for bit (the released rollouts and the leaderboard rows replay)."""
    al = np.ascontiguousarray(np.atleast_2d(alpha), np.float64)
    n = len(al)
    rows = np.arange(n) if rows is None else np.asarray(rows, np.int64)
    if pose is None:
        pose = capaman.forward(al, geometry, validate=False)
    parts, middles, radii, local = _blocks(clusters)
    part_radii = _part_radii(clusters)
    n_parts = len(part_radii)
    bounds, group_middles, group_radii = _block_groups(clusters)
    first = np.searchsorted(bounds[:-1], np.searchsorted(parts, np.arange(n_parts + 1)))  # part p's runs
    cap = round(grids.cap / grids.unit)
    kernel = _clearance_parallel if n >= PARALLEL_FROM else _clearance_serial
    grid = (*capaman.part_table(geometry), grids.origin, grids.shape, grids.slot, grids.values,
            grids.active_lo.astype(np.float32), grids.active_hi.astype(np.float32), part_radii.astype(np.float32),
            first, bounds, group_middles.astype(np.float32), group_radii.astype(np.float32),
            middles.astype(np.float32), radii.astype(np.float32), local, 1.0 / grids.resolution, cap, n_parts)
    best = kernel(capaman.crank_trig(al), np.ascontiguousarray(pose.position), np.ascontiguousarray(pose.quaternion),
                  rows, grid)
    value, part = best // n_parts, best % n_parts
    part[value >= cap] = -1
    return np.minimum(value, cap) * grids.unit, part


#: from this many configurations on, :func:`grid_clearance` runs its kernel on every core numba has
PARALLEL_FROM = 256


@njit(cache=True, inline="always")
def _gap(frame: np.ndarray, middle: np.ndarray, box: np.ndarray) -> np.float32:
    """The culling test in float32: the squared distance from the box ``box`` (lower and upper corners,
    (2, 3)) of the centre of a sphere at ``middle`` (3,) in a part's ``frame`` (3, 4: centre, rotation)."""
    total = np.float32(0.0)
    for k in range(3):
        c = ((frame[k, 0] + middle[0] * frame[k, 1]) + middle[1] * frame[k, 2]) + middle[2] * frame[k, 3]
        d = max(max(box[0, k] - c, c - box[1, k]), np.float32(0.0))
        total += d * d
    return total


@njit(cache=True)
def _clearance_one(trig, position, quat, g, grid):
    """The smallest key value * parts + part of one configuration against grid ``g`` (the docstring of
    :func:`grid_clearance`); ``trig``, ``position``, ``quat`` and the part table (``c0_`` to ``tool_half``)
    place its parts (:func:`paragym.mechanisms.capaman.k_part_frames`). ``grid``: the part table, the grids
    and the cluster points' blocks, as :func:`grid_clearance` gathers them."""
    c0_, c1_, c2_, qc, qs, leg, crank, tool_half, origin, shape, slot, values, lo, hi, part_radii, first, bounds, \
        group_middles, group_radii, middles, radii, local, inv, cap, n_parts = grid
    centres, quats, rot = np.empty((n_parts, 3)), np.empty((n_parts, 4)), np.empty((n_parts, 3, 3))
    capaman.k_part_frames(trig, position, quat, c0_, c1_, c2_, qc, qs, leg, crank, tool_half, centres, quats)
    for p in range(n_parts):
        k_quat_to_matrix(quats[p], rot[p])
    zero = np.float32(0.0)
    best = cap * n_parts
    top0, top1, top2 = np.float32(shape[g, 0] - 1), np.float32(shape[g, 1] - 1), np.float32(shape[g, 2] - 1)
    sy, sz = shape[g, 1], shape[g, 2]
    base = g * slot
    box = np.empty((2, 3), np.float32)
    for k in range(3):  # by element: a slice copy compiles a shape check that costs seconds
        box[0, k], box[1, k] = lo[g, k], hi[g, k]
    frame = np.empty((3, 4), np.float32)  # a part's centre and rotation, float32: the culling's frame
    origin_point = np.zeros(3, np.float32)
    for p in range(n_parts):
        for k in range(3):
            frame[k, 0] = np.float32(centres[p, k])
            for j in range(3):
                frame[k, 1 + j] = np.float32(rot[p, k, j])
        if not _gap(frame, origin_point, box) <= part_radii[p] * part_radii[p]:
            continue
        t0 = np.float32((centres[p, 0] - origin[g, 0]) * inv)
        t1 = np.float32((centres[p, 1] - origin[g, 1]) * inv)
        t2 = np.float32((centres[p, 2] - origin[g, 2]) * inv)
        m00, m01, m02 = np.float32(rot[p, 0, 0] * inv), np.float32(rot[p, 0, 1] * inv), \
            np.float32(rot[p, 0, 2] * inv)
        m10, m11, m12 = np.float32(rot[p, 1, 0] * inv), np.float32(rot[p, 1, 1] * inv), \
            np.float32(rot[p, 1, 2] * inv)
        m20, m21, m22 = np.float32(rot[p, 2, 0] * inv), np.float32(rot[p, 2, 1] * inv), \
            np.float32(rot[p, 2, 2] * inv)
        for r in range(first[p], first[p + 1]):  # the part's runs of blocks, then each run's blocks
            if not _gap(frame, group_middles[r], box) <= group_radii[r] * group_radii[r]:
                continue
            for b in range(bounds[r], bounds[r + 1]):
                if not _gap(frame, middles[b], box) <= radii[b] * radii[b]:
                    continue
                low = 1 << 30
                for q in range(local.shape[1]):
                    x0, x1, x2 = local[b, q, 0], local[b, q, 1], local[b, q, 2]
                    u = min(max(((t0 + x0 * m00) + x1 * m01) + x2 * m02, zero), top0)
                    v = min(max(((t1 + x0 * m10) + x1 * m11) + x2 * m12, zero), top1)
                    w = min(max(((t2 + x0 * m20) + x1 * m21) + x2 * m22, zero), top2)
                    value = values[base + (np.int64(u) * sy + np.int64(v)) * sz + np.int64(w)]
                    if value < low:
                        low = value
                key = low * n_parts + p
                if key < best:
                    best = key
    return best


@njit(cache=True)
def _clearance_serial(trig, position, quat, rows, grid):
    """:func:`_clearance_one` of every configuration, one after the other (``grid``: its other arguments)."""
    best = np.empty(trig.shape[0], np.int64)
    for i in range(trig.shape[0]):
        best[i] = _clearance_one(trig[i], position[i], quat[i], rows[i], grid)
    return best


@njit(cache=True, parallel=True)
def _clearance_parallel(trig, position, quat, rows, grid):
    """:func:`_clearance_serial` on numba's threads (consecutive configurations on one thread)."""
    best = np.empty(trig.shape[0], np.int64)
    for i in prange(trig.shape[0]):
        best[i] = _clearance_one(trig[i], position[i], quat[i], rows[i], grid)
    return best


def _block_groups(clusters: ClusterPoints, size: int = 16) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of up to ``size`` consecutive blocks of one part (:func:`_blocks`; consecutive blocks lie near each
    other): the first block of each run and one past the last, (G + 1,); each run's centre (G, 3) and the
    radius (G,) of a sphere that holds its blocks' spheres (m, in the part's frame). Kept on the clusters."""
    key = ("block groups", size)
    if key not in clusters._grid_cache:
        parts, middles, radii, _ = _blocks(clusters)
        edges = np.flatnonzero(np.diff(parts)) + 1
        starts = np.concatenate([np.arange(a, b, size) for a, b in zip(np.r_[0, edges], np.r_[edges, len(parts)],
                                                                       strict=True)])
        bounds = np.r_[starts, len(parts)]
        centre = np.array([(middles[a:b].min(axis=0) + middles[a:b].max(axis=0)) / 2
                           for a, b in zip(bounds[:-1], bounds[1:], strict=True)])
        radius = np.array([np.max(np.linalg.norm(middles[a:b] - c, axis=1) + radii[a:b]) + 1e-9
                           for a, b, c in zip(bounds[:-1], bounds[1:], centre, strict=True)])
        clusters._grid_cache[key] = (bounds, centre, radius)
    return clusters._grid_cache[key]


def _part_radii(clusters: ClusterPoints) -> np.ndarray:
    """The radius (m) of each part's cluster points about the part's origin, (parts,). Kept on the clusters."""
    if "part radii" not in clusters._grid_cache:
        radii = np.zeros(int(clusters.part.max()) + 1)
        np.maximum.at(radii, clusters.part, np.sqrt(np.sum(clusters.local ** 2, axis=1)) + 1e-9)
        clusters._grid_cache["part radii"] = radii
    return clusters._grid_cache["part radii"]


def _blocks(clusters: ClusterPoints, size: int = 16) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The cluster points in blocks of at most ``size`` points near each other
    in their part's frame (each part split at the median of its longest side
    until the pieces are small): part index (B,), centre (B, 3) and bounding
    radius (B,) (m) in the part's frame, and the points (B, size, 3) float32,
    a short block padded with copies of its first point. Kept on the clusters."""
    key = ("blocks", size)
    if key not in clusters._grid_cache:
        parts, local = [], []
        for p in np.unique(clusters.part):
            pts = clusters.local[clusters.part == p]
            idx = np.array([np.concatenate([g, np.full(size - len(g), g[0])]) for g in _groups(pts, size)])
            parts.append(np.full(len(idx), p))
            local.append(pts[idx])
        blocks = np.concatenate(local)  # (B, size, 3)
        middles = (blocks.min(axis=1) + blocks.max(axis=1)) / 2
        radii = np.sqrt(np.sum((blocks - middles[:, None]) ** 2, axis=2)).max(axis=1) + 1e-9
        clusters._grid_cache[key] = (np.concatenate(parts), middles, radii, blocks.astype(np.float32))
    return clusters._grid_cache[key]


