"""The Orthoglide task's scenarios (paper 003): paths in the table frame, the paper's circle, random paths.

A :class:`OrthoglideScenario` is the path the tool follows; the paper's case is the 0.8 m
circle of section 6; random tasks are seeded circles, ellipses and lines that
an admissible table position serves. Used by the env, the vector env, the
planner and the CLI alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym.mechanisms import orthoglide as og
from paragym.tasks import base

__all__ = ["LADDER", "SCENARIOS", "OrthoglideRung", "OrthoglideScenario", "circle_task", "draw_scenarios",
           "knob_table", "ladder_scenarios", "paper_scenario", "random_scenario", "random_scenarios",
           "resolve_scenario", "servable", "start_table_position", "validate_scenario"]

SCENARIOS = ("paper", "random")


@dataclass(frozen=True)
class OrthoglideScenario:
    """A path in the table frame: times (K,) s, points (K, 2) m, velocities (K, 2) m/s."""

    name: str
    t: np.ndarray
    points: np.ndarray
    velocities: np.ndarray


def circle_task(centre: tuple[float, float], radius: float, duration: float = 10.0, start: float = 0.0,
                steps: int = 1000, name: str = "circle") -> OrthoglideScenario:
    """A circle run once counter-clockwise from angle ``start`` (rad) in ``duration`` s."""
    t = np.linspace(0.0, duration, steps + 1)
    w = 2 * np.pi / duration
    ang = start + w * t
    pts = np.asarray(centre) + radius * np.stack([np.cos(ang), np.sin(ang)], 1)
    vel = radius * w * np.stack([-np.sin(ang), np.cos(ang)], 1)
    return OrthoglideScenario(name, t, pts, vel)


def paper_scenario() -> OrthoglideScenario:
    """Paper 003, section 6: a 0.8 m circle centred at (0.1, 0.55) m in the
    table frame, in 10 s. The paper does not say where the circle starts; it
    starts here where the fixed table's worst kappa falls near t = 2.2 s, as
    in the paper's Fig 11 (angle 5.70 rad)."""
    return circle_task((0.1, 0.55), 0.4, 10.0, start=np.pi + 2 * np.pi * 0.407, name="paper")


