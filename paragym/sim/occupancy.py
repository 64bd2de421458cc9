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

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from paragym.mechanisms import capaman
from paragym.sim.obstacles import Box, Obstacle

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
        # Bounding box of the obstacles plus the margin: the outer cell stays free (see lookup).
        pad = max(2 * resolution, margin or 0.0)
        lo = np.min([np.subtract(o.center, o.half_extents) for o in obstacles], axis=0) - pad
        hi = np.max([np.add(o.center, o.half_extents) for o in obstacles], axis=0) + pad
        shape = np.ceil((hi - lo) / resolution).astype(int)
        axes = [lo[i] + (np.arange(shape[i]) + 0.5) * resolution for i in range(3)]
        centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
        occupied = np.zeros(tuple(shape), bool)
        half = resolution / 2
        for o in obstacles:  # a handful of obstacles; every cell at once
            side = half if isinstance(o, Box) else half * np.sqrt(2.0)
            occupied |= o.contains(centres, inflate=(side, half))
        return cls(occupied, lo, resolution)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners (m)."""
        return self.origin, self.origin + np.array(self.occupied.shape) * self.resolution

    def lookup(self, points: np.ndarray) -> np.ndarray:
        """Psi at points (..., 3): True where occupied (eq 1).

        The grid has a free border one cell wide, so indices are clipped onto
        it instead of masking points outside.
        """
        shape = self.occupied.shape
        pts = np.asarray(points, dtype=np.float32)  # float32/int32: half the memory traffic
        idx = ((pts - self.origin.astype(np.float32)) * np.float32(1.0 / self.resolution)).astype(np.int32)
        np.maximum(idx, 0, out=idx)
        np.minimum(idx, np.array(shape, np.int32) - 1, out=idx)
        flat = (idx[..., 0] * shape[1] + idx[..., 1]) * shape[2] + idx[..., 2]
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
                      key: tuple, max_bytes: int = 64 << 20) -> np.ndarray:
        """World positions (N, M_part, 3) of one part's points at configurations
        ``alpha``; kept under ``key`` when smaller than ``max_bytes`` (the
        joint grid does not change between scenarios, only the obstacles do)."""
        cached = self._grid_cache.get((key, part))
        if cached is not None:
            return cached
        centres, quats = capaman.part_frames(alpha, geometry, validate=False)
        f32 = np.float32
        world = _place(self.local[self.part == part].astype(f32), centres[:, part].astype(f32),
                       capaman.quat_to_matrix(quats[:, part]).astype(f32))
        if world.nbytes <= max_bytes:
            self._grid_cache[(key, part)] = world
        return world


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
        rot = capaman.quat_to_matrix(quats)  # (n, parts, 3, 3)
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
            theta |= grid.lookup(clusters.on_joint_grid(p, alpha, g, (g, points_per_axis))).any(axis=1)
    return theta.reshape((points_per_axis,) * 3), axis


# --- the grid's clearance: signed distances on Psi, for many robots at once ---------------------------------


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
    grid = OccupancyGrid.from_obstacles(obstacles, resolution, margin=cap + 2 * resolution)
    occ = grid.occupied
    outside = ndimage.distance_transform_edt(~occ) * resolution - resolution / 2
    inside = ndimage.distance_transform_edt(occ) * resolution - resolution / 2
    d = np.where(occ, -inside, outside)
    return np.clip(np.round(d / unit), -round(cap / unit), round(cap / unit)).astype(np.int8), grid.origin


class DistanceGrids:
    """The signed-distance grids of N robots' scenes in one flat buffer (one
    slot per robot, as big as the largest grid so far), looked up for all
    robots' cluster points at once."""

    def __init__(self, n: int, resolution: float = 0.005, cap: float = 0.05, unit: float = 0.0005) -> None:
        self.n, self.resolution, self.cap, self.unit = n, resolution, cap, unit
        self.origin = np.zeros((n, 3))
        self.shape = np.ones((n, 3), np.int64)
        self.slot = 1
        self.values = np.full(n, round(cap / unit), np.int8)

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

    def lookup(self, points: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """Signed distances (in ``unit`` steps, int) at points (M, P, 3) of
        robots ``rows`` (M,) (default all); the cap outside a robot's grid."""
        rows = np.arange(self.n) if rows is None else rows
        rel = (points - self.origin[rows, None].astype(points.dtype)) * points.dtype.type(1.0 / self.resolution)
        ix, iy, iz = (np.floor(rel[..., k]).astype(np.int64) for k in range(3))
        sx, sy, sz = (self.shape[rows, k, None] for k in range(3))
        # one unsigned comparison per axis: a negative index wraps to a huge one
        inside = (ix.astype(np.uint64) < sx.astype(np.uint64)) & (iy.astype(np.uint64) < sy.astype(np.uint64)) & (
            iz.astype(np.uint64) < sz.astype(np.uint64))
        flat = (rows * self.slot)[:, None] + (ix * sy + iy) * sz + iz
        out = np.full(inside.shape, round(self.cap / self.unit), np.int64)
        out[inside] = self.values[flat[inside]]
        return out


def grid_clearance(alpha: np.ndarray, grids: DistanceGrids, clusters: ClusterPoints,
                   geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, rows: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The clearance (m, N) of robots at crank angles ``alpha`` (N, 3) from
    their grids (``rows`` of ``grids``, default all): the smallest signed
    distance at any cluster point (negative: a collision by eq 2), and the
    part (N,) that holds that point (-1 when every point is beyond the cap).
    A part whose bounding sphere misses a robot's grid is skipped for that
    robot (its points all read the cap). Element-wise arithmetic only, so
    that a robot's answer does not depend on the others in the batch."""
    n = len(alpha)
    rows = np.arange(n) if rows is None else rows
    centres, quats = capaman.part_frames(alpha, geometry, validate=False)
    rot = capaman.quat_to_matrix(quats)  # (N, parts, 3, 3)
    lo = grids.origin[rows]
    hi = lo + grids.shape[rows] * grids.resolution
    cap = round(grids.cap / grids.unit)
    best = np.full(n, cap, np.int64)
    part = np.full(n, -1, np.int64)
    blocks = _blocks(clusters)
    parts, middles, radii = _block_arrays(clusters)
    # every block's bounding sphere against every robot's grid at once: (N, blocks)
    r = rot[:, parts]
    c = (centres[:, parts] + middles[None, :, 0, None] * r[..., 0] + middles[None, :, 1, None] * r[..., 1]
         + middles[None, :, 2, None] * r[..., 2])
    gap = np.sqrt(np.sum((c - np.clip(c, lo[:, None], hi[:, None])) ** 2, axis=2))
    close = gap <= radii
    for b in np.flatnonzero(close.any(axis=0)):  # a loop over the blocks near some grid, each for all robots at once
        p, local = blocks[b][:2]
        near = np.flatnonzero(close[:, b])
        r, cn = rot[near, p].astype(np.float32), centres[near, p].astype(np.float32)  # element-wise float32
        local = local.astype(np.float32)
        world = (cn[:, None, :] + local[None, :, 0, None] * r[:, None, :, 0]
                 + local[None, :, 1, None] * r[:, None, :, 1] + local[None, :, 2, None] * r[:, None, :, 2])
        low = grids.lookup(world, rows[near]).min(axis=1)
        closer = (low < best[near]) | ((low == best[near]) & (p < part[near]))
        best[near[closer]] = low[closer]
        part[near[closer]] = p
    return best * grids.unit, part


def _blocks(clusters: ClusterPoints, edge: float = 0.06) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
    """The cluster points in blocks of ``edge`` (m) cubes of their part's
    frame: part index, local points (M, 3), the block's centre (3,) and
    bounding radius (m) in the part's frame. Kept on the clusters."""
    key = ("blocks", edge)
    if key not in clusters._grid_cache:
        out = []
        for p in np.unique(clusters.part):
            pts = clusters.local[clusters.part == p]
            cells = np.floor(pts / edge).astype(np.int64)
            _, which = np.unique(cells, axis=0, return_inverse=True)
            for b in range(which.max() + 1):
                block = pts[which.ravel() == b]
                middle = (block.min(axis=0) + block.max(axis=0)) / 2
                out.append((int(p), block, middle, float(np.sqrt(np.sum((block - middle) ** 2, axis=1)).max()) + 1e-9))
        clusters._grid_cache[key] = out
    return clusters._grid_cache[key]


def _block_arrays(clusters: ClusterPoints, edge: float = 0.06) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_blocks` as arrays: part index (B,), centre (B, 3), radius (B,). Kept on the clusters."""
    key = ("block arrays", edge)
    if key not in clusters._grid_cache:
        blocks = _blocks(clusters, edge)
        clusters._grid_cache[key] = (np.array([b[0] for b in blocks]), np.array([b[2] for b in blocks]),
                                     np.array([b[3] for b in blocks]))
    return clusters._grid_cache[key]
