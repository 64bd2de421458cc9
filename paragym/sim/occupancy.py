"""Paper 000's own collision test: the Cartesian matrix Psi and cluster points.

Section 2 of paper 000: the environment is a boolean grid Psi over Cartesian
space (eq 1: a cell is 1 when an obstacle occupies it); the manipulator is a
set of cluster points C_p regularly spaced on the surfaces of its parts; a
configuration is collision-free iff no cluster point falls in an occupied
cell (eq 2). Sweeping eq 2 over an epsilon-grid of the joint space gives the
joint matrix Theta (Fig 2). Everything here is vectorised over
configurations and points; no PyBullet.

Resolution (stated for the tests): a cell of size eps is marked occupied when
its centre lies in the obstacle grown by eps/2 (boxes; cylinders: eps/sqrt(2)
sideways, eps/2 vertically), so every cell that meets an obstacle is
occupied. A grid collision therefore means a cluster point within
(sqrt(2) + sqrt(3))/2 * eps < 1.6 eps of an obstacle; a penetration deeper
than the cluster spacing is seen (the tests check both against PyBullet).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field

import numba
import numpy as np
from numba import njit, prange

from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import k_quat_to_matrix, quat_to_matrix
from paragym.sim.obstacles import Box, Obstacle

# The compiled loops run on numba's threads. GNU OpenMP's, numba's default here, abort a process that forks
# after using them, as gymnasium's AsyncVectorEnv and multiprocessing do; a fork-safe layer (TBB or numba's
# own work queue) is chosen instead, unless the user chose one.
if "NUMBA_THREADING_LAYER" not in os.environ and numba.config.THREADING_LAYER == "default":
    numba.config.THREADING_LAYER = "forksafe"

__all__ = ["ClusterPoints", "DistanceGrids", "OccupancyGrid", "cluster_points", "grid_clearance", "grid_collision",
           "joint_matrix", "signed_distances"]


@dataclass(frozen=True)
class OccupancyGrid:
    """The Cartesian matrix Psi (eq 1): ``occupied[i, j, k]`` over cells of
    size ``resolution`` (m) starting at ``origin`` (m). Points outside the
    grid are free (the grid covers every obstacle)."""

    occupied: np.ndarray
    origin: np.ndarray
    resolution: float

    @classmethod
    def from_obstacles(cls, obstacles: Sequence[Obstacle], resolution: float = 0.005,
                       margin: float | None = None) -> OccupancyGrid:
        """Rasterise ``obstacles`` on a grid that covers their bounding boxes
        plus ``margin`` (m; default two cells, at least two cells)."""
        if resolution <= 0:
            raise ValueError(f"resolution must be > 0 m; got {resolution}")
        if not obstacles:
            return cls(np.zeros((1, 1, 1), bool), np.zeros(3), resolution)
        origin, shape, prisms = _prisms(obstacles, resolution, margin)
        return cls(_occupied(shape, prisms), origin, resolution)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners (m)."""
        return self.origin, self.origin + np.array(self.occupied.shape) * self.resolution

    def lookup(self, points: np.ndarray) -> np.ndarray:
        """Psi at points (..., 3): True where occupied (eq 1).

        The grid has a free border one cell wide, so indices are clipped onto
        it instead of masking points outside.
        """
        return self.lookup_axes(*np.moveaxis(np.asarray(points, dtype=np.float32), -1, 0))

    def lookup_axes(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """:meth:`lookup` at points given as their three coordinates (arrays of
        one shape, float32/int32: half the memory traffic), axis by axis."""
        shape = self.occupied.shape
        flat = 0
        for k, c in enumerate((x, y, z)):
            i = c - np.float32(self.origin[k])
            i *= np.float32(1.0 / self.resolution)
            np.maximum(i, 0, out=i)  # clipped onto the grid, so that truncating is flooring
            np.minimum(i, np.float32(shape[k] - 1), out=i)
            flat = flat * shape[k] + i.astype(np.int32)
        return self.occupied.ravel()[flat]


@dataclass(frozen=True)
class ClusterPoints:
    """Cluster points C_p: ``local`` positions (M, 3) in their part's frame and
    the ``part`` index (M,) of each, in the order of ``part_shapes``."""

    local: np.ndarray
    part: np.ndarray
    spacing: float
    #: world positions of one part's points over a joint grid, kept by :func:`joint_matrix`
    _grid_cache: dict = field(default_factory=dict, compare=False, repr=False)

    def subset(self, parts: np.ndarray) -> ClusterPoints:
        """Only the points of the given part indices."""
        keep = np.isin(self.part, parts)
        return ClusterPoints(self.local[keep], self.part[keep], self.spacing)

    def on_joint_grid(self, part: int, alpha: np.ndarray, geometry: capaman.CaPaManGeometry,
                      key: tuple, max_bytes: int = 64 << 20) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """World positions (3, N, M_part) float32, axis by axis, of one part's
        points at configurations ``alpha`` (N, 3), in the order of its blocks
        of up to 16 points near each other (:func:`_groups`); the blocks as
        indices into that order, (B, 16) (a short block repeats its last
        point); and each block's bounding box at every configuration (lower
        and upper corners, (3, N, B)). Kept under ``key`` when the positions
        take less than ``max_bytes`` (the joint grid does not change between
        scenarios, only the obstacles do)."""
        cached = self._grid_cache.get((key, part))
        if cached is not None:
            return cached
        centres, quats = capaman.part_frames(alpha, geometry, validate=False)
        f32 = np.float32
        local = self.local[self.part == part]
        world = _place(local.astype(f32), centres[:, part].astype(f32),
                       quat_to_matrix(quats[:, part]).astype(f32))
        groups = _groups(local, 16)
        order = np.concatenate(groups)  # block after block
        world = np.stack([np.take(world[..., k], order, axis=1) for k in range(3)])
        sizes = np.array([len(g) for g in groups])
        starts = np.cumsum(sizes) - sizes
        idx = starts[:, None] + np.minimum(np.arange(16), sizes[:, None] - 1)
        out = (world, idx, np.minimum.reduceat(world, starts, axis=2), np.maximum.reduceat(world, starts, axis=2))
        if world.nbytes <= max_bytes:
            self._grid_cache[(key, part)] = out
        return out


def _prisms(obstacles: Sequence[Obstacle], resolution: float, margin: float | None
            ) -> tuple[np.ndarray, tuple[int, int, int], list[tuple[np.ndarray, np.ndarray]]]:
    """The grid of :meth:`OccupancyGrid.from_obstacles`: origin (m), shape, and
    each obstacle's occupied cells as a vertical prism: a mask over (x, y)
    (nx, ny) times a mask over z (nz,). A cell is occupied when its centre
    lies in the obstacle grown by half a cell (boxes; cylinders: a half
    diagonal sideways); both kinds are a shape in (x, y) times an interval
    in z, so the centres in the obstacle's mid plane and on its axis decide,
    with the same arithmetic as at every centre."""
    # Bounding box of the obstacles plus the margin: the outer cell stays free (see lookup).
    pad = max(2 * resolution, margin or 0.0)
    lo = np.min([np.subtract(o.center, o.half_extents) for o in obstacles], axis=0) - pad
    hi = np.max([np.add(o.center, o.half_extents) for o in obstacles], axis=0) + pad
    shape = tuple(int(v) for v in np.ceil((hi - lo) / resolution))
    axes = [lo[i] + (np.arange(shape[i]) + 0.5) * resolution for i in range(3)]
    plane = np.stack(np.meshgrid(axes[0], axes[1], [0.0], indexing="ij"), axis=-1)[:, :, 0]  # (nx, ny, 3)
    column = np.zeros((shape[2], 3))
    column[:, 2] = axes[2]
    half = resolution / 2
    out = []
    for o in obstacles:
        side = half if isinstance(o, Box) else half * np.sqrt(2.0)
        plane[..., 2], column[:, :2] = o.center[2], o.center[:2]
        out.append((o.contains(plane, (side, half)), o.contains(column, (side, half))))
    return lo, shape, out


def _place(local: np.ndarray, centres: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """World positions (N, M, 3) of part-frame points (M, 3) for N poses
    (centres (N, 3), rotations (N, 3, 3)): one matrix product for all."""
    n = len(rot)
    world = np.swapaxes(rot, 1, 2).reshape(n, 3, 3)  # R^T per pose, so that local @ R^T is one product
    world = local @ world  # (N, M, 3), a batched product numpy hands to BLAS
    world += centres[:, None, :]
    return world


def _grid(length: float, spacing: float) -> np.ndarray:
    n = max(2, int(np.ceil(length / spacing)) + 1)
    return np.linspace(-length / 2, length / 2, n)


def _box_surface(h: Sequence[float], spacing: float) -> np.ndarray:
    axes = [_grid(2 * v, spacing) for v in h]
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    on_face = np.any(np.isclose(np.abs(pts), h), axis=1)
    return pts[on_face]


def _cylinder_surface(radius: float, length: float, spacing: float) -> np.ndarray:
    z = _grid(length, spacing)
    n_ring = max(6, int(np.ceil(2 * np.pi * radius / spacing)))
    ang = np.linspace(0, 2 * np.pi, n_ring, endpoint=False)
    side = np.stack(np.broadcast_arrays(radius * np.cos(ang)[:, None], radius * np.sin(ang)[:, None],
                                        z[None, :]), axis=-1).reshape(-1, 3)
    caps = []
    for r in np.arange(radius - spacing, 0, -spacing):  # concentric rings on both caps
        n = max(6, int(np.ceil(2 * np.pi * r / spacing)))
        a = np.linspace(0, 2 * np.pi, n, endpoint=False)
        caps.append(np.stack([r * np.cos(a), r * np.sin(a)], axis=1))
    disc = np.concatenate(caps + [np.zeros((1, 2))])
    cap_pts = [np.column_stack([disc, np.full(len(disc), zc)]) for zc in (-length / 2, length / 2)]
    return np.concatenate([side, *cap_pts])


def cluster_points(geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                   spacing: float = 0.005) -> ClusterPoints:
    """Points regularly spaced (about ``spacing`` m) on the surface of every part."""
    if spacing <= 0:
        raise ValueError(f"spacing must be > 0 m; got {spacing}")
    local, part = [], []
    for i, shape in enumerate(capaman.part_shapes(geometry)):
        pts = (_box_surface(shape.half_extents, spacing) if shape.kind == "box"
               else _cylinder_surface(shape.radius, shape.length, spacing))
        local.append(pts)
        part.append(np.full(len(pts), i))
    return ClusterPoints(np.concatenate(local), np.concatenate(part), spacing)


def reachable_parts(grid: OccupancyGrid, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                    samples_per_axis: int = 7) -> np.ndarray:
    """Indices of the parts that can reach the grid's box anywhere in the joint range.

    Each part's bounding box is swept over a coarse grid of the joint range
    and padded by the largest move of that box between neighbouring samples
    (a heuristic margin, checked by the tests against PyBullet); parts whose
    swept box misses the grid cannot collide and are skipped by
    :func:`joint_matrix` (e.g. the plate when the obstacles stand below it).
    """
    if not grid.occupied.any():
        return np.zeros(0, int)
    lo, hi = capaman.swept_part_boxes(geometry, samples_per_axis)
    glo, ghi = grid.bounds
    return np.flatnonzero(np.all((hi >= glo) & (lo <= ghi), axis=1))


def grid_collision(alpha: np.ndarray, grid: OccupancyGrid, clusters: ClusterPoints,
                   geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                   chunk_points: int = 2_000_000) -> np.ndarray:
    """Eq 2 for a batch of configurations (N, 3) rad: True where any cluster
    point lies in an occupied cell. Evaluated in chunks of about
    ``chunk_points`` points to bound memory."""
    al = capaman.check_joint_angles(alpha, geometry)
    out = np.zeros(len(al), bool)
    if len(clusters.part) == 0 or not grid.occupied.any():
        return out
    step = max(1, chunk_points // len(clusters.part))
    by_part = [(p, clusters.local[clusters.part == p]) for p in np.unique(clusters.part)]
    for start in range(0, len(al), step):  # chunks of configurations, not single samples
        block = al[start:start + step]
        centres, quats = capaman.part_frames(block, geometry, validate=False)
        rot = quat_to_matrix(quats)  # (n, parts, 3, 3)
        hit = np.zeros(len(block), bool)
        for p, local in by_part:  # a loop over the (at most 17) parts, each vectorised
            world = _place(local, centres[:, p], rot[:, p])
            hit |= grid.lookup(world).any(axis=1)
        out[start:start + step] = hit
    return out


def joint_matrix(grid: OccupancyGrid, clusters: ClusterPoints, points_per_axis: int,
                 geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The joint matrix Theta (Fig 2): collision map on an epsilon-grid of the joint space.

    Returns ``theta`` (n, n, n) bool, True where the configuration collides,
    and ``axis`` (n,) rad, the grid values of each crank angle (equal for the
    three). Only parts that can reach the obstacles are tested
    (:func:`reachable_parts`).
    """
    g = geometry
    axis = np.linspace(g.alpha_min, g.alpha_max, points_per_axis)
    alpha = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    theta = np.zeros(len(alpha), bool)
    for p in reachable_parts(grid, g):  # a loop over parts, each vectorised over the grid
        if len(alpha) * np.count_nonzero(clusters.part == p) > 20_000_000:  # too big to hold at once
            theta |= grid_collision(alpha, grid, clusters.subset([p]), g)
        else:
            theta |= _grid_hits(grid, *clusters.on_joint_grid(p, alpha, g, (g, points_per_axis)))
    return theta.reshape((points_per_axis,) * 3), axis


def _grid_hits(grid: OccupancyGrid, world: np.ndarray, idx: np.ndarray, lo: np.ndarray, hi: np.ndarray
               ) -> np.ndarray:
    """Eq 2 at N configurations from their points' world positions (3, N, M)
    float32, in blocks ``idx`` (B, 16) with bounding boxes ``lo``, ``hi``
    (3, N, B) (:meth:`ClusterPoints.on_joint_grid`): only the blocks that
    reach the box of a clump of occupied cells (grown by a cell, far more
    than float32 rounding) are looked up; the others lie in free cells; a
    configuration stops at its first occupied point. The same answer as
    ``grid.lookup(world).any(axis=1)`` in (N, M, 3) order, with the same
    float32 arithmetic as :meth:`OccupancyGrid.lookup_axes` (one compiled
    loop over the configurations, :func:`_hits_one`)."""
    from scipy import ndimage

    labels, _ = ndimage.label(grid.occupied)
    boxes = ndimage.find_objects(labels)  # each clump of occupied cells (an obstacle or touching ones)
    f32 = np.float32
    clump_lo = np.array([[f32(grid.origin[k] + (s.start - 1) * grid.resolution) for k, s in enumerate(box)]
                         for box in boxes], f32).reshape(-1, 3)
    clump_hi = np.array([[f32(grid.origin[k] + (s.stop + 1) * grid.resolution) for k, s in enumerate(box)]
                         for box in boxes], f32).reshape(-1, 3)
    kernel = _hits_parallel if world.shape[1] >= 1024 else _hits_serial
    return kernel(world, idx, lo, hi, clump_lo, clump_hi, grid.origin.astype(f32), f32(1.0 / grid.resolution),
                  np.array(grid.occupied.shape, np.int64), grid.occupied.ravel())


@njit(cache=True, inline="always")
def _hits_one(n, world, idx, lo, hi, clump_lo, clump_hi, origin, inv, shape, occupied):
    """Whether configuration ``n`` puts a point in an occupied cell (:func:`_grid_hits`)."""
    zero = np.float32(0.0)
    top = (np.float32(shape[0] - 1), np.float32(shape[1] - 1), np.float32(shape[2] - 1))
    for b in range(idx.shape[0]):
        reach = False
        for c in range(clump_lo.shape[0]):
            inside = True
            for k in range(3):
                inside = inside and hi[k, n, b] >= clump_lo[c, k] and lo[k, n, b] <= clump_hi[c, k]
            reach = reach or inside
        if not reach:
            continue
        for q in range(idx.shape[1]):
            m = idx[b, q]
            flat = 0
            for k in range(3):
                i = (world[k, n, m] - origin[k]) * inv
                i = min(max(i, zero), top[k])  # clipped onto the grid, so that truncating is flooring
                flat = flat * shape[k] + np.int64(np.int32(i))
            if occupied[flat]:
                return True
    return False


@njit(cache=True)
def _hits_serial(world, idx, lo, hi, clump_lo, clump_hi, origin, inv, shape, occupied):
    out = np.zeros(world.shape[1], np.bool_)
    for n in range(world.shape[1]):
        out[n] = _hits_one(n, world, idx, lo, hi, clump_lo, clump_hi, origin, inv, shape, occupied)
    return out


@njit(cache=True, parallel=True)
def _hits_parallel(world, idx, lo, hi, clump_lo, clump_hi, origin, inv, shape, occupied):
    out = np.zeros(world.shape[1], np.bool_)
    for n in prange(world.shape[1]):
        out[n] = _hits_one(n, world, idx, lo, hi, clump_lo, clump_hi, origin, inv, shape, occupied)
    return out


# --- the grid's clearance: signed distances on Psi, for many robots at once ---------------------------------


def _mask_bounds(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and last index (3,) along each axis of the True cells of a 3-D ``mask`` (some cell True)."""
    spans = [np.flatnonzero(mask.any(axis=tuple(j for j in range(3) if j != k))) for k in range(3)]
    return np.array([c[0] for c in spans]), np.array([c[-1] for c in spans])


def _occupied(shape: tuple[int, int, int], prisms: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Psi (eq 1) from the obstacles' prisms (:func:`_prisms`)."""
    occupied = np.zeros(shape, bool)
    for plane, column in prisms:
        occupied |= plane[:, :, None] & column[None, None]
    return occupied


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
def _clearance_one(trig, position, quat, g, c0_, c1_, c2_, qc, qs, leg, crank, tool_half, origin, shape, slot, values,
                   lo, hi, part_radii, first, bounds, group_middles, group_radii, middles, radii, local, inv, cap,
                   n_parts):
    """The smallest key value * parts + part of one configuration against grid ``g`` (the docstring of
    :func:`grid_clearance`); ``trig``, ``position``, ``quat`` and the part table (``c0_`` to ``tool_half``)
    place its parts (:func:`paragym.mechanisms.capaman.k_part_frames`)."""
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
    box[0], box[1] = lo[g], hi[g]
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
        best[i] = _clearance_one(trig[i], position[i], quat[i], rows[i], *grid)
    return best


@njit(cache=True, parallel=True)
def _clearance_parallel(trig, position, quat, rows, grid):
    """:func:`_clearance_serial` on numba's threads (consecutive configurations on one thread)."""
    best = np.empty(trig.shape[0], np.int64)
    for i in prange(trig.shape[0]):
        best[i] = _clearance_one(trig[i], position[i], quat[i], rows[i], *grid)
    return best


def _groups(points: np.ndarray, size: int) -> list[np.ndarray]:
    """Indices of ``points`` (M, 3) in groups of at most ``size`` near each
    other: split at the median of the longest side until the pieces are small."""
    out, todo = [], [np.arange(len(points))]
    while todo:
        idx = todo.pop()
        if len(idx) <= size:
            out.append(idx)
            continue
        pts = points[idx]
        order = idx[np.argsort(pts[:, np.argmax(np.ptp(pts, axis=0))], kind="stable")]
        todo += [order[:len(idx) // 2], order[len(idx) // 2:]]
    return out


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
