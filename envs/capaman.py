"""``paragym/CaPaManCollisionFree-v0``: the CaPaMan tour around obstacles (paper 000).

The single env and the native vector env are shells over one transition,
:mod:`paragym.tasks.capaman_step` (the single env is its N = 1 case, with
PyBullet's or the grid's collision check, or the dynamics); the scenarios
come from :mod:`paragym.tasks.capaman`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv, check_control_period, pose6
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import capaman
from paragym.sim.capaman_dynamic import CaPaManDynamics, CaPaManDynamicScene
from paragym.sim.capaman_scene import CaPaManScene
from paragym.sim.client import physics_steps
from paragym.tasks import capaman_step as task_step
from paragym.tasks.capaman import TOUR, CaPaManScenario, draw_scenario, resolve_capaman
from paragym.tasks.capaman_step import (
    SWEEP_STEP,
    CaPaManParams,
    CaPaManState,
    DynamicWorld,
    GridWorld,
    SceneWorld,
    _clusters,
)
from paragym.units import DEG

__all__ = ["SWEEP_STEP", "CaPaManCollisionFreeEnv", "CaPaManCollisionFreeV1Env", "CaPaManCollisionFreeV1VectorEnv",
           "CaPaManCollisionFreeVectorEnv"]


class _CaPaManTask:
    """The task's hooks, the same for the single env (N = 1) and the vector env."""

    state: CaPaManState
    params: CaPaManParams
    world: Any

    def new_state(self, n: int) -> CaPaManState:
        return CaPaManState.empty(n, self.params.obs_size)

    def _start(self, rows: np.ndarray, rngs: list[np.random.Generator], options: dict[str, Any]) -> list[Any]:
        choice = resolve_capaman(options.get("scenario", self.scenario_arg))
        checker = self._checker()
        scenarios = [draw_scenario(choice, rng, checker, _clusters(self.geometry)) for rng in rngs]
        task_step.reset(self.state, self.params, rows, scenarios, self.world, self._probe())
        return scenarios

    def _transition(self, actions: np.ndarray, active: np.ndarray) -> None:
        task_step.step(self.state, self.params, actions, active, self.world, self._probe())

    def _probe(self) -> Any:
        """v1's look-ahead world: the kinematic one (for the dynamics, the kinematic checker scene)."""
        if self.params.version == 0:
            return None
        if isinstance(self.world, DynamicWorld):
            if self._probe_world is None:
                self._probe_world = SceneWorld(self._checker())
            return self._probe_world
        return self.world


