"""``paragym/CaPaManCollisionFree-v0``: the CaPaMan tour around obstacles (paper 000)."""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import capaman
from paragym.sim import occupancy
from paragym.sim.capaman_dynamic import CaPaManDynamicScene
from paragym.sim.capaman_model import CaPaManScene
from paragym.sim.obstacles import ENCODING_SIZE
from paragym.tasks.capaman import (
    MAX_OBSTACLES,
    TOUR,
    CaPaManScenario,
    draw_scenario,
    resolve_capaman,
)
from paragym.units import DEG

__all__ = ["CaPaManCollisionFreeEnv", "CaPaManCollisionFreeVectorEnv"]

#: the largest crank motion (rad, each crank) between two collision checks: in a step of 2 deg no point of
#: the 17 parts moves more than 4.7 mm (measured over the joint space, tested), under the 5 mm cell of the
#: occupancy grid, so checking the end of each such step checks the motion at the grid's resolution
SWEEP_STEP = 2 * DEG
OBS_SIZE = 3 + 3 + 3 + 3 + MAX_OBSTACLES * ENCODING_SIZE + 1 + 1


@lru_cache(maxsize=4)
def _clusters(geometry: capaman.CaPaManGeometry) -> occupancy.ClusterPoints:
    return occupancy.cluster_points(geometry, spacing=0.01)


