"""Paper 000's own collision test for the CaPaMan: the Cartesian matrix Psi and cluster points.

Section 2 of paper 000: the environment is a boolean grid Psi over Cartesian
space (eq 1: a cell is 1 when an obstacle occupies it); the manipulator is a
set of cluster points C_p regularly spaced on the surfaces of its parts; a
configuration is collision-free iff no cluster point falls in an occupied
cell (eq 2). Sweeping eq 2 over an epsilon-grid of the joint space gives the
joint matrix Theta (Fig 2). Everything here is vectorised over
configurations and points; no PyBullet. The same grid as signed distances,
for N robots at once, is :mod:`paragym.sim.capaman_clearance`.

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
from paragym.mechanisms.geometry import quat_to_matrix
from paragym.sim.obstacles import Box, Obstacle

# The compiled loops run on numba's threads. GNU OpenMP's, numba's default here, abort a process that forks
# after using them, as gymnasium's AsyncVectorEnv and multiprocessing do; a fork-safe layer (TBB or numba's
# own work queue) is chosen instead, unless the user chose one.
if "NUMBA_THREADING_LAYER" not in os.environ and numba.config.THREADING_LAYER == "default":
    numba.config.THREADING_LAYER = "forksafe"

__all__ = ["ClusterPoints", "OccupancyGrid", "cluster_points", "grid_collision", "joint_matrix", "reachable_parts"]


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
    with the same arithmetic as at every centre. A capsule is rasterised as the
    cylinder that holds it (its radius, its whole height): conservative, as
    the grid's cells are."""
    # Bounding box of the obstacles plus the margin: the outer cell stays free (see lookup).
    pad = max(2 * resolution, margin or 0.0)
    lo = np.min([np.subtract(o.center, o.half_extents) for o in obstacles], axis=0) - pad
    hi = np.max([np.add(o.center, o.half_extents) for o in obstacles], axis=0) + pad
    nx, ny, nz = (int(v) for v in np.ceil((hi - lo) / resolution))
    shape = (nx, ny, nz)
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
            theta |= grid_collision(alpha, grid, clusters.subset(np.array([p])), g)
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