class CaPaManCollisionFreeEnv(_CaPaManTask, ParagymEnv):
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
    ``geometry``, ``render_mode`` ("rgb_array" or "human"). ``dynamics``: a
    :class:`~paragym.sim.capaman_dynamic.CaPaManDynamics` for the dynamic
    fidelity (default ``CaPaManDynamics()``, the released settings: 1 ms,
    150 solver iterations, no joint stops); the presets
    ``CaPaManDynamics.fast()`` and ``.split()`` (the same motion in a
    cheaper layout) have joint stops and keep the loops closed within 1 mm
    under contact, several times faster than the released settings
    (:mod:`paragym.sim.capaman_dynamic`).

    ## Version History
    * v0: initial release (kinematic and dynamic fidelity). Since paragym 0.2.0
      an action outside the Box is clipped to it (before, an action of 30 moved
      a crank 60 deg in one step past obstacles); episodes of in-Box actions are
      unchanged, bit for bit (tested against recorded rollouts). Since
      paragym 0.3.0 a scenario argument of the wrong type is a TypeError (it
      was a ValueError), as in every paragym env; no episode changes. Since
      paragym 0.6.0 a ``dynamics`` argument chooses the dynamic fidelity's
      settings; its default is the released ones (episodes unchanged, bit for
      bit).
    * v1 (paragym 0.4.0): :class:`CaPaManCollisionFreeV1Env`, a new
      observation, reward and reach tolerance; v0 is unchanged.
    * paragym 0.8.0, v0 and v1: ``info["failure"]`` ("collision",
      "broken"); in dynamic fidelity a loop open by more than 5 mm ends the
      episode as "broken" (no released setting opens one that far before a
      collision ends the episode: their rollouts are unchanged); a
      ``control_period`` that the physics step does not divide warns.
    """

    version = 0
    #: v1's defaults that differ from v0's
    _defaults: dict[str, float] = {}

    def __init__(self, scenario: str | CaPaManScenario = "random", fidelity: str = "kinematic",
                 render_mode: str | None = None, max_joint_step: float = 2 * DEG,
                 reach_tolerance: float | None = None, delta: float = 0.01, beta: float = 0.1,
                 w_length: float = 1.0, w_progress: float = 2.0, reach_bonus: float = 1.0,
                 collision_penalty: float | None = None, clearance_cap: float = 0.05, control_period: float = 0.02,
                 geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY, collision: str = "pybullet",
                 time_penalty: float | None = None, dynamics: CaPaManDynamics | None = None) -> None:
        super().__init__(render_mode)
        if dynamics is not None and not isinstance(dynamics, CaPaManDynamics):
            raise TypeError(f"dynamics must be a CaPaManDynamics or None; got {type(dynamics).__name__}")
        defaults = {"reach_tolerance": 1 * DEG, "collision_penalty": 5.0, "time_penalty": 0.0, **self._defaults}
        reach_tolerance = defaults["reach_tolerance"] if reach_tolerance is None else reach_tolerance
        collision_penalty = defaults["collision_penalty"] if collision_penalty is None else collision_penalty
        time_penalty = defaults["time_penalty"] if time_penalty is None else time_penalty
        if self.version == 0 and time_penalty != 0.0:
            raise ValueError("time_penalty is a v1 argument: use paragym/CaPaManCollisionFree-v1")
        if not (np.isfinite(time_penalty) and time_penalty >= 0):
            raise ValueError(f"time_penalty must be >= 0; got {time_penalty!r}")
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
        self.control_period = float(control_period)
        self.time_penalty = float(time_penalty)
        self.params = CaPaManParams(self.max_joint_step, self.reach_tolerance, self.delta, self.beta, self.w_length,
                                    self.w_progress, self.reach_bonus, self.collision_penalty, float(clearance_cap),
                                    geometry, self.version, self.time_penalty)
        self.observation_space = spaces.Box(-1.0, 1.0, (self.params.obs_size,), np.float32)
        if fidelity == "kinematic" and collision == "grid":  # the scene that checks scenarios comes when asked
            self.scene: CaPaManScene | CaPaManDynamicScene | None = None
            self.world = GridWorld(1, geometry, clearance_cap)
        elif fidelity == "kinematic":
            self.scene = CaPaManScene(geometry, gui=render_mode == "human", clearance_cap=clearance_cap,
                                      draws=render_mode is not None)
            self.world = SceneWorld(self.scene)
        else:
            check_control_period(self.control_period, (dynamics or CaPaManDynamics()).time_step, refuse=False)
            self.scene = CaPaManDynamicScene(geometry, dynamics, gui=render_mode == "human",
                                             clearance_cap=clearance_cap)
            self.world = DynamicWorld(self.scene, self.control_period)
        self._scenario_scene: CaPaManScene | None = None
        self._probe_world: SceneWorld | None = None  # v1 in dynamic fidelity: the look-ahead's kinematic scene
        self.state = self.new_state(1)

    def _checker(self) -> CaPaManScene:
        """The kinematic scene that generates and checks scenarios (the env's
        own in kinematic fidelity, built on first use where the grid checks
        collisions; a second, kinematic one in dynamic fidelity)."""
        if self.scene is None:
            self.scene = CaPaManScene(self.geometry, gui=self.render_mode == "human",
                                      clearance_cap=self.params.clearance_cap, draws=self.render_mode is not None)
        if isinstance(self.scene, CaPaManScene):
            return self.scene
        if self._scenario_scene is None:
            self._scenario_scene = CaPaManScene(self.geometry, clearance_cap=self.scene.clearance_cap, draws=False)
        return self._scenario_scene

    def _info(self) -> dict[str, Any]:
        s = self.state
        collision = bool(s.clearance[0] <= 0.0)
        broken = isinstance(self.world, DynamicWorld) and self.world.broken
        return {
            "collision": collision,
            "failure": "collision" if collision else "broken" if broken else None,
            "clearance": float(s.clearance[0]),
            "nearest_part": s.near[0],
            "reached": int(s.reached[0]),
            "target_index": TOUR[min(int(s.reached[0]), len(TOUR) - 1)],
            "path_length": float(s.path_length[0]),
            "is_success": bool(s.reached[0] >= len(TOUR) and not collision and not broken),
            "alpha": s.alpha[0].copy(),
            "tool_tip": s.tip[0].copy(),
        }

    def _ended(self) -> bool:
        return False  # stepping on after the end is the caller's business, as in the released env

    # KF validation (dynamic fidelity): paper 000's accelerometer array on the movable plate about H
    sensor_layout: dict[str, float] = {}

    def _body(self) -> tuple[Any, str, int, np.ndarray, float]:
        return (self.scene.sim, *self.scene.plate, np.zeros(3), self.scene.dynamics.time_step)

    def commanded_pose(self) -> np.ndarray:
        """The plate's pose by the closed-form direct kinematics of the motors' targets."""
        pose = capaman.forward(self.state.command[:1], self.geometry, validate=False)
        return pose6(pose.position[0], pose.rotation[0])

    def step_duration(self) -> float:
        h = self._dynamic_body()[4]
        return h * physics_steps(self.control_period, h)

    def _show(self) -> None:
        """PyBullet keeps the GUI's scene posed (the grid check does not pose it: render does)."""

    def _render_rgb(self) -> np.ndarray:
        if self.collision == "grid":  # the scene is not posed by the steps
            self._checker().set_configuration(self.state.alpha[0])
        return self.scene.render()

    def _close(self) -> None:
        if self.scene is not None:
            self.scene.close()
        if self._scenario_scene is not None:
            self._scenario_scene.close()