class CaPaManCollisionFreeEnv(ParagymEnv):
    """Move the CaPaMan's tool through T.C.1 -> T.C.2 -> T.C.3 -> T.C.1 with no
    part of the manipulator touching an obstacle.

    ## Description
    Paper 000 (Carbone, Gomez-Bravo, Selvi), sections 2 and 4: the 3-DOF
    Cassino Parallel Manipulator carries a tool rod under its movable plate and
    must visit task configurations placed around obstacles. Collision is
    checked for the whole manipulator (17 parts: cranks, couplers, bars,
    rails, plate, tool) by PyBullet; the kinematics is the closed-form model
    of :mod:`paragym.mechanisms.capaman`.

    ## Action Space
    ``Box(-1, 1, (3,), float32)``: crank-angle increments, scaled by
    ``max_joint_step`` (default 2 deg) per step. An action outside the Box is
    clipped to it (every paragym env does so); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``. The result is
    held inside the mechanical range 45-135 deg (a joint stop).
    Collision is checked along the motion, not only at its end: in kinematic
    fidelity a step is checked every :data:`SWEEP_STEP` (2 deg per crank, at
    most 4.7 mm of motion of any point of the manipulator, under the 5 mm
    occupancy grid), so a step of the default size is checked at its end and
    a larger ``max_joint_step`` is cut into sub-steps; the mechanism stops
    where a sub-step first collides. In dynamic fidelity the obstacles are
    rigid bodies and PyBullet's contact solver stops the parts at every
    physics step.

    ## Observation Space
    ``Box(-1, 1, (38,), float32)``:

    ==========  ==========================================================
    0-2         crank angles, normalised to [-1, 1] over 45-135 deg
    3-5         tool-tip position (m, fixed-plate frame)
    6-8         current target T.P., normalised like 0-2
    9-11        current target T.C., tool-tip position (m)
    12-35       three obstacles x [present, is_box, centre (3), half sizes (3)] (m; zeros when absent)
    36          clearance of the whole manipulator (m, signed, capped at +-``clearance_cap``)
    37          progress: T.C.s reached / 3
    ==========  ==========================================================

    ## Rewards
    After the fitness of paper 000 (eqs 3-5), per step:
    ``-w_length * |d alpha|`` (joint-space path length, rad)
    ``- beta * [clearance < delta]`` (too close to an obstacle; the paper's
    k_i beta, here with the Cartesian clearance)
    ``+ w_progress * (d_before - d_after)`` (potential-based shaping on the
    joint distance to the current target: it telescopes, so it does not
    change which tour is optimal)
    ``+ reach_bonus`` per T.C. reached ``- collision_penalty`` on collision
    (the paper's Lambda = infinity, made finite and terminal).

    ## Starting State
    The manipulator at T.P.1. ``info["scenario"]`` (a frozen
    :class:`CaPaManScenario`) holds obstacles, T.C.s and T.P.s.

    ## Episode End
    Terminated on collision (clearance <= 0) or when the tour is complete
    (``is_success``). Truncated after 400 steps (registration).

    ## Arguments
    ``scenario``: "random" (default; seeded, generated feasible), "paper",
    or a :class:`CaPaManScenario`; ``reset(options={"scenario": ...})``
    overrides it for one episode. ``fidelity``: "kinematic" (default: the
    joints go where the action says, the analytic model places the parts)
    or "dynamic" (the closed chain under physics: the action moves the
    motors' commands, which the motors chase for ``control_period`` s of
    simulated time; observations report the encoders and the plate's
    simulated pose). ``collision``: "pybullet" (default: PyBullet's exact
    signed distance between the 17 parts and the obstacles) or "grid"
    (kinematic fidelity only: paper 000's own test, the occupancy grid Psi
    and the cluster points of eq 2, 10 mm apart; the clearance is the
    smallest signed distance on Psi at any cluster point, in 0.5 mm steps;
    PyBullet then only draws). The native vector env uses "grid", and with
    it gives this env's numbers. ``max_joint_step`` (rad), ``reach_tolerance`` (rad, joint-space
    norm), ``delta`` (m), ``beta``, ``w_length``, ``w_progress``,
    ``reach_bonus``, ``collision_penalty``, ``clearance_cap`` (m),
    ``geometry``, ``render_mode`` ("rgb_array" or "human").

    ## Version History
    * v0: initial release (kinematic and dynamic fidelity). Since paragym 0.2.0
      an action outside the Box is clipped to it (before, an action of 30 moved
      a crank 60 deg in one step past obstacles); episodes of in-Box actions are
      unchanged, bit for bit (tested against recorded rollouts). Since
      paragym 0.3.0 a scenario argument of the wrong type is a TypeError (it
      was a ValueError), as in every paragym env; no episode changes.
    """

    def __init__(self, scenario: str | CaPaManScenario = "random", fidelity: str = "kinematic",
                 render_mode: str | None = None, max_joint_step: float = 2 * DEG,
                 reach_tolerance: float = 1 * DEG, delta: float = 0.01, beta: float = 0.1,
                 w_length: float = 1.0, w_progress: float = 2.0, reach_bonus: float = 1.0,
                 collision_penalty: float = 5.0, clearance_cap: float = 0.05, control_period: float = 0.02,
                 geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, collision: str = "pybullet") -> None:
        super().__init__(render_mode)
        if fidelity not in ("kinematic", "dynamic"):
            raise ValueError(f"fidelity must be 'kinematic' or 'dynamic'; got {fidelity!r}")
        if collision not in ("pybullet", "grid"):
            raise ValueError(f"collision must be 'pybullet' or 'grid'; got {collision!r}")
        if collision == "grid" and fidelity != "kinematic":
            raise ValueError("collision='grid' needs fidelity='kinematic' (the dynamic scene is PyBullet's)")
        self.collision = collision
        if not (np.isfinite(control_period) and control_period > 0):
            raise ValueError(f"control_period must be a positive number of seconds; got {control_period!r}")
        resolve_capaman(scenario)
        for name, value in (("max_joint_step", max_joint_step), ("reach_tolerance", reach_tolerance),
                            ("clearance_cap", clearance_cap)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number; got {value!r}")
        self.scenario_arg = scenario
        self.fidelity = fidelity
        self.geometry = geometry
        self.max_joint_step = float(max_joint_step)
        self.reach_tolerance = float(reach_tolerance)
        self.delta, self.beta = float(delta), float(beta)
        self.w_length, self.w_progress = float(w_length), float(w_progress)
        self.reach_bonus, self.collision_penalty = float(reach_bonus), float(collision_penalty)
        self.action_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
        self.observation_space = spaces.Box(-1.0, 1.0, (OBS_SIZE,), np.float32)
        self.control_period = float(control_period)
        #: sub-steps of one step's motion, each checked for collision (1 at the default max_joint_step)
        self._substeps = max(1, math.ceil(self.max_joint_step / SWEEP_STEP - 1e-9))
        if fidelity == "kinematic":
            self.scene = CaPaManScene(geometry, gui=render_mode == "human", clearance_cap=clearance_cap)
        else:
            self.scene = CaPaManDynamicScene(geometry, gui=render_mode == "human", clearance_cap=clearance_cap)
        self._scenario_scene: CaPaManScene | None = None
        if collision == "grid":
            self._grids = occupancy.DistanceGrids(1, cap=clearance_cap)
            self._grid_clusters = _clusters(geometry)
            self._part_names = [p.name for p in capaman.part_shapes(geometry)]
        self._lo, self._hi = geometry.alpha_min, geometry.alpha_max
        self._mid, self._half = (self._hi + self._lo) / 2, (self._hi - self._lo) / 2
        self.scenario: CaPaManScenario | None = None

    # --- hooks ---------------------------------------------------------------------------
    def _reset_task(self, options: dict[str, Any]) -> dict[str, Any]:
        scenario = draw_scenario(options.get("scenario", self.scenario_arg), self.np_random, self._checker(),
                                 _clusters(self.geometry))
        self.scene.set_obstacles(scenario.obstacles)
        self.scenario = scenario
        self._tp = scenario.alpha
        self._tc = np.array(scenario.task_configs) if scenario.task_configs else \
            capaman.tool_tip(capaman.forward(self._tp, self.geometry), self.geometry)
        self._obstacle_code = np.zeros(MAX_OBSTACLES * ENCODING_SIZE)
        for i, o in enumerate(scenario.obstacles):
            self._obstacle_code[i * ENCODING_SIZE:(i + 1) * ENCODING_SIZE] = o.encode()
        self._alpha = self._tp[0].copy()
        self._command = self._alpha.copy()
        self._reached = 0
        self._path_length = 0.0
        self._step_length = 0.0
        self._progress = 0.0
        self._just_reached = False
        if self.collision == "grid":
            self._grids.set(0, scenario.obstacles)
        self._place(self._alpha)
        info = self._info()
        info["scenario"] = scenario
        return info

    def _checker(self) -> CaPaManScene:
        """The kinematic scene that generates and checks scenarios (the env's
        own in kinematic fidelity; a second, kinematic one in dynamic fidelity)."""
        if isinstance(self.scene, CaPaManScene):
            return self.scene
        if self._scenario_scene is None:
            self._scenario_scene = CaPaManScene(self.geometry, clearance_cap=self.scene.clearance_cap)
        return self._scenario_scene

    @property
    def _target(self) -> int:
        return TOUR[min(self._reached, len(TOUR) - 1)]

    def _apply_action(self, action: np.ndarray) -> None:
        target = self._tp[self._target]
        command = np.clip(self._command + action * self.max_joint_step, self._lo, self._hi)
        if self.fidelity == "kinematic":
            for k in range(1, self._substeps):  # the motion checked on the way (SWEEP_STEP apart)
                on_the_way = self._alpha + (command - self._alpha) * (k / self._substeps)
                self._place(on_the_way)
                if self._collision:
                    command = on_the_way
                    break
            new = command
        else:  # the motors chase the command for one control period; the encoders say where they got
            self.scene.drive(command, self.control_period)
            new = self.scene.alpha
        self._command = command
        self._step_length = math.hypot(*(new - self._alpha))
        self._path_length += self._step_length
        before = math.hypot(*(target - self._alpha))
        after = math.hypot(*(target - new))
        self._alpha = new
        self._place(new, posed=self.fidelity == "dynamic")
        self._progress = before - after
        self._just_reached = after <= self.reach_tolerance and not self._collision
        if self._just_reached:
            self._reached += 1

    def _place(self, alpha: np.ndarray, posed: bool = False) -> None:
        """The tool tip and the clearance at ``alpha``: by PyBullet (posing the
        scene unless the dynamics already did), or by the grid."""
        if self.collision == "grid":
            a = np.asarray(alpha, float)[None]
            pose = capaman.forward(a, self.geometry, validate=False)
            self._tip = capaman.tool_tip(pose, self.geometry)[0]
            clearance, part = occupancy.grid_clearance(a, self._grids, self._grid_clusters, self.geometry, pose=pose)
            self._clearance = float(clearance[0])
            self._near = self._part_names[int(part[0])] if part[0] >= 0 else None
            return
        if not posed:
            self.scene.set_configuration(alpha)
        self._tip = self.scene.tip
        self._clearance, self._near = self.scene.clearance()

    @property
    def _collision(self) -> bool:
        return self._clearance <= 0.0

    def _observe(self) -> np.ndarray:
        t = self._target
        obs = np.concatenate([
            np.clip((self._alpha - self._mid) / self._half, -1.0, 1.0), self._tip,
            (self._tp[t] - self._mid) / self._half, self._tc[t],
            self._obstacle_code,
            [max(self._clearance, -self.scene.clearance_cap), self._reached / len(TOUR)],
        ])
        return obs.astype(np.float32)

    def _reward(self) -> float:
        r = -self.w_length * self._step_length + self.w_progress * self._progress
        if self._clearance < self.delta:
            r -= self.beta
        if self._just_reached:
            r += self.reach_bonus
        if self._collision:
            r -= self.collision_penalty
        return float(r)

    def _terminated(self) -> bool:
        return self._collision or self._reached >= len(TOUR)

    def _info(self) -> dict[str, Any]:
        return {
            "collision": self._collision,
            "clearance": float(self._clearance),
            "nearest_part": self._near,
            "reached": self._reached,
            "target_index": self._target,
            "path_length": self._path_length,
            "is_success": self._reached >= len(TOUR) and not self._collision,
            "alpha": self._alpha.copy(),
            "tool_tip": np.array(self._tip),
        }

    def _render_rgb(self) -> np.ndarray:
        if self.collision == "grid":  # the scene is not posed by the steps
            self.scene.set_configuration(self._alpha)
        return self.scene.render()

    def _close(self) -> None:
        self.scene.close()
        if self._scenario_scene is not None:
            self._scenario_scene.close()


class CaPaManCollisionFreeVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeEnv` with
    ``collision="grid"`` stepped together: closed-form kinematics and paper
    000's grid test (Psi as signed distances, the cluster points of eq 2) for
    all robots in numpy (:mod:`paragym.envs.vector`; the same numbers as the
    single env with ``collision="grid"``). Scenarios are generated (and
    checked) by the single env's PyBullet scene, robot by robot, at reset.
    Keyword arguments are the single env's (``collision`` is "grid";
    ``fidelity`` is "kinematic")."""

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 **kwargs: Any) -> None:
        if kwargs.get("collision", "grid") != "grid" or kwargs.get("fidelity", "kinematic") != "kinematic":
            raise ValueError("the native CaPaMan vector env checks collisions on the grid in kinematic fidelity: "
                             "use gymnasium's sync/async modes for PyBullet's check or the dynamic fidelity")
        kwargs.update(collision="grid", fidelity="kinematic")
        super().__init__(num_envs, CaPaManCollisionFreeEnv(**kwargs), max_episode_steps, render_index)
        e, n = self.single_env, self.num_envs
        self.geometry = e.geometry
        self._grids = occupancy.DistanceGrids(n, cap=e.scene.clearance_cap)
        self._clusters = _clusters(e.geometry)
        self._tp, self._tc = np.zeros((n, 3, 3)), np.zeros((n, 3, 3))
        self._code = np.zeros((n, MAX_OBSTACLES * ENCODING_SIZE))
        self._alpha, self._command, self._tip = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
        self._reached = np.zeros(n, np.int64)
        self._path_length, self._step_length, self._progress = np.zeros(n), np.zeros(n), np.zeros(n)
        self._just_reached = np.zeros(n, bool)
        self._clearance = np.zeros(n)
        self._tour = np.array(TOUR)
        self._idx = np.arange(n)
        self._scenarios: list[CaPaManScenario | None] = [None] * n

    def _reset_rows(self, rows: np.ndarray, options: dict[str, Any]) -> None:
        e = self.single_env
        choice = resolve_capaman(options.get("scenario", e.scenario_arg))
        checker = e._checker()
        for i in rows:
            scenario = draw_scenario(choice, self._rngs[i], checker, _clusters(self.geometry))
            self._scenarios[i] = scenario
            self._grids.set(int(i), scenario.obstacles)
            self._tp[i] = scenario.alpha
            self._tc[i] = np.array(scenario.task_configs) if scenario.task_configs else \
                capaman.tool_tip(capaman.forward(scenario.alpha, self.geometry), self.geometry)
            self._code[i] = 0.0
            for k, o in enumerate(scenario.obstacles):
                self._code[i, k * ENCODING_SIZE:(k + 1) * ENCODING_SIZE] = o.encode()
        self._alpha[rows] = self._tp[rows, 0]
        self._command[rows] = self._alpha[rows]
        self._reached[rows] = 0
        self._path_length[rows], self._step_length[rows], self._progress[rows] = 0.0, 0.0, 0.0
        self._just_reached[rows] = False
        self._place(rows)

    def _place(self, rows: np.ndarray) -> None:
        a = self._alpha[rows]
        pose = capaman.forward(a, self.geometry, validate=False)
        self._tip[rows] = capaman.tool_tip(pose, self.geometry)
        self._clearance[rows] = occupancy.grid_clearance(a, self._grids, self._clusters, self.geometry, rows,
                                                         pose=pose)[0]

    def _target(self) -> np.ndarray:
        return self._tour[np.minimum(self._reached, len(TOUR) - 1)]

    def _apply(self, actions: np.ndarray, active: np.ndarray) -> None:
        e = self.single_env
        rows = np.flatnonzero(active)
        target = self._tp[rows, self._target()[rows]]
        command = np.clip(self._command[rows] + actions[rows] * e.max_joint_step, e._lo, e._hi)
        old = self._alpha[rows].copy()
        moving = np.ones(len(rows), bool)
        for k in range(1, e._substeps):  # the motion checked on the way, as the single env does
            on_the_way = old + (command - old) * (k / e._substeps)
            self._alpha[rows[moving]] = on_the_way[moving]
            self._place(rows[moving])
            hit = moving & (self._clearance[rows] <= 0.0)
            command[hit] = on_the_way[hit]
            moving &= ~hit
        step = np.sqrt(np.sum((command - old) ** 2, axis=1))
        before = np.sqrt(np.sum((target - old) ** 2, axis=1))
        after = np.sqrt(np.sum((target - command) ** 2, axis=1))
        self._command[rows], self._alpha[rows] = command, command
        self._step_length[rows] = step
        self._path_length[rows] += step
        self._place(rows)
        self._progress[rows] = before - after
        reached = (after <= e.reach_tolerance) & (self._clearance[rows] > 0.0)
        self._just_reached[rows] = reached
        self._reached[rows] += reached

    def _observe(self) -> np.ndarray:
        e = self.single_env
        t = self._target()
        obs = np.concatenate([np.clip((self._alpha - e._mid) / e._half, -1.0, 1.0), self._tip,
                              (self._tp[self._idx, t] - e._mid) / e._half, self._tc[self._idx, t], self._code,
                              np.maximum(self._clearance, -e.scene.clearance_cap)[:, None],
                              (self._reached / len(TOUR))[:, None]], axis=1)
        return obs.astype(np.float32)

    def _reward(self) -> np.ndarray:
        e = self.single_env
        r = -e.w_length * self._step_length + e.w_progress * self._progress
        r = r - e.beta * (self._clearance < e.delta) + e.reach_bonus * self._just_reached
        return r - e.collision_penalty * (self._clearance <= 0.0)

    def _terminated(self) -> np.ndarray:
        return (self._clearance <= 0.0) | (self._reached >= len(TOUR))

    def _infos(self) -> dict[str, Any]:
        collision = self._clearance <= 0.0
        return self._for_every_robot(clearance=self._clearance.copy(), collision=collision,
                                     is_success=(self._reached >= len(TOUR)) & ~collision)

    def _load_single(self, i: int) -> None:
        e = self.single_env
        e.scene.set_obstacles(self._scenarios[i].obstacles)
        e._alpha = self._alpha[i].copy()
