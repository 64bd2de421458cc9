"""``paragym/Orthoglide2PRRKappa-v0``: track a path with the 2PRR + table, keeping kappa(J) low (paper 003)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import orthoglide as og

__all__ = ["Orthoglide2PRRKappaEnv", "Orthoglide2PRRKappaVectorEnv", "orthoglide_random_task",
           "orthoglide_random_tasks", "servable", "start_table_position"]

OBS_SIZE = 3 + 2 + 2 + 1 + 3
KAPPA_LIMIT = 100.0  # kappa above this counts as a singularity


def _task_module() -> Any:
    from paragym.planners import nullspace_gradient

    return nullspace_gradient


def _sweep(table: np.ndarray, points: np.ndarray, g: og.OrthoglideGeometry
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every (point, table position) pair of points (K, 2) and positions (T,),
    point-major: rho1, px, py (K * T,) and whether the pair is admissible
    (reachable in the working mode, rho2 and rho3 inside their limits)."""
    rr = np.tile(table, len(points))
    px, py = np.repeat(points[:, 0], len(table)), np.repeat(points[:, 1], len(table))
    r2, r3, mode = og.inverse_rows(rr, px, py, g)
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
        return _sweep(table, pts, g)[3].reshape(len(pts), len(table)).any(axis=1)

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


def orthoglide_random_tasks(rngs: list[np.random.Generator],
                            geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY, max_tries: int = 100) -> list[Any]:
    """One seeded circle, ellipse or line (10 s) per generator, each drawn
    until some admissible table position serves every tenth point (a sweep of
    101 table positions, :func:`servable`). Each generator draws exactly what
    it would alone (a candidate, then the test); the candidates of all
    pending generators are tested in one batch."""
    ng = _task_module()
    tasks: list[Any] = [None] * len(rngs)
    pending = np.arange(len(rngs))
    for _ in range(max_tries):
        if not pending.size:
            return tasks
        drawn = [_draw_path(rngs[i]) for i in pending]
        every_tenth = np.concatenate([_path(kind, q, 10)[0] for kind, q in drawn])
        ok = servable(every_tenth, geometry).reshape(len(drawn), -1).all(axis=1)
        for j in np.flatnonzero(ok):
            kind, q = drawn[j]
            tasks[pending[j]] = ng.Task(_KINDS[kind], _TIMES, *_path(kind, q))
        pending = pending[~ok]
    raise RuntimeError(f"no reachable random path in {max_tries} tries")


def orthoglide_random_task(rng: np.random.Generator, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                           max_tries: int = 100) -> Any:
    """:func:`orthoglide_random_tasks` for one generator."""
    return orthoglide_random_tasks([rng], geometry, max_tries)[0]


