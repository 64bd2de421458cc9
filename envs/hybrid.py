"""``paragym/HybridSingularityFree-v0``: the hexapod + tripod along a polynomial path (paper 002)."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import hybrid
from paragym.tasks.hybrid import (
    HybridScenario,
    hybrid_paper_scenario,
    hybrid_random_scenario,
    hybrid_random_scenarios,
    nominal_rows,
    resolve_hybrid,
)
from paragym.trajectories import nominal_path

__all__ = ["HybridScenario", "HybridSingularityFreeEnv", "HybridSingularityFreeVectorEnv", "hybrid_paper_scenario",
           "hybrid_random_scenario", "hybrid_random_scenarios"]

POSE_SCALE = np.array([0.1, 0.1, 0.1, 0.5, 0.5, 0.5])  # m, m, m, rad, rad, rad: observation units
OBS_SIZE = 1 + 6 + 6 + 1 + 9 + 2 + 3


class HybridSingularityFreeEnv(ParagymEnv):
    """Move a hexapod + tripod's end-effector along a polynomial path without
    singular poses or leg-limit violations.

    ## Description
    Paper 002 (Rakhodaei, Ding, Saadat, Rastegarpanah): a 6-UPU hexapod
    carries a 3-RPS tripod (nine prismatic actuators). The end-effector E
    follows the rest-to-rest 7th-degree path from P0 to P1 (eq 17); the
    episode walks u from 0 to 1 in steps of tau = 0.01. At each step the agent
    chooses how the motion is split between the stages (Delta, eqs 19-20) and
    may offset E's position from the nominal path by at most J-bar (the
    paper's detour); the kinematics is :mod:`paragym.mechanisms.hybrid`.

    ## Action Space
    ``Box(-1, 1, (4,), float32)``: the change of Delta (times
    ``max_delta_step`` = 0.05, Delta held in [0, 1]) and the offset of E's
    x, y, z from the nominal path (times ``j_bar`` = 20 mm). The last pose is
    P1 exactly: its offset is ignored.
    An action outside the Box is clipped to it (the rule of every paragym env,
    :func:`paragym.envs.base.check_action`); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``.

    ## Observation Space
    ``Box(-10, 10, (28,), float32)``: u; the nominal pose at this step and at
    the next (x, y, z / 0.1 m, angles / 0.5 rad); Delta; the nine strokes
    mapped so that L_min -> -1 and L_max -> +1; the two singularity measures
    (1 at home, singular below 0.2); the current offset / j_bar.

    ## Rewards
    Per step: ``-w_offset |offset| / j_bar`` (deviation from the nominal
    path) ``- w_delta |change of Delta| / max_delta_step`` (smoothness)
    ``- w_singular * sum of (0.4 - mu)_+ / 0.4`` over both measures
    (closeness to singularity) ``- w_limit * (legs out of limits)``.

    ## Starting State
    u = 0, Delta = 0.5, E at P0 (``info["scenario"]``: a frozen HybridScenario).

    ## Episode End
    Terminated after the step that reaches u = 1 (100 steps);
    ``info["is_success"]`` when every pose of the episode was
    singularity-free and within the limits (eq 14).

    ## Arguments
    ``scenario``: "random" (default), "paper" or a HybridScenario;
    ``max_delta_step``, ``j_bar`` (m), ``w_offset``, ``w_delta``,
    ``w_singular``, ``w_limit``, ``geometry``, ``render_mode``.

    ## Version History
    * v0: initial release (kinematic fidelity).
      Since paragym 0.2.0 a custom scenario that cannot run (NaN, outside
      the workspace, malformed) and non-dict ``options`` are refused at reset
      with a ValueError or TypeError naming them; every episode that ran
      before runs the same (tested against recorded rollouts).
    """

    def __init__(self, scenario: str | HybridScenario = "random", render_mode: str | None = None,
                 max_delta_step: float = 0.05, j_bar: float = 0.02, w_offset: float = 0.1, w_delta: float = 0.05,
                 w_singular: float = 1.0, w_limit: float = 1.0,
                 geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY, tau: float = 0.01) -> None:
        super().__init__(render_mode)
        resolve_hybrid(scenario)
        for name, value in (("max_delta_step", max_delta_step), ("j_bar", j_bar), ("tau", tau)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number; got {value!r}")
        self.scenario_arg, self.geometry = scenario, geometry
        self.max_delta_step, self.j_bar, self.tau = float(max_delta_step), float(j_bar), float(tau)
        self.w_offset, self.w_delta, self.w_singular, self.w_limit = w_offset, w_delta, w_singular, w_limit
        self.action_space = spaces.Box(-1.0, 1.0, (4,), np.float32)
        self.observation_space = spaces.Box(-10.0, 10.0, (OBS_SIZE,), np.float32)

    def _reset_task(self, options: dict[str, Any]) -> dict[str, Any]:
        choice = resolve_hybrid(options.get("scenario", self.scenario_arg))
        if choice == "random":
            scenario = hybrid_random_scenario(self.np_random, self.geometry)
        elif choice == "paper":
            scenario = hybrid_paper_scenario(self.geometry)
        else:
            scenario = choice
        self.scenario = scenario
        self._u, self._nominal = nominal_path(np.array(scenario.p0), np.array(scenario.p1), self.tau)
        self._k = 0
        self._delta = 0.5
        self._d_delta = 0.0
        self._offset = np.zeros(3)
        self._all_free = True
        self._evaluate()
        info = self._info()
        info["scenario"] = scenario
        return info

    def _evaluate(self) -> None:
        pose = self._nominal[self._k].copy()
        pose[:3] += self._offset
        self._pose = pose
        lengths, self._mu_h, self._mu_t, self._within, self._free = hybrid.solve_one(pose, self._delta, self.geometry)
        self._lengths, self._lengths_list = np.array(lengths), lengths
        self._all_free &= self._free

    def _apply_action(self, action: np.ndarray) -> None:
        if self._k >= len(self._u) - 1:
            raise RuntimeError("the episode has ended: call reset()")
        a = np.clip(action, -1.0, 1.0)
        new_delta = float(np.clip(self._delta + a[0] * self.max_delta_step, 0.0, 1.0))
        self._d_delta = new_delta - self._delta
        self._delta = new_delta
        self._k += 1
        self._offset = np.zeros(3) if self._k == len(self._u) - 1 else a[1:] * self.j_bar
        self._evaluate()

    def _observe(self) -> np.ndarray:
        g = self.geometry
        nxt = min(self._k + 1, len(self._u) - 1)
        strokes = 2 * (self._lengths - g.l_min) / (g.l_max - g.l_min) - 1
        obs = np.concatenate([[self._u[self._k]], self._nominal[self._k] / POSE_SCALE,
                              self._nominal[nxt] / POSE_SCALE, [self._delta], strokes,
                              [self._mu_h, self._mu_t], self._offset / self.j_bar])
        return np.clip(obs, -10.0, 10.0).astype(np.float32)

    def _reward(self) -> float:
        g = self.geometry
        close = sum(max(0.0, 2 * g.singularity_threshold - m) / (2 * g.singularity_threshold)
                    for m in (self._mu_h, self._mu_t))
        out = sum(1 for v in self._lengths_list if v < g.l_min or v > g.l_max)
        return float(-self.w_offset * np.linalg.norm(self._offset) / self.j_bar
                     - self.w_delta * abs(self._d_delta) / self.max_delta_step
                     - self.w_singular * close - self.w_limit * out)

    def _terminated(self) -> bool:
        return self._k >= len(self._u) - 1

    def _info(self) -> dict[str, Any]:
        return {"step": self._k, "u": float(self._u[self._k]), "delta": self._delta,
                "offset": self._offset.copy(), "lengths": self._lengths.copy(),
                "mu_hexapod": self._mu_h, "mu_tripod": self._mu_t,
                "free": self._free, "within_limits": self._within,
                "is_success": self._terminated() and self._all_free,
                "max_delta_step": self.max_delta_step, "j_bar": self.j_bar}

    def _render_rgb(self) -> np.ndarray:
        from paragym.sim.hybrid_model import HybridScene

        state = hybrid.solve(self._pose[None], self._delta, self.geometry, validate=False)
        return self._drawn(lambda gui: HybridScene(self.geometry, gui=gui),
                           lambda scene: scene.set_state(state.t_a[0], state.t_e[0]))

    def _show(self) -> None:
        self._render_rgb()  # the scene is posed when drawn

    def _close(self) -> None:
        self._close_render_scene()


class HybridSingularityFreeVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeEnv` stepped together:
    one batched :func:`paragym.mechanisms.hybrid.solve_rows` (nine legs, two
    singularity measures) per step for all robots (:mod:`paragym.envs.vector`;
    the same numbers as the single env). Keyword arguments are the single env's."""

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 **kwargs: Any) -> None:
        super().__init__(num_envs, HybridSingularityFreeEnv(**kwargs), max_episode_steps, render_index)
        e = self.single_env
        self.geometry = e.geometry
        self._u = nominal_path(np.zeros(6), np.zeros(6), e.tau)[0]
        self._last = len(self._u) - 1
        n = self.num_envs
        self._idx = np.arange(n)
        self._nominal = np.zeros((n, len(self._u), 6))
        self._k = np.zeros(n, np.int64)
        self._delta, self._d_delta = np.full(n, 0.5), np.zeros(n)
        self._offset = np.zeros((n, 3))
        self._all_free = np.ones(n, bool)
        self._pose, self._lengths = np.zeros((n, 6)), np.zeros((n, 9))
        self._mu_h, self._mu_t, self._free = np.zeros(n), np.zeros(n), np.zeros(n, bool)
        self._scenarios: list[HybridScenario | None] = [None] * n

    def _reset_rows(self, rows: np.ndarray, options: dict[str, Any]) -> None:
        e = self.single_env
        choice = resolve_hybrid(options.get("scenario", e.scenario_arg))  # before any robot changes
        if choice == "random":
            scenarios = hybrid_random_scenarios([self._rngs[i] for i in rows], self.geometry)
        else:
            scenarios = [hybrid_paper_scenario(self.geometry) if choice == "paper" else choice] * len(rows)
        for i, scenario in zip(rows, scenarios, strict=True):
            self._scenarios[i] = scenario
        p0 = np.array([sc.p0 for sc in scenarios])
        p1 = np.array([sc.p1 for sc in scenarios])
        self._nominal[rows] = nominal_rows(p0, p1, e.tau)
        self._k[rows] = 0
        self._delta[rows], self._d_delta[rows] = 0.5, 0.0
        self._offset[rows] = 0.0
        self._all_free[rows] = True
        self._evaluate(rows)

    def _evaluate(self, rows: np.ndarray) -> None:
        """The legs and the measures of ``rows`` (all robots after a step)."""
        pose = self._nominal[rows, self._k[rows]]
        pose[:, :3] += self._offset[rows]
        lengths, mu_h, mu_t, _, free = hybrid.solve_rows(pose, self._delta[rows], self.geometry)
        self._pose[rows], self._lengths[rows] = pose, lengths
        self._mu_h[rows], self._mu_t[rows], self._free[rows] = mu_h, mu_t, free
        self._all_free &= self._free

    def _apply(self, actions: np.ndarray, active: np.ndarray) -> None:
        e = self.single_env
        a = np.clip(actions, -1.0, 1.0)
        new_delta = np.clip(self._delta + a[:, 0] * e.max_delta_step, 0.0, 1.0)
        self._d_delta = np.where(active, new_delta - self._delta, self._d_delta)
        self._delta = np.where(active, new_delta, self._delta)
        k = np.where(active, np.minimum(self._k + 1, self._last), self._k)
        offset = np.where((k == self._last)[:, None], 0.0, a[:, 1:] * e.j_bar)
        self._offset = np.where(active[:, None], offset, self._offset)
        self._k = k
        self._evaluate(self._idx)

    def _observe(self) -> np.ndarray:
        g, e = self.geometry, self.single_env
        nxt = np.minimum(self._k + 1, self._last)
        strokes = 2 * (self._lengths - g.l_min) / (g.l_max - g.l_min) - 1
        obs = np.concatenate([self._u[self._k][:, None], self._nominal[self._idx, self._k] / POSE_SCALE,
                              self._nominal[self._idx, nxt] / POSE_SCALE, self._delta[:, None], strokes,
                              self._mu_h[:, None], self._mu_t[:, None], self._offset / e.j_bar], axis=1)
        return np.clip(obs, -10.0, 10.0).astype(np.float32)

    def _reward(self) -> np.ndarray:
        g, e = self.geometry, self.single_env
        thr = 2 * g.singularity_threshold
        close = np.maximum(0.0, thr - self._mu_h) / thr + np.maximum(0.0, thr - self._mu_t) / thr
        out = np.sum((self._lengths < g.l_min) | (self._lengths > g.l_max), axis=1)
        return (-e.w_offset * np.sqrt((self._offset ** 2).sum(axis=1)) / e.j_bar
                - e.w_delta * np.abs(self._d_delta) / e.max_delta_step - e.w_singular * close - e.w_limit * out)

    def _terminated(self) -> np.ndarray:
        return self._k >= self._last

    def _infos(self) -> dict[str, Any]:
        return self._for_every_robot(is_success=self._terminated() & self._all_free, free=self._free.copy())

    def _load_single(self, i: int) -> None:
        e = self.single_env
        e._pose, e._delta = self._pose[i].copy(), float(self._delta[i])