class CaPaManCollisionFreeV1Env(CaPaManCollisionFreeEnv):
    """``paragym/CaPaManCollisionFree-v1``: v0's mechanism, scenarios, motion,
    collision test and episode end, with an observation, a reward and a reach
    tolerance under which learning beats standing still.

    ## Why v1
    In v0, PPO on 4 M steps never completed a tour (0 % on 30 scenarios)
    and every shipped agent scored below standing still (return 0): a
    one-line controller that steers the cranks straight to the target
    succeeds on about half the scenarios but collides on the other half
    (-5), so its median return is below 0 and learning is pulled toward
    timidity. The clearance was one number, with no direction in joint
    space to move away from an obstacle, and the reach tolerance (1 deg of
    joint-space norm, half an action's step) is hard to meet with a
    stochastic policy. The ablation behind v1 is in ``baselines/ABLATION.md``.

    ## Observation Space
    ``Box(-1, 1, (41,), float32)``:

    ==========  ==========================================================
    0-2         crank angles, normalised to [-1, 1] over 45-135 deg
    3-5         current target T.P. minus the cranks (/ 45 deg)
    6-8         the next target T.P. minus the cranks (/ 45 deg)
    9-11        current target T.C. minus the tool tip (x 5 /m)
    12-35       three obstacles x [present, is_box, centre minus tool tip (3), half sizes (3)] (x 5 /m)
    36          clearance / ``clearance_cap`` (signed)
    37-39       look-ahead: the clearance's change if crank k alone moved 3 deg further, / cap
                (:data:`paragym.tasks.capaman_step.LOOKAHEAD`; 0 away from obstacles)
    40          progress: T.C.s reached / 3
    ==========  ==========================================================

    ## Rewards
    v0's terms plus ``-time_penalty`` (0.01) per step; ``collision_penalty``
    is 4, the whole time budget of 400 steps, so that ending an episode by a
    collision never pays, and standing still (-4) scores below any attempt
    that makes progress.

    ## Starting State, Episode End, Action Space
    As v0. ``reach_tolerance`` is 3 deg (joint-space norm): one and a half
    action steps.

    ## Arguments
    As v0, plus ``time_penalty``. In dynamic fidelity the look-ahead is
    computed in the kinematic scene at the encoders' angles.

    ## Version History
    * v1 (paragym 0.4.0): the observation, reward and reach tolerance above;
      the motion, the collision test, the scenarios and the end are v0's.
    """

    version = 1
    _defaults = {"reach_tolerance": 3 * DEG, "collision_penalty": 4.0, "time_penalty": 0.01}


class CaPaManCollisionFreeVectorEnv(_CaPaManTask, ParagymVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeEnv` with
    ``collision="grid"`` stepped together: the same transition
    (:mod:`paragym.tasks.capaman_step`) over N robots, with paper 000's grid
    test (Psi as signed distances, the cluster points of eq 2) for all of
    them at once. Scenarios are generated (and checked) by a kinematic
    PyBullet scene of its own, robot by robot, at reset; the same scene draws
    robot ``render_index``. Keyword arguments are the single env's
    (``collision`` is "grid"; ``fidelity`` is "kinematic"), which checks them
    and derives the parameters (built with the grid, it builds no PyBullet
    scene)."""

    single_class = CaPaManCollisionFreeEnv

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 **kwargs: Any) -> None:
        if kwargs.get("collision", "grid") != "grid" or kwargs.get("fidelity", "kinematic") != "kinematic":
            raise ValueError("the native CaPaMan vector env checks collisions on the grid in kinematic fidelity: "
                             "use gymnasium's sync/async modes for PyBullet's check or the dynamic fidelity")
        kwargs.update(collision="grid", fidelity="kinematic")
        super().__init__(num_envs, max_episode_steps, render_index, **kwargs)
        self.world = GridWorld(self.num_envs, self.geometry, self.params.clearance_cap)
        self._scene: CaPaManScene | None = None

    def _checker(self) -> CaPaManScene:
        """The kinematic scene that checks every robot's scenario and draws robot ``render_index``."""
        if self._scene is None:
            self._scene = CaPaManScene(self.geometry, clearance_cap=self.params.clearance_cap,
                                       draws=self.render_mode is not None)
        return self._scene

    def render(self) -> np.ndarray | None:
        """Robot ``render_index`` drawn by PyBullet (``render_mode="rgb_array"``)."""
        if self.render_mode != "rgb_array":
            return None
        i, scene = self.render_index, self._checker()
        scene.set_obstacles(self.state.scenarios[i].obstacles)
        scene.set_configuration(self.state.alpha[i])
        return scene.render()

    def close_extras(self, **kwargs: Any) -> None:
        super().close_extras(**kwargs)
        if self._scene is not None:
            self._scene.close()

    def _infos(self) -> dict[str, Any]:
        s = self.state
        collision = s.clearance <= 0.0
        return self._for_every_robot(clearance=s.clearance.copy(), collision=collision,
                                     is_success=(s.reached >= 3) & ~collision)



class CaPaManCollisionFreeV1VectorEnv(CaPaManCollisionFreeVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeV1Env` stepped together on the grid."""

    single_class = CaPaManCollisionFreeV1Env