def start_table_position(points: np.ndarray, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                         samples: int = 401) -> tuple[np.ndarray, np.ndarray]:
    """The optimal initial configuration for first path points (N, 2): the
    lowest kappa (N,) over ``samples`` admissible table positions and the
    rho1 (N,) that gives it (inf where none is admissible). The sweep of
    ``pointwise_optimum`` in the per-step formulas (:func:`og.jacobian_rows`)."""
    g = geometry
    r1 = np.linspace(g.rho_min[0], g.rho_max[0], samples)
    kap, best = np.empty(len(points)), np.empty(len(points), np.int64)
    chunk = max(1, 2 ** 16 // samples)  # robots per pass: arrays that stay in the cache
    for lo in range(0, len(points), chunk):
        pts = points[lo:lo + chunk]
        rr, px, py, admissible = _sweep(r1, pts, g)
        ok = np.flatnonzero(admissible)
        k = np.full(len(rr), np.inf)  # kappa where admissible (element-wise: the same as sweeping all)
        k[ok] = og.kappa_rows(rr[ok], px[ok], py[ok], g)
        k = np.where(np.isfinite(k), k, np.inf).reshape(len(pts), samples)
        best[lo:lo + chunk] = k.argmin(axis=1)
        kap[lo:lo + chunk] = k[np.arange(len(pts)), best[lo:lo + chunk]]
    return kap, r1[best]


def resolve_task(choice: Any, geometry: og.OrthoglideGeometry) -> Any:
    """The scenario argument checked at the boundary (single and vector env
    alike): "paper", "random", or a Task of finite, increasing times (at
    least two) with points and velocities (K, 2) whose first point the
    manipulator reaches. Anything else is a ValueError or TypeError naming
    ``scenario``."""
    ng = _task_module()
    if isinstance(choice, str):
        if choice not in ("paper", "random"):
            raise ValueError(f"scenario must be 'paper', 'random' or a Task; got {choice!r}")
        return choice
    if not isinstance(choice, ng.Task):
        raise TypeError(f"scenario must be 'paper', 'random' or a Task; got {choice!r}")
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
    return choice


class Orthoglide2PRRKappaEnv(ParagymEnv):
    """Track a path with the 2-dof Orthoglide assisted by a translating table,
    keeping the condition number of J low.

    ## Description
    Paper 003 (Moreno, Pamanes, Wenger, Chablat): the 2PRR and its table form
    a redundant 3-dof manipulator for a 2-D task in the table frame. With the
    default action the tool follows the path exactly (least-norm motion
    ``J^+ t_dot``) and the agent chooses the motion in the null space of J,
    where kappa(J) (eq 8) can be lowered without leaving the path (eqs 5, 9-10).
    Kinematics: :mod:`paragym.mechanisms.orthoglide`.

    ## Action Space
    ``action_mode="null_space"`` (default): ``Box(-1, 1, (1,))``, the null-space
    rate times ``max_null_rate`` (m/s along the unit null vector n).
    ``action_mode="joint_velocity"``: ``Box(-1, 1, (3,))``, joint rates times
    ``max_joint_rate`` (m/s); the tool then tracks only as well as the agent does.
    An action outside the Box is clipped to it (the rule of every paragym env,
    :func:`paragym.envs.base.check_action`); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``.

    ## Observation Space
    ``Box(-10, 10, (11,))``: rho normalised to [-1, 1] over its limits; the
    path point now and next (table frame, m); log kappa (clipped at 10); n.

    ## Rewards
    ``-log(kappa)`` per step (0 at an isotropic pose); in joint-velocity mode
    also ``- w_track * tracking error / 0.01 m``. Reaching a joint limit or a
    singularity (kappa > 100, or leaving the working mode) costs
    ``limit_penalty`` and ends the episode.

    ## Starting State
    The optimal initial configuration: the admissible table position with
    the lowest kappa at the first path point. ``info["scenario"]`` is the task.

    ## Episode End
    Terminated at the path's end (``is_success``: no limit or singularity on
    the way) or at a limit/singularity.

    ## Arguments
    ``scenario``: "paper" (the 0.8 m circle in 10 s) or "random" (default:
    seeded circles, ellipses, lines); ``action_mode``; ``max_null_rate`` (0.5
    m/s); ``max_joint_rate`` (0.5 m/s); ``w_track``; ``limit_penalty`` (10);
    ``geometry``; ``render_mode``.

    ## Version History
    * v0: initial release (kinematic fidelity).
      Since paragym 0.2.0 a custom scenario that cannot run (NaN, outside
      the workspace, malformed) and non-dict ``options`` are refused at reset
      with a ValueError or TypeError naming them; every episode that ran
      before runs the same (tested against recorded rollouts).
    """

    def __init__(self, scenario: str | Any = "random", action_mode: str = "null_space",
                 render_mode: str | None = None, max_null_rate: float = 0.5, max_joint_rate: float = 0.5,
                 w_track: float = 1.0, limit_penalty: float = 10.0,
                 geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY) -> None:
        super().__init__(render_mode)
        if action_mode not in ("null_space", "joint_velocity"):
            raise ValueError(f"action_mode must be 'null_space' or 'joint_velocity'; got {action_mode!r}")
        self.scenario_arg = resolve_task(scenario, geometry)
        self.action_mode, self.geometry = action_mode, geometry
        self.max_null_rate, self.max_joint_rate = float(max_null_rate), float(max_joint_rate)
        self.w_track, self.limit_penalty = float(w_track), float(limit_penalty)
        dim = 1 if action_mode == "null_space" else 3
        self.action_space = spaces.Box(-1.0, 1.0, (dim,), np.float32)
        self.observation_space = spaces.Box(-10.0, 10.0, (OBS_SIZE,), np.float32)
        self._lo, self._hi = np.array(geometry.rho_min), np.array(geometry.rho_max)

    def _reset_task(self, options: dict[str, Any]) -> dict[str, Any]:
        ng = _task_module()
        choice = resolve_task(options.get("scenario", self.scenario_arg), self.geometry)
        if isinstance(choice, str):
            task = ng.paper_task() if choice == "paper" else orthoglide_random_task(self.np_random, self.geometry)
        else:
            task = choice
        kap, r1 = start_table_position(task.points[:1], self.geometry)
        self.task = task
        self._points, self._vel = task.points.tolist(), task.velocities.tolist()
        self._dt, self._last = np.diff(task.t).tolist(), len(task.t) - 1
        self._k = 0
        r2, r3, _ = og.inverse_one(float(r1[0]), *task.points[0], self.geometry)
        self._rho = [float(r1[0]), r2, r3]
        self._failed = False
        self._evaluate()
        info = self._info()
        info["scenario"] = task
        return info

    def _evaluate(self) -> None:
        px, py = self._points[self._k]
        r1, r2, r3 = self._rho
        self._err = 0.0
        if self.action_mode == "joint_velocity":
            tool = og.forward(np.array([self._rho]), self.geometry)[0]
            self._err = math.hypot(tool[0] - px, tool[1] - py)
        _, _, mode = og.inverse_one(r1, px, py, self.geometry)
        lo, hi = self.geometry.rho_min, self.geometry.rho_max
        inside = lo[0] <= r1 <= hi[0] and lo[1] <= r2 <= hi[1] and lo[2] <= r3 <= hi[2]
        if not (mode and inside):
            self._kappa, self._n, self._j = math.inf, [0.0, 0.0, 0.0], None
            self._failed = True
            return
        j0, j1, self._kappa, self._n = og.jacobian_one(r1, px, py, self.geometry)
        self._j = (j0, j1)
        if not self._kappa < KAPPA_LIMIT:
            self._failed = True

    def _apply_action(self, action: np.ndarray) -> None:
        if self._k >= self._last:
            raise RuntimeError("the episode has ended: call reset()")
        dt = self._dt[self._k]
        if self.action_mode == "null_space":
            a = min(1.0, max(-1.0, float(action[0])))
            tx, ty = self._vel[self._k]
            rate = og.least_norm_one(self._j[0], self._j[1], tx, ty)
            r1 = self._rho[0] + dt * (rate[0] + a * self.max_null_rate * self._n[0])
            self._k += 1
            r2, r3, _ = og.inverse_one(r1, *self._points[self._k], self.geometry)  # exact tracking
            self._rho = [r1, r2, r3]
        else:
            a = np.clip(action, -1.0, 1.0)
            self._rho = [r + dt * self.max_joint_rate * float(x) for r, x in zip(self._rho, a, strict=True)]
            self._k += 1
        self._evaluate()

    def _observe(self) -> np.ndarray:
        k = self._k
        nxt = min(k + 1, self._last)
        lo, hi = self.geometry.rho_min, self.geometry.rho_max
        kap = math.log(self._kappa) if self._kappa < 2.2e4 else 10.0
        obs = [2 * (self._rho[i] - lo[i]) / (hi[i] - lo[i]) - 1 for i in range(3)]
        obs += [*self._points[k], *self._points[nxt], kap, *self._n]
        # plain floats: clip (and a NaN after leaving the working mode) without numpy's per-call overhead
        return np.array([10.0 if v != v else min(10.0, max(-10.0, v)) for v in obs], np.float32)

    def _reward(self) -> float:
        if self._failed:
            return -self.limit_penalty
        return float(-math.log(self._kappa) - self.w_track * self._err / 0.01)

    def _terminated(self) -> bool:
        return self._failed or self._k >= self._last

    def _info(self) -> dict[str, Any]:
        return {"kappa": self._kappa, "tracking_error": self._err, "rho": np.array(self._rho),
                "step": self._k, "is_success": (not self._failed) and self._k >= self._last}

    def _render_rgb(self) -> np.ndarray:
        from paragym.sim.orthoglide_model import OrthoglideScene

        return self._drawn(lambda gui: OrthoglideScene(self.geometry, gui=gui),
                           lambda scene: scene.set_state(np.array(self._rho), self.task.points))

    def _show(self) -> None:
        self._render_rgb()  # the scene is posed when drawn

    def _close(self) -> None:
        self._close_render_scene()


class Orthoglide2PRRKappaVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaEnv` stepped together
    in numpy (:mod:`paragym.envs.vector`; the same numbers as the single env).
    Keyword arguments are the single env's; all tasks have the same number of
    path points (the paper's and the random ones: 1001)."""

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 **kwargs: Any) -> None:
        super().__init__(num_envs, Orthoglide2PRRKappaEnv(**kwargs), max_episode_steps, render_index)
        e = self.single_env
        self.geometry, self.joint_mode = e.geometry, e.action_mode == "joint_velocity"
        self._lo, self._hi = np.array(e.geometry.rho_min), np.array(e.geometry.rho_max)
        self._tasks: list[Any] = [None] * self.num_envs
        self._idx = np.arange(self.num_envs)

    def _reset_rows(self, rows: np.ndarray, options: dict[str, Any]) -> None:
        ng = _task_module()
        e = self.single_env
        choice = resolve_task(options.get("scenario", e.scenario_arg), self.geometry)
        if choice == "random":
            tasks = orthoglide_random_tasks([self._rngs[i] for i in rows], self.geometry)
        else:
            tasks = [ng.paper_task() if choice == "paper" else choice] * len(rows)
        first = np.array([t.points[0] for t in tasks])
        kap, r1 = start_table_position(first, self.geometry)
        if not np.all(np.isfinite(kap)):
            raise ValueError("the task's first point is outside the reachable set")
        n = self.num_envs
        if self._tasks[0] is None:  # the first reset allocates the path arrays
            k = len(tasks[0].t)
            self._path = np.zeros((n, k, 4))  # per robot and path point: x, y, vx, vy (table frame)
            self._flat = self._path.reshape(n * k, 4)  # a view, for gathers by flat index
            self._dt = np.zeros((n, k - 1))
            self._last = np.zeros(n, np.int64)
            self._rho, self._k = np.zeros((n, 3)), np.zeros(n, np.int64)
            self._j, self._n = np.zeros((2, 3, n)), np.zeros((3, n))
            self._kappa, self._err, self._failed = np.zeros(n), np.zeros(n), np.zeros(n, bool)
        k = self._path.shape[1]
        for i, task in zip(rows, tasks, strict=True):
            if len(task.t) != k:
                raise ValueError(f"every task must have {k} path points; got {len(task.t)}")
            self._tasks[i] = task
        # one stacked copy per array rather than three per robot
        self._path[rows, :, :2] = np.stack([task.points for task in tasks])
        self._path[rows, :, 2:] = np.stack([task.velocities for task in tasks])
        self._dt[rows] = np.diff(np.stack([task.t for task in tasks]), axis=1)
        self._last[rows] = k - 1
        self._k[rows] = 0
        r2, r3, mode = og.inverse_rows(r1, first[:, 0], first[:, 1], self.geometry)
        self._rho[rows] = np.stack([r1, r2, r3], -1)
        self._evaluate(rows, first[:, 0], first[:, 1], mode)

    def _at(self, k: np.ndarray) -> np.ndarray:
        """Every robot's path point k (N,) and its velocity: (N, 4)."""
        return self._flat.take(self._idx * self._path.shape[1] + k, axis=0)

    def _evaluate(self, rows: np.ndarray | slice, px: np.ndarray, py: np.ndarray, mode: np.ndarray) -> None:
        """kappa, J, n and failure of ``rows`` at path points (px, py), given
        whether the working mode reaches them (``mode``)."""
        g = self.geometry
        rho = self._rho[rows]
        r1, r2, r3 = rho[:, 0], rho[:, 1], rho[:, 2]
        if self.joint_mode:
            tool = og.forward(rho, g)
            self._err[rows] = np.hypot(tool[:, 0] - px, tool[:, 1] - py)
        lo, hi = g.rho_min, g.rho_max
        ok = mode & (r1 >= lo[0]) & (r1 <= hi[0]) & (r2 >= lo[1]) & (r2 <= hi[1]) & (r3 >= lo[2]) & (r3 <= hi[2])
        j, kap, n = og.jacobian_rows(r1, px, py, g)
        kap = np.where(ok, kap, np.inf)
        self._j[:, :, rows], self._kappa[rows], self._n[:, rows] = j, kap, np.where(ok, n, 0.0)
        with np.errstate(invalid="ignore"):
            self._failed[rows] = ~ok | ~(kap < KAPPA_LIMIT)

    def _apply(self, actions: np.ndarray, active: np.ndarray) -> None:
        e, k = self.single_env, self._k
        step = np.minimum(k, self._dt.shape[1] - 1)  # rows being reset may sit at the path's end
        dt = self._dt.take(self._idx * self._dt.shape[1] + step)
        k1 = np.where(active, np.minimum(k + 1, self._last), k)
        p = self._at(k1)
        if self.joint_mode:
            a = np.clip(actions, -1.0, 1.0)
            rho = self._rho + dt[:, None] * e.max_joint_rate * a
            mode = None
        else:
            a = np.clip(actions[:, 0], -1.0, 1.0)
            v = self._at(step)
            with np.errstate(invalid="ignore", divide="ignore"):
                rate = og.least_norm_rows(self._j, v[:, 2], v[:, 3])
            r1 = self._rho[:, 0] + dt * (rate[0] + a * e.max_null_rate * self._n[0])
            r2, r3, mode = og.inverse_rows(r1, p[:, 0], p[:, 1], self.geometry)  # exact tracking
            rho = np.stack([r1, r2, r3], -1)
        all_step = active.all()
        self._rho = rho if all_step else np.where(active[:, None], rho, self._rho)
        self._k = k1
        if mode is None or not all_step:  # the working mode where the robots now are
            mode = og.inverse_rows(self._rho[:, 0], p[:, 0], p[:, 1], self.geometry)[2]
        self._evaluate(slice(None), p[:, 0], p[:, 1], mode)

    def _observe(self) -> np.ndarray:
        k = self._k
        nxt = np.minimum(k + 1, self._last)
        with np.errstate(divide="ignore", invalid="ignore"):
            kap = np.where(self._kappa < 2.2e4, np.log(self._kappa), 10.0)
        obs = np.concatenate([2 * (self._rho - self._lo) / (self._hi - self._lo) - 1, self._at(k)[:, :2],
                              self._at(nxt)[:, :2], kap[:, None], self._n.T], axis=1)
        return np.clip(np.nan_to_num(obs, nan=10.0), -10.0, 10.0).astype(np.float32)

    def _reward(self) -> np.ndarray:
        e = self.single_env
        with np.errstate(divide="ignore", invalid="ignore"):
            r = -np.log(self._kappa) - e.w_track * self._err / 0.01
        return np.where(self._failed, -e.limit_penalty, r)

    def _terminated(self) -> np.ndarray:
        return self._failed | (self._k >= self._last)

    def _infos(self) -> dict[str, Any]:
        return self._for_every_robot(kappa=self._kappa.copy(), is_success=~self._failed & (self._k >= self._last))

    def _load_single(self, i: int) -> None:
        e = self.single_env
        e.task, e._rho, e._k = self._tasks[i], self._rho[i].tolist(), int(self._k[i])