def _sweep(table: np.ndarray, points: np.ndarray, g: og.OrthoglideGeometry
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every (point, table position) pair of points (K, 2) and positions (T,),
    point-major: rho1, px, py (K * T,) and whether the pair is admissible
    (reachable in the working mode, rho2 and rho3 inside their limits)."""
    rr = np.tile(table, len(points))
    px, py = np.repeat(points[:, 0], len(table)), np.repeat(points[:, 1], len(table))
    rho, mode = og.inverse(rr, np.stack([px, py], 1), g)
    r2, r3 = rho[:, 1], rho[:, 2]
    with np.errstate(invalid="ignore"):
        inside = (r2 >= g.rho_min[1]) & (r2 <= g.rho_max[1]) & (r3 >= g.rho_min[2]) & (r3 <= g.rho_max[2])
    return rr, px, py, mode & inside


def servable(points: np.ndarray, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
             samples: int = 101) -> np.ndarray:
    """Whether some table position among ``samples`` over its range serves
    each table-frame point (K, 2): reachable in the working mode and inside
    the joint limits. There J has full rank (det A = r4 x r5 > 0 and B's
    last two columns are r4x e1 and r5y e2 with r4x, r5y > 0), so kappa is
    finite: the same answer as sweeping kappa itself, several times cheaper.
    Every 25th position is tried first; only the points none of those serve
    are swept in full (the same answer: any of a subset is any of the whole)."""
    g = geometry
    r1 = np.linspace(g.rho_min[0], g.rho_max[0], samples)

    def any_of(table: np.ndarray, pts: np.ndarray) -> np.ndarray:
        return np.asarray(_sweep(table, pts, g)[3].reshape(len(pts), len(table)).any(axis=1))

    chunk = 2 ** 16 // samples  # points per pass: arrays that stay in the cache
    out = np.concatenate([any_of(r1[::25], points[lo:lo + chunk]) for lo in range(0, len(points), chunk)])
    rest = np.flatnonzero(~out)
    for lo in range(0, rest.size, chunk):
        out[rest[lo:lo + chunk]] = any_of(r1, points[rest[lo:lo + chunk]])
    return out


_KINDS = ("circle", "ellipse", "line")
_KIND_ARRAY = np.array(_KINDS)  # what rng.choice makes of the tuple, made once
_CENTRE_LOW, _CENTRE_HIGH = np.array([-0.2, 0.3]), np.array([0.4, 0.8])  # m, table frame
_TIMES = np.linspace(0.0, 10.0, 1001)  # the random tasks' times (s), shared by them: read-only
_TIMES.setflags(write=False)
# a line's share of the way and its rate (1/s) at those times
_LINE_SHAPE = np.array([0.5 - 0.5 * np.cos(np.pi * _TIMES / 10.0), 0.5 * np.pi / 10.0 * np.sin(np.pi * _TIMES / 10.0)])


def _draw_path(rng: np.random.Generator) -> tuple[int, list[float]]:
    """One candidate path's kind (index into circle, ellipse, line) and
    parameters, drawn from ``rng``: the centre (x, y), then for a line its end
    (x, y), for a circle or an ellipse the radii rx, ry and the start angle."""
    kind = str(rng.choice(_KIND_ARRAY))
    centre = rng.uniform(_CENTRE_LOW, _CENTRE_HIGH)
    if kind == "line":
        return 2, [*centre, *(centre + rng.uniform(-0.5, 0.5, 2))]
    rx = rng.uniform(0.1, 0.4)
    ry = rng.uniform(0.1, 0.4) if kind == "ellipse" else rx
    return _KINDS.index(kind), [*centre, rx, ry, rng.uniform(0, 2 * np.pi)]


def _path(kind: int, q: list[float], step: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Points and velocities (1001 / step, 2) of a drawn path at every
    ``step``-th of its times :data:`_TIMES` (10 s): a circle or an ellipse
    run once from its start angle, or a rest-to-rest line (0.5 - 0.5
    cos(pi t / 10) of the way)."""
    t = _TIMES[::step]
    pts, vel = np.empty((len(t), 2)), np.empty((len(t), 2))
    if kind == 2:  # from a = q[:2] to b = q[2:4]
        s, ds = _LINE_SHAPE[0, ::step], _LINE_SHAPE[1, ::step]
        for k in range(2):
            d = q[2 + k] - q[k]
            pts[:, k], vel[:, k] = q[k] + d * s, d * ds
    else:  # centre q[:2], radii q[2:4], start angle q[4]
        w = 2 * np.pi / 10.0
        ang = q[4] + w * t
        c, sn = np.cos(ang), np.sin(ang)
        pts[:, 0], pts[:, 1] = q[0] + q[2] * c, q[1] + q[3] * sn
        vel[:, 0], vel[:, 1] = w * (-q[2] * sn), w * (q[3] * c)
    return pts, vel


def random_scenarios(rngs: list[np.random.Generator], geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                     max_tries: int = 100) -> list[OrthoglideScenario]:
    """One seeded circle, ellipse or line (10 s) per generator, each drawn
    until some admissible table position serves every tenth point (a sweep of
    101 table positions, :func:`servable`). Each generator draws exactly what
    it would alone (a candidate, then the test); the candidates of all
    pending generators are tested in one batch."""
    tasks: list[OrthoglideScenario | None] = [None] * len(rngs)
    pending = np.arange(len(rngs))
    for _ in range(max_tries):
        if not pending.size:
            return [task for task in tasks if task is not None]  # every one by now
        drawn = [_draw_path(rngs[i]) for i in pending]
        every_tenth = np.concatenate([_path(kind, q, 10)[0] for kind, q in drawn])
        ok = servable(every_tenth, geometry).reshape(len(drawn), -1).all(axis=1)
        for j in np.flatnonzero(ok):
            kind, q = drawn[j]
            tasks[pending[j]] = OrthoglideScenario(_KINDS[kind], _TIMES, *_path(kind, q))
        pending = pending[~ok]
    raise RuntimeError(f"no reachable random path in {max_tries} tries")


@dataclass(frozen=True)
class OrthoglideRung:
    """The knobs of one rung of the Orthoglide's difficulty ladder (:func:`ladder_scenarios`).

    Attributes:
        share: success asks for a mean kappa at most this share of the way from 1 to the least-norm motion's
            on the same path (:func:`paragym.tasks.orthoglide_step.kappa_bounds`).
        radius: the radii of the circles and ellipses (m), drawn uniformly in [low, high].
        period: the time (s) of one lap.
        actions: the action mode the rung fixes (the env's ``action_mode``): "null_space", where the env keeps
            the tool on the path and the policy chooses the table's null-space rate, or "joint_velocity", where
            the policy drives all three joints and must track the path itself, eq 5 in full (the observation
            then shows the tool's offset from the path point).
        left_penalty: a failure's cost per path point left, beyond the env's ``limit_penalty``: every step's
            reward is at most 0 (-log kappa, the tracking cost), so without it failing at once pays better than
            tracking the path; 1 per point is more than a tracking step costs on the rung's paths (log kappa
            about 0.1, the tracking cost at most 0.5), so failing no longer pays. Where the env tracks for the
            policy (null-space actions) a failure is rare and the rungs leave it at 0.
    """

    share: float
    radius: tuple[float, float]
    period: float
    actions: str = "null_space"
    left_penalty: float = 0.0


#: the Orthoglide's difficulty ladder, easiest first: closed paths (circles and ellipses, where the table's
#: null-space choice matters: on random lines the paper's gradient cannot beat the least-norm motion on one in
#: five) and a bound on the mean kappa that the least-norm motion never meets; a rung tightens the bound and
#: speeds the lap. On the hard rung the policy drives the joints (eq 5 in full): in null-space actions PPO
#: matched the paper's gradient within a minute on every rung, the choice being one rate along n.
LADDER = (OrthoglideRung(share=0.7, radius=(0.1, 0.4), period=10.0),
          OrthoglideRung(share=0.7, radius=(0.2, 0.4), period=7.0),
          OrthoglideRung(share=0.65, radius=(0.25, 0.4), period=5.0, actions="joint_velocity", left_penalty=1.0))


def knob_table(indent: str = "") -> str:
    """The knobs of every rung of :data:`LADDER` as a reStructuredText table (the rung pages show it)."""
    return base.knob_table(LADDER, {"share": "share of the least-norm excess", "radius": "radii (m)",
                                    "period": "lap (s)", "actions": "actions",
                                    "left_penalty": "failure cost per point left"}, indent)


def ladder_scenarios(rngs: list[np.random.Generator], rung: OrthoglideRung,
                     geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY, max_tries: int = 100
                     ) -> list[OrthoglideScenario]:
    """One path of a rung per generator (named "random" on the rung's env id), drawn from it in this order, again
    until some admissible table position serves every tenth point (:func:`servable`): circle or ellipse, the
    centre (x in -0.2-0.4 m, y in 0.3-0.8 m, table frame), the radii in ``radius`` (equal for a circle), the
    start angle; one lap in ``period`` s, sampled every 10 ms."""
    times = np.linspace(0.0, rung.period, int(round(rung.period * 100)) + 1)
    w = 2 * np.pi / rung.period
    tasks: list[OrthoglideScenario | None] = [None] * len(rngs)
    for i, rng in enumerate(rngs):
        for _ in range(max_tries):
            kind = ("circle", "ellipse")[int(rng.integers(2))]
            cx, cy = rng.uniform(_CENTRE_LOW, _CENTRE_HIGH)
            rx = rng.uniform(*rung.radius)
            ry = rng.uniform(*rung.radius) if kind == "ellipse" else rx
            ang = rng.uniform(0, 2 * np.pi) + w * times
            points = np.stack([cx + rx * np.cos(ang), cy + ry * np.sin(ang)], axis=1)
            if servable(points[::10], geometry).all():
                velocities = np.stack([-w * rx * np.sin(ang), w * ry * np.cos(ang)], axis=1)
                tasks[i] = OrthoglideScenario(kind, times, points, velocities)
                break
        if tasks[i] is None:
            raise RuntimeError(f"no reachable path of the rung in {max_tries} tries")
    return tasks  # type: ignore[return-value]


def random_scenario(rng: np.random.Generator, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                    max_tries: int = 100) -> OrthoglideScenario:
    """:func:`random_scenarios` for one generator."""
    return random_scenarios([rng], geometry, max_tries)[0]


def start_table_position(points: np.ndarray, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                         samples: int = 401) -> tuple[np.ndarray, np.ndarray]:
    """The optimal initial configuration for first path points (N, 2): the
    lowest kappa (N,) over ``samples`` admissible table positions and the
    rho1 (N,) that gives it (inf where none is admissible). The sweep of
    ``pointwise_optimum`` at the path point (:func:`og.kappa_at`)."""
    g = geometry
    r1 = np.linspace(g.rho_min[0], g.rho_max[0], samples)
    kap, best = np.empty(len(points)), np.empty(len(points), np.int64)
    chunk = max(1, 2 ** 16 // samples)  # robots per pass: arrays that stay in the cache
    for lo in range(0, len(points), chunk):
        pts = points[lo:lo + chunk]
        rr, px, py, admissible = _sweep(r1, pts, g)
        ok = np.flatnonzero(admissible)
        k = np.full(len(rr), np.inf)  # kappa where admissible (element-wise: the same as sweeping all)
        k[ok] = og.kappa_at(rr[ok], px[ok], py[ok], g)
        table = np.where(np.isfinite(k), k, np.inf).reshape(len(pts), samples)
        best[lo:lo + chunk] = table.argmin(axis=1)
        kap[lo:lo + chunk] = table[np.arange(len(pts)), best[lo:lo + chunk]]
    return kap, r1[best]


def validate_scenario(choice: OrthoglideScenario, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY) -> None:
    """A custom task that can run: finite, increasing times (at least two)
    with points and velocities (K, 2), whose first point the manipulator
    reaches."""
    try:
        t = np.asarray(choice.t, dtype=float)
        points = np.asarray(choice.points, dtype=float)
        velocities = np.asarray(choice.velocities, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"scenario's t, points and velocities must be arrays of real numbers ({exc})") from None
    if t.ndim != 1 or len(t) < 2 or points.shape != (len(t), 2) or velocities.shape != (len(t), 2):
        raise ValueError(f"scenario must have times (K,) with K >= 2 and points and velocities (K, 2); got "
                         f"{t.shape}, {points.shape}, {velocities.shape}")
    if not (np.isfinite(t).all() and np.isfinite(points).all() and np.isfinite(velocities).all()):
        raise ValueError("scenario's times, points and velocities must be finite")
    if not np.all(np.diff(t) > 0):
        raise ValueError("scenario's times must increase")
    kap, _ = start_table_position(points[:1], geometry)
    if not np.isfinite(kap[0]):
        raise ValueError("scenario's first point is outside the reachable set")


def resolve_scenario(choice: Any, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY) -> str | OrthoglideScenario:
    """The scenario argument, checked (:func:`paragym.tasks.base.resolve_scenario`):
    "paper", "random", or a :class:`OrthoglideScenario` that can run."""
    return base.resolve_scenario(choice, SCENARIOS, OrthoglideScenario, lambda task: validate_scenario(task, geometry))


def draw_scenarios(choice: Any, rngs: list[np.random.Generator],
                   geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY, rung: OrthoglideRung | None = None
                   ) -> list[OrthoglideScenario]:
    """One episode's path per generator (single env, vector env and CLI
    alike): the paper's circle, random paths drawn from the generators, or
    the custom path once :func:`resolve_scenario` accepts it. On a rung of the ladder (``rung``, one of
    :data:`LADDER`) "random" is the rung's path (:func:`ladder_scenarios`)."""
    choice = resolve_scenario(choice, geometry)
    if choice == "random" and rung is not None:
        return ladder_scenarios(rngs, rung, geometry)
    if choice == "random":
        return random_scenarios(rngs, geometry)
    return [paper_scenario() if choice == "paper" else choice] * len(rngs)

#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = base.renamed(__name__, {
    "resolve_task": "resolve_scenario",
    "draw_tasks": "draw_scenarios",
    "Task": "OrthoglideScenario",
    "paper_task": "paper_scenario",
    "orthoglide_random_task": "random_scenario",
    "orthoglide_random_tasks": "random_scenarios",
})
