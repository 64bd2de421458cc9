"""``paragym/Orthoglide2PRRKappa-v0``: track a path with the 2PRR + table, keeping kappa(J) low (paper 003)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import orthoglide as og
from paragym.tasks.orthoglide import (
    draw_tasks,
    orthoglide_random_task,
    orthoglide_random_tasks,
    resolve_task,
    servable,
    start_table_position,
)

__all__ = ["Orthoglide2PRRKappaEnv", "Orthoglide2PRRKappaVectorEnv", "orthoglide_random_task",
           "orthoglide_random_tasks", "servable", "start_table_position"]

OBS_SIZE = 3 + 2 + 2 + 1 + 3
KAPPA_LIMIT = 100.0  # kappa above this counts as a singularity


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
        task = draw_tasks(options.get("scenario", self.scenario_arg), [self.np_random], self.geometry)[0]
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
        e = self.single_env
        tasks = draw_tasks(options.get("scenario", e.scenario_arg), [self._rngs[i] for i in rows], self.geometry)
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
