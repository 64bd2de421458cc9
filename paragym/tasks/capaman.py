"""Scenarios of the CaPaMan collision-free task (paper 000, section 4).

One module for the env, the vector env, the planners and the CLI.

A scenario is the obstacles plus the task configurations T.C.1..3 (tool-tip
positions) and their task points T.P.1..3 in the joint space (crank angles
from the inverse kinematics). The tour is T.C.1 -> T.C.2 -> T.C.3 -> T.C.1.

* ``paper_scenario()``: the paper's case as a fixed scenario: a vertical
  cylinder standing on the fixed plate under the movable plate, the three
  T.C.s close around it, so that straight joint-space motion between them
  collides (tested). The paper gives no sizes; these are assumptions.
* ``random_scenario(rng)``: seeded random obstacles (cylinders and boxes on
  the fixed plate, below the movable plate) and T.P.s, generated feasible:
  every T.P. collision-free with a margin (PyBullet), and all three in one
  connected free component of the joint matrix Theta (paper 000's collision
  map on a joint grid, colliding cells grown by one), so a collision-free
  tour exists at that resolution (the tests follow one with a planner).
* ``ladder_scenarios(rngs, rung)``: a rung of the difficulty ladder
  (:data:`LADDER`): capsule posts standing on the fixed plate, some of them on
  the straight joint-space lines between the T.P.s, so that a rung's tour
  needs detours; drawn by one compiled kernel (:func:`_ladder_kernel`) and
  judged by the exact capsule model of :mod:`paragym.sim.capaman_posts`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numba import njit
from scipy import ndimage

from paragym.kernels import entry
from paragym.mechanisms import capaman
from paragym.sim import capaman_grid
from paragym.sim.capaman_posts import forward_table, k_post_clearance, kernel_constants, post_ceiling, post_clearance
from paragym.sim.capaman_scene import CaPaManScene
from paragym.sim.obstacles import Box, Capsule, Cylinder, Obstacle
from paragym.tasks import base
from paragym.units import DEG

__all__ = ["CaPaManRung", "CaPaManScenario", "draw_scenarios", "knob_table", "ladder_scenarios", "paper_scenario",
           "posts_of", "random_scenario", "resolve_scenario", "scene_clearance", "solvable", "validate_scenario",
           "LADDER", "LADDER_MAX_OBSTACLES", "MAX_OBSTACLES", "SCENARIOS", "TOUR", "WITNESSES"]

SCENARIOS = ("paper", "random")

MAX_OBSTACLES = 3
TOUR = (1, 2, 0)  # indices of the T.C.s visited after starting at T.C.1 (index 0)


@dataclass(frozen=True)
class CaPaManScenario:
    """Obstacles and task of one CaPaMan episode (frozen; SI units).

    Attributes:
        name: "paper", "random" or a user label.
        obstacles: up to ``MAX_OBSTACLES`` cylinders/boxes.
        task_points: T.P.1..3, crank angles (3, 3) rad, as nested tuples.
        task_configs: T.C.1..3, tool-tip positions (3, 3) m.
        seed: the seed that generated it (random scenarios), else None.
    """

    name: str
    obstacles: tuple[Obstacle, ...]
    task_points: tuple[tuple[float, float, float], ...]
    task_configs: tuple[tuple[float, float, float], ...] = field(default=())
    seed: int | None = None

    @classmethod
    def from_tool_tips(cls, tips: Sequence[Sequence[float]] | np.ndarray, obstacles: Sequence[Obstacle],
                       name: str = "custom", geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY
                       ) -> CaPaManScenario:
        """Build a scenario from three tool-tip positions (m); the task points
        come from the inverse kinematics (``ValueError`` if unreachable)."""
        tips_arr = np.asarray(tips, float)
        if tips_arr.shape != (3, 3):
            raise ValueError(f"tips must be three 3-D points, shape (3, 3); got {tips_arr.shape}")
        alpha = capaman.inverse_tool_tip(tips_arr, geometry)
        return cls(name, tuple(obstacles), _tuples(alpha), _tuples(tips_arr))

    @property
    def alpha(self) -> np.ndarray:
        """Task points as an array (3, 3), rad."""
        return np.array(self.task_points)


def _tuples(a: np.ndarray) -> tuple[tuple[float, float, float], ...]:
    return tuple(tuple(row) for row in np.asarray(a, float).tolist())


@lru_cache(maxsize=8)
def paper_scenario(geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY) -> CaPaManScenario:
    """The paper's case (section 4, Fig 3a), with assumed sizes.

    A cylinder of radius 15 mm and height 100 mm stands at the centre of the
    fixed plate; T.C.1..3 put the tool tip 35 mm from its axis at 90, 210 and
    330 deg, 50 mm above the fixed plate (inside the paper's 6 cm circle).
    """
    obstacle = Cylinder(center=(0.0, 0.0, 0.05), radius=0.015, height=0.10)
    ang = np.radians([90.0, 210.0, 330.0])
    tips = np.column_stack([0.035 * np.cos(ang), 0.035 * np.sin(ang), np.full(3, 0.05)])
    return CaPaManScenario.from_tool_tips(tips, [obstacle], name="paper", geometry=geometry)


def validate_scenario(scenario: CaPaManScenario, scene: CaPaManScene, max_obstacles: int = MAX_OBSTACLES,
                      rung: CaPaManRung | None = None) -> None:
    """Raise ``ValueError`` if the scenario is malformed (more than ``max_obstacles``), a task point is out
    of range, or the manipulator collides at a task configuration
    (PyBullet's exact check). On a rung of :data:`LADDER` (its own number of posts then), also unless
    every obstacle is a :class:`~paragym.sim.obstacles.Capsule` whose top is the clearance cap below the
    plate's floor (:func:`~paragym.sim.capaman_posts.post_ceiling`) and every T.C. is free in the capsule model.
    Leaves the scene's obstacles set."""
    base.resolve_scenario(scenario, (), CaPaManScenario)
    if rung is not None:
        posts = posts_of(scenario.obstacles)
        max_obstacles = rung.max_obstacles
    if not 1 <= len(scenario.obstacles) <= max_obstacles:
        raise ValueError(f"a scenario has 1 to {max_obstacles} obstacles; got {len(scenario.obstacles)}")
    alpha = capaman.check_joint_angles(scenario.alpha, scene.geometry, name="scenario.task_points")
    if alpha.shape != (3, 3):
        raise ValueError(f"scenario.task_points must be three configurations; got {alpha.shape}")
    scene.set_obstacles(scenario.obstacles)
    for i, a in enumerate(alpha):
        scene.set_configuration(a)
        d, part = scene.clearance()
        if d <= 0.0:
            raise ValueError(f"scenario T.C.{i + 1} collides: the {part} is {-d * 1000:.1f} mm inside an obstacle")
    if rung is None:
        return
    highest = post_ceiling(scene.geometry)
    for k, o in enumerate(scenario.obstacles):
        if isinstance(o, Capsule) and o.top > highest:  # (every one is: posts_of took them)
            raise ValueError(f"obstacle {k}'s top is at {o.top * 1000:.1f} mm: a rung's posts end below "
                             f"{highest * 1000:.1f} mm, the clearance cap under the plate's lowest reach")
    clearance = scene_clearance(alpha, posts, scene.geometry)
    for i, d in enumerate(clearance):
        if d <= 0.0:
            raise ValueError(f"scenario T.C.{i + 1} collides in the capsule model: {-d * 1000:.1f} mm inside a post")


def _random_obstacles(rng: np.random.Generator) -> list[Obstacle]:
    """1-3 cylinders or boxes standing on the fixed plate near its centre,
    10 mm to 25 mm wide and 60 mm to 100 mm tall (below the movable plate)."""
    out: list[Obstacle] = []
    for _ in range(int(rng.integers(1, MAX_OBSTACLES + 1))):
        r = rng.uniform(0.0, 0.05)
        t = rng.uniform(0.0, 2 * np.pi)
        height = rng.uniform(0.06, 0.10)
        centre = (r * np.cos(t), r * np.sin(t), height / 2)
        if rng.random() < 0.5:
            out.append(Cylinder(centre, radius=rng.uniform(0.008, 0.02), height=height))
        else:
            out.append(Box(centre, half_extents=(rng.uniform(0.006, 0.016), rng.uniform(0.006, 0.016),
                                                  height / 2)))
    return out


def random_scenario(rng: np.random.Generator, scene: CaPaManScene,
                    clusters: capaman_grid.ClusterPoints | None = None, min_clearance: float = 0.004,
                    grid_points: int = 16, max_tries: int = 50) -> CaPaManScenario:
    """A seeded random feasible scenario (see the module docstring).

    T.P.s are drawn in the free cells of a ``grid_points``^3 joint matrix
    Theta (6 deg cells by default; cluster points every 10 mm unless
    ``clusters`` are given) with the colliding cells grown by one cell, in one
    connected component (26-neighbours),
    at least 20 deg apart, and each must have ``min_clearance`` (m) in
    PyBullet. Leaves the scene's obstacles set.
    """
    g = scene.geometry
    clusters = clusters or capaman_grid.cluster_points(g, spacing=0.01)
    for _ in range(max_tries):
        obstacles = _random_obstacles(rng)
        grid = capaman_grid.OccupancyGrid.from_obstacles(obstacles)
        theta, axis = capaman_grid.joint_matrix(grid, clusters, grid_points, g)
        blocked = ndimage.binary_dilation(theta, structure=np.ones((3, 3, 3), bool))  # edges stay clear
        labels, count = ndimage.label(~blocked, structure=np.ones((3, 3, 3)))
        if count == 0:
            continue
        sizes = np.bincount(labels.ravel())[1:]
        biggest = 1 + int(np.argmax(sizes))
        cells = np.argwhere(labels == biggest)
        if len(cells) < 10:
            continue
        scene.set_obstacles(obstacles)
        chosen: list[np.ndarray] = []
        for _ in range(60):
            a = axis[cells[rng.integers(len(cells))]]
            if any(np.linalg.norm(a - b) < 20 * DEG for b in chosen):
                continue
            scene.set_configuration(a)
            if scene.clearance()[0] < min_clearance:
                continue
            chosen.append(a)
            if len(chosen) == 3:
                alpha = np.array(chosen)
                tips = capaman.tool_tip(capaman.forward(alpha, g, validate=False), g)
                return CaPaManScenario("random", tuple(obstacles), _tuples(alpha), _tuples(tips))
    raise RuntimeError(f"no feasible random scenario in {max_tries} tries")


# --- the difficulty ladder ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class CaPaManRung:
    """The knobs of one rung of the CaPaMan's difficulty ladder (:func:`ladder_scenarios`).

    Attributes:
        blocked_legs: of the tour's three legs, how many have a post standing on their straight joint-space line
            (where the tool is midway along it), so that going straight collides there.
        clutter: further posts anywhere within :data:`CLUTTER_RADIUS` of the plate's centre.
        radius: the posts' radius range (m).
        spread: the least joint distance (rad) between two T.P.s.
        gap: the least distance (m) between two posts' surfaces that do not overlap: the narrowest passage (the
            tool is 10 mm thick).
    """

    blocked_legs: int
    clutter: int
    radius: tuple[float, float]
    spread: float
    gap: float

    @property
    def max_obstacles(self) -> int:
        """The posts of the rung's every scenario (its observation's obstacle slots)."""
        return self.blocked_legs + self.clutter

    @property
    def spread_deg(self) -> float:
        """``spread`` in degrees (the rung pages show it)."""
        return round(math.degrees(self.spread), 6)


#: the CaPaMan's difficulty ladder, easiest first: posts on one, two and all three legs' straight lines, with
#: one, two and one posts of clutter, wider and closer together up the ladder
LADDER = (CaPaManRung(1, 1, (0.005, 0.008), 40 * DEG, 0.025), CaPaManRung(2, 2, (0.010, 0.014), 40 * DEG, 0.02),
          CaPaManRung(3, 1, (0.010, 0.014), 50 * DEG, 0.016))
#: the most obstacles any scenario of the ladder has
LADDER_MAX_OBSTACLES = max(r.max_obstacles for r in LADDER)
#: the clutter posts' centres lie within this distance (m) of the fixed plate's centre: the tool tip's reach
CLUTTER_RADIUS = 0.065
#: a post's top (m) is drawn from this range; its upper end keeps it the clearance cap below the plate
#: (:func:`paragym.sim.capaman_posts.plate_floor`), so the plate never nears it
POST_TOP = (0.075, 0.09)
#: the least clearance (m) of each T.P. in the capsule model: more than the 8 mm by which paper 000's 5 mm grid
#: may grow an obstacle, so that the planners on the grid see every T.P. free (at 5 mm, 1 of 50 tours failed so)
LADDER_CLEARANCE = 0.009
#: the T.P.s are drawn this far (rad) inside the joint range, so that a detour can pass a post on either side
LADDER_EDGE = 5 * DEG
#: how often :func:`_ladder_kernel` tries to place one post; the uniforms one attempt may read (the T.P.s, the
#: legs' order, four per try of the most posts a rung has); attempts per block of them
_TRIES = 8
_ATTEMPT, _BLOCK = 12 + 4 * _TRIES * LADDER_MAX_OBSTACLES, 4


def knob_table(indent: str = "") -> str:
    """The knobs of every rung of :data:`LADDER` as a reStructuredText table (the rung pages show it)."""
    return base.knob_table(LADDER, {"blocked_legs": "legs with a post on their straight line",
                                    "clutter": "further posts", "radius": "post radius (m)",
                                    "spread_deg": "T.P.s apart (deg)", "gap": "posts apart (m)"}, indent)


#: one post at a time for :func:`_ladder_kernel`, typed as a call from Python types a count (a literal 1 would
#: compile :func:`~paragym.sim.capaman_posts.k_post_clearance` a second time)
_ONE_POST = np.int64(1)


@njit(cache=True, error_model="numpy")
def _ladder_kernel(u, knobs, model, cap, tp, tips, posts):
    """The first attempt (a row of ``u``, uniforms in [0, 1)) that makes a scenario of the rung; writes its T.P.s
    ``tp`` (3, 3) rad, their tool tips ``tips`` (3, 3) m and its posts ``posts`` (K, 5) and returns its index,
    or -1. An attempt draws three T.P.s inside the joint range less ``edge``, at least ``spread`` apart; orders
    the legs at random and stands a post on the first ``blocked``: at the tool tip of a configuration 40-60 %
    along the leg's straight line, moved by at most a third of its radius; then ``clutter`` posts anywhere
    within :data:`CLUTTER_RADIUS`. A post is tried up to :data:`_TRIES` times until it is ``gap`` from the
    posts before it or overlaps them (one obstacle then, with no slit), leaves every T.P.
    ``min_clearance`` and, on a blocked leg, collides there; the attempt fails when one is not placed.
    ``knobs``: the rung's, :func:`_ladder_args`; ``model``: the geometry's
    :func:`~paragym.sim.capaman_posts.kernel_constants`."""
    blocked, clutter, r_low, r_high, spread, gap, top_low, top_high, edge, alpha_min, alpha_max, min_clearance = knobs
    consts, radius = model[0], model[9]
    legs = ((0, 1), (1, 2), (2, 0))
    tip = np.empty(3)
    every = np.ones(radius.shape[0], np.bool_)  # every part placed
    mids = np.empty((3, 3))  # the blocked legs' configurations where their posts stand
    n = blocked + clutter
    for attempt in range(u.shape[0]):
        v = u[attempt]
        lo, span = alpha_min + edge, alpha_max - alpha_min - 2 * edge
        for i in range(3):
            for c in range(3):
                tp[i, c] = lo + span * v[3 * i + c]
        close = False
        for i, j in legs:
            d = 0.0
            for c in range(3):
                d += (tp[i, c] - tp[j, c]) ** 2
            close = close or math.sqrt(d) < spread
        if close:
            continue
        poses = (capaman.k_forward(tp[0, 0], tp[0, 1], tp[0, 2], consts),
                 capaman.k_forward(tp[1, 0], tp[1, 1], tp[1, 2], consts),
                 capaman.k_forward(tp[2, 0], tp[2, 1], tp[2, 2], consts))
        order = np.argsort(v[9:12])  # the legs in a random order
        ok = True
        for b in range(n):  # each post tried up to _TRIES times where it keeps the gap and the T.P.s' clearance
            placed = False
            for k in range(_TRIES):
                w = v[12 + 4 * (_TRIES * b + k):]
                r = r_low + (r_high - r_low) * w[0]
                top = top_low + (top_high - top_low) * w[1]
                if b < blocked:
                    i, j = legs[order[b]]
                    t = 0.4 + 0.2 * w[2]
                    for c in range(3):
                        mids[b, c] = tp[i, c] + t * (tp[j, c] - tp[i, c])
                    f = capaman.k_forward(mids[b, 0], mids[b, 1], mids[b, 2], consts)
                    turn, shift = 2 * math.pi * w[3], r / 3 * w[2]
                    x, y = f[8] + shift * math.cos(turn), f[9] + shift * math.sin(turn)
                else:
                    rho, turn = CLUTTER_RADIUS * math.sqrt(w[2]), 2 * math.pi * w[3]
                    x, y = rho * math.cos(turn), rho * math.sin(turn)
                posts[b, 0], posts[b, 1], posts[b, 2], posts[b, 3], posts[b, 4] = x, y, 0.0, top - r, r
                placed = True
                for e in range(b):  # apart by the gap at least, or overlapping (one obstacle, no slit)
                    apart = math.hypot(x - posts[e, 0], y - posts[e, 1]) - r - posts[e, 4]
                    placed = placed and (apart >= gap or apart <= 0.0)
                for i in range(3):
                    if placed:
                        d, _ = k_post_clearance(tp[i, 0], tp[i, 1], tp[i, 2], poses[i], posts[b:b + 1], _ONE_POST,
                                                every, model, cap, tip)
                        placed = d >= min_clearance
                if placed and b < blocked:
                    d, _ = k_post_clearance(mids[b, 0], mids[b, 1], mids[b, 2], f, posts[b:b + 1], _ONE_POST, every,
                                            model, cap, tip)
                    placed = d < 0.0
                if placed:
                    break
            if not placed:
                ok = False
                break
        if ok:  # the tool tips at the T.P.s
            for i in range(3):
                tips[i, 0], tips[i, 1], tips[i, 2] = poses[i][8], poses[i][9], poses[i][10]
        if ok:
            return attempt
    return -1


@njit(cache=True, error_model="numpy")
def _ladder_draw(rng, max_blocks, knobs, model, cap, tp, tips, posts):
    """One generator's scenario of the rung: blocks of :data:`_BLOCK` attempts of uniforms drawn from ``rng`` (a
    ``numpy.random.Generator``; numba draws numpy's own stream from it, and the generator moves on as in
    Python) until :func:`_ladder_kernel` makes one of them a scenario, at most ``max_blocks``; whether it did."""
    for _ in range(max_blocks):
        u = rng.random((_BLOCK, _ATTEMPT))
        if _ladder_kernel(u, knobs, model, cap, tp, tips, posts) >= 0:
            return True
    return False


#: :func:`_ladder_draw`'s compiled entry per rung, geometry and kind of bit generator (the types of its call)
_DRAWS: dict[tuple[Any, ...], Any] = {}


@lru_cache(maxsize=16)
def _ladder_args(rung: CaPaManRung, geometry: capaman.CaPaManGeometry) -> tuple[Any, ...]:
    """What :func:`_ladder_draw` takes after ``max_blocks``, made once per rung and geometry: the rung's knobs
    (the number of blocked legs and of clutter posts, the posts' radii, the T.P.s' spread, the posts' gap, their
    tops' range, the joint range's edge and bounds, the T.P.s' clearance), the geometry's
    :func:`~paragym.sim.capaman_posts.kernel_constants` and the clearance cap."""
    g = geometry
    top_high = min(POST_TOP[1], post_ceiling(g))
    knobs = (rung.blocked_legs, rung.clutter, *rung.radius, rung.spread, rung.gap, POST_TOP[0], top_high, LADDER_EDGE,
             g.alpha_min, g.alpha_max, LADDER_CLEARANCE)
    return knobs, kernel_constants(g), 0.05


def ladder_scenarios(rngs: list[np.random.Generator], rung: CaPaManRung,
                     geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                     max_blocks: int = 10_000) -> list[CaPaManScenario]:
    """One scenario of a rung per generator (named "random" on the rung's env id): each generator gives blocks
    of :data:`_BLOCK` attempts of uniforms until :func:`_ladder_kernel` makes one of them a scenario (the
    stream is numpy's, so the same on every machine; one compiled call per generator, :func:`_ladder_draw`).
    The posts are :class:`~paragym.sim.obstacles.Capsule` s standing on the fixed plate (their segment from
    z = 0). That a collision-free tour exists is checked by :func:`solvable` over 100 seeds per
    rung in the tests, and as many as asked by ``benchmarks/capaman_solvable.py`` (1,000 when the ladder was made)."""
    n = len(rngs)
    args = _ladder_args(rung, geometry)
    tp, tips, posts = np.empty((n, 3, 3)), np.empty((n, 3, 3)), np.empty((n, rung.max_obstacles, 5))
    for r, rng in enumerate(rngs):
        call = (rng, max_blocks, *args, tp[r], tips[r], posts[r])
        key = (rung, geometry, type(rng.bit_generator))
        draw = _DRAWS.get(key) or _DRAWS.setdefault(key, entry(_ladder_draw, call))  # typed once, not per call
        if not draw(*call):
            raise RuntimeError(f"no scenario of the rung in {max_blocks * _BLOCK} attempts")
    out = []
    for r in range(n):
        obstacles = tuple(Capsule((float(x), float(y), float(high) / 2), float(radius), float(high))
                          for x, y, _, high, radius in posts[r].tolist())
        out.append(CaPaManScenario("random", obstacles, _tuples(tp[r]), _tuples(tips[r])))
    return out


def scene_clearance(alpha: np.ndarray, posts: np.ndarray, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                    poses: np.ndarray | None = None, cap: float = 0.05) -> np.ndarray:
    """The capsule model's clearance (m, capped at ``cap``) of configurations ``alpha`` (M, 3) among one scene's
    ``posts`` (K, 5, :func:`posts_of`); ``poses`` as :func:`~paragym.sim.capaman_posts.post_clearance` takes
    them."""
    rows = np.zeros(len(np.atleast_2d(alpha)), np.int64)
    return post_clearance(alpha, posts[None], np.array([len(posts)]), rows, geometry, cap=cap, poses=poses)[0]


def posts_of(obstacles: Sequence[Obstacle]) -> np.ndarray:
    """Capsule obstacles as the posts (K, 5) of :mod:`paragym.sim.capaman_posts` (``ValueError`` on another
    kind)."""
    out = np.empty((len(obstacles), 5))
    for k, o in enumerate(obstacles):
        if not isinstance(o, Capsule):
            raise ValueError(f"the capsule model takes Capsule obstacles; obstacle {k} is a {type(o).__name__}")
        out[k] = o.center[0], o.center[1], o.center[2] - o.height / 2, o.center[2] + o.height / 2, o.radius
    return out


@lru_cache(maxsize=2)
def _joint_grid(geometry: capaman.CaPaManGeometry, points_per_axis: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The axis (rad), the nodes (M, 3) and their poses (:func:`~paragym.sim.capaman_posts.forward_table`) of a
    ``points_per_axis``^3 grid of the joint range."""
    axis = np.linspace(geometry.alpha_min, geometry.alpha_max, points_per_axis)
    grid = np.ascontiguousarray(np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3))
    return axis, grid, forward_table(grid, geometry)


#: the witnesses :func:`solvable` tries in turn: (grid points per axis, margin in m); the coarse one settles
#: almost every scene, the fine one the few whose passages are narrower than its margin and cells allow
WITNESSES = ((46, 0.001), (61, 0.0))


def solvable(scenario: CaPaManScenario, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
             witnesses: tuple[tuple[int, float], ...] = WITNESSES) -> bool:
    """Whether a collision-free tour of a capsule scenario exists at the resolution of a grid of the joint range,
    by the first of ``witnesses`` (points per axis, margin in m) that finds one: the nodes whose clearance in the
    capsule model is under the margin, grown by one node, are blocked, and the free node nearest each T.P. must
    lie in one connected (26-neighbour) component. A witness, not a proof: a path along free nodes passes at
    least the margin and a cell (2 deg at 46 points, 1.5 deg at 61) from every blocked node."""
    return any(_witness(scenario, geometry, n, margin) for n, margin in witnesses)


def _witness(scenario: CaPaManScenario, geometry: capaman.CaPaManGeometry, points_per_axis: int,
             margin: float) -> bool:
    """One witness of :func:`solvable`."""
    axis, grid, poses = _joint_grid(geometry, points_per_axis)
    # only "under the margin" matters: a cap just above it leaves every answer and skips the parts out of its reach
    clearance = scene_clearance(grid, posts_of(scenario.obstacles), geometry, poses,
                                cap=margin + 0.004).reshape((points_per_axis,) * 3)
    blocked = ndimage.binary_dilation(clearance < margin, structure=np.ones((3, 3, 3), bool))
    labels, _ = ndimage.label(~blocked, structure=np.ones((3, 3, 3)))
    free = np.argwhere(labels > 0)
    if not len(free):
        return False
    found = set()
    for a in scenario.alpha:
        node = free[np.argmin(np.linalg.norm(axis[free] - a, axis=1))]
        found.add(int(labels[tuple(node)]))
    return len(found) == 1


def resolve_scenario(choice: Any) -> str | CaPaManScenario:
    """The scenario argument's kind checked (:func:`paragym.tasks.base.resolve_scenario`):
    "paper", "random" or a :class:`CaPaManScenario`. Whether a custom one
    can run needs PyBullet: :func:`draw_scenario` checks it at reset."""
    return base.resolve_scenario(choice, SCENARIOS, CaPaManScenario)


def draw_scenarios(choice: Any, rngs: list[np.random.Generator], scene: CaPaManScene,
                   clusters: capaman_grid.ClusterPoints | None = None) -> list[CaPaManScenario]:
    """One episode's scenario per generator (single env, vector env and CLI alike): the paper's, random
    ones drawn from the generators one after another, or the custom one once :func:`validate_scenario`
    accepts it. Leaves ``scene``'s obstacles set to the last one's."""
    choice = resolve_scenario(choice)
    return [_draw_one(choice, rng, scene, clusters) for rng in rngs]


def _draw_one(choice: Any, rng: np.random.Generator, scene: CaPaManScene,
              clusters: capaman_grid.ClusterPoints | None = None) -> CaPaManScenario:
    """:func:`draw_scenarios` for one generator (the name of before paragym 0.9: ``draw_scenario``)."""
    choice = resolve_scenario(choice)
    if choice == "random":
        return random_scenario(rng, scene, clusters)
    scenario = paper_scenario(scene.geometry) if choice == "paper" else choice
    validate_scenario(scenario, scene)
    return scenario


#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = base.renamed(__name__, {"resolve_capaman": "resolve_scenario", "draw_scenario": "_draw_one"})
