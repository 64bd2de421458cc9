"""``paragym/Orthoglide2PRRKappa-v0``: track a path with the 2PRR + table, keeping kappa(J) low (paper 003).

The single env and the native vector env are shells over one transition,
:mod:`paragym.tasks.orthoglide_step` (the single env is its N = 1 case); the
scenarios come from :mod:`paragym.tasks.orthoglide`.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import orthoglide as og
from paragym.sim.client import divides, physics_steps
from paragym.sim.orthoglide_dynamic import OrthoglideDynamics, OrthoglideDynamicScene
from paragym.tasks import orthoglide_step as task_step
from paragym.tasks.base import renamed
from paragym.tasks.orthoglide import draw_tasks, random_scenario, random_scenarios, resolve_task
from paragym.tasks.orthoglide_step import KAPPA_LIMIT, OBS_SIZE, OrthoglideParams, OrthoglideState

__all__ = ["KAPPA_LIMIT", "Orthoglide2PRRKappaEnv", "Orthoglide2PRRKappaV1Env", "Orthoglide2PRRKappaV1VectorEnv",
           "Orthoglide2PRRKappaVectorEnv", "random_scenario",
           "random_scenarios"]


class _OrthoglideTask:
    """The task's hooks, the same for the single env (N = 1) and the vector env."""

    state: OrthoglideState
    params: OrthoglideParams

    def new_state(self, n: int) -> OrthoglideState:
        return OrthoglideState.empty(n)

    def _start(self, rows: np.ndarray, rngs: list[np.random.Generator], options: dict[str, Any]) -> list[Any]:
        tasks = draw_tasks(options.get("scenario", self.scenario_arg), rngs, self.geometry)
        self._warn_rounded_time(tasks)
        task_step.reset(self.state, self.params, rows, tasks)
        if getattr(self, "world", None) is not None:
            self.world.reset(self.state)
        return tasks

    def _transition(self, actions: np.ndarray, active: np.ndarray) -> None:
        task_step.step(self.state, self.params, actions, active, getattr(self, "world", None))

    def _warn_rounded_time(self, tasks: list[Any]) -> None:
        """v0 in dynamic fidelity simulates each path step over whole physics steps: say so where that is
        not the path's own time (its hole; v1 simulates it exactly)."""
        world = getattr(self, "world", None)
        if world is None or world.exact_time:
            return
        step = world.scene.dynamics.time_step
        for task in tasks:
            dt = np.diff(task.t)
            if not all(divides(float(d), step) for d in np.unique(dt)):
                simulated = sum(physics_steps(float(d), step) * step for d in dt)
                warnings.warn(f"the path's {task.t[-1]:g} s are simulated over {simulated:g} s: the dynamic "
                              f"fidelity of {self.spec.id if self.spec else 'v0'} rounds each path step to whole "
                              f"physics steps of {step:g} s; paragym/Orthoglide2PRRKappa-v1 simulates it exactly",
                              UserWarning, stacklevel=3)


class Orthoglide2PRRKappaEnv(_OrthoglideTask, ParagymEnv):
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
    ``Box(-10, 10, (11,), float32)``, each component clipped to +-10:

    ==========  ==========================================================
    0-2         rho (the table and the two sliders), normalised to [-1, 1] over their limits
    3-4         the path point of this step (table frame, m)
    5-6         the path point of the next step (table frame, m)
    7           log kappa (10 from kappa = 2.2e4 on, and where J is singular)
    8-10        n, the null vector of J (zeros where J is singular)
    ==========  ==========================================================

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
    ``geometry``; ``render_mode``. ``fidelity``: "kinematic" (default: the
    joints are set where the step puts them) or "dynamic"
    (:mod:`paragym.sim.orthoglide_dynamic`: the table and the two sliders
    are motors with force limits that chase those joints over the path's
    time step, the links and the tool's closure follow under PyBullet's
    dynamics; the encoders are the joints the env observes, kappa is taken
    where they put the tool, and the tracking error, charged by
    ``w_track`` in both action modes, is how far the tool is from the
    path). ``dynamics``: an
    :class:`~paragym.sim.orthoglide_dynamic.OrthoglideDynamics`.

    ## Version History
    * v0: initial release (kinematic fidelity).
      Since paragym 0.6.0 ``fidelity="dynamic"`` is offered; the default,
      kinematic, is unchanged.
      Since paragym 0.2.0 a custom scenario that cannot run (NaN, outside
      the workspace, malformed) and non-dict ``options`` are refused at reset
      with a ValueError or TypeError naming them; every episode that ran
      before runs the same (tested against recorded rollouts).
      Its holes, kept so that its episodes replay: in joint-velocity mode
      success ignores tracking (doing nothing succeeds); kappa is taken at
      the path point in kinematic fidelity and at the tool in dynamic; the
      dynamic fidelity rounds each path step to whole physics steps (it
      warns where that is not the path's time). Since paragym 0.8.0
      ``info["failure"]`` names why an episode failed.
    * v1 (paragym 0.8.0): :class:`Orthoglide2PRRKappaV1Env` closes them.
    """

    version = 0

    def __init__(self, scenario: str | Any = "random", action_mode: str = "null_space",
                 render_mode: str | None = None, max_null_rate: float = 0.5, max_joint_rate: float = 0.5,
                 w_track: float = 1.0, limit_penalty: float = 10.0,
                 geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY, fidelity: str = "kinematic",
                 dynamics: OrthoglideDynamics | None = None, track_tolerance: float | None = None) -> None:
        super().__init__(render_mode)
        if self.version == 0 and track_tolerance is not None:
            raise ValueError("track_tolerance is an argument of paragym/Orthoglide2PRRKappa-v1")
        track_tolerance = 0.005 if track_tolerance is None else track_tolerance
        if not (np.isfinite(track_tolerance) and track_tolerance > 0):
            raise ValueError(f"track_tolerance must be a positive number of metres; got {track_tolerance!r}")
        if fidelity not in ("kinematic", "dynamic"):
            raise ValueError(f"fidelity must be 'kinematic' or 'dynamic'; got {fidelity!r}")
        if dynamics is not None and not isinstance(dynamics, OrthoglideDynamics):
            raise TypeError(f"dynamics must be an OrthoglideDynamics or None; got {type(dynamics).__name__}")
        if action_mode not in ("null_space", "joint_velocity"):
            raise ValueError(f"action_mode must be 'null_space' or 'joint_velocity'; got {action_mode!r}")
        self.scenario_arg = resolve_task(scenario, geometry)
        self.action_mode, self.geometry = action_mode, geometry
        self.max_null_rate, self.max_joint_rate = float(max_null_rate), float(max_joint_rate)
        self.w_track, self.limit_penalty = float(w_track), float(limit_penalty)
        self.track_tolerance = float(track_tolerance)
        self.params = OrthoglideParams(action_mode == "joint_velocity", self.max_null_rate, self.max_joint_rate,
                                       self.w_track, self.limit_penalty, geometry, self.version,
                                       self.track_tolerance)
        dim = 1 if action_mode == "null_space" else 3
        self.action_space = spaces.Box(-1.0, 1.0, (dim,), np.float32)
        self.observation_space = spaces.Box(-10.0, 10.0, (OBS_SIZE,), np.float32)
        self.state = self.new_state(1)
        self.fidelity = fidelity
        self.world: task_step.DynamicWorld | None = None
        if fidelity == "dynamic":
            self.world = task_step.DynamicWorld(OrthoglideDynamicScene(geometry, dynamics,
                                                                       gui=render_mode == "human"),
                                                exact_time=self.version >= 1)

    @property
    def task(self) -> Any:
        """The episode's path (:class:`paragym.tasks.orthoglide.OrthoglideScenario`)."""
        return self.state.scenarios[0]

    def _ended(self) -> bool:
        return bool(self.state.k[0] >= self.state.last[0])

    def _info(self) -> dict[str, Any]:
        s = self.state
        done = bool(s.k[0] >= s.last[0])
        return {"kappa": float(s.kappa[0]), "tracking_error": float(s.err[0]), "rho": s.rho[0].copy(),
                "step": int(s.k[0]), "is_success": done and not s.failed[0],
                "failure": task_step.FAILURES[int(s.reason[0])]}

    # KF validation (dynamic fidelity): the tool holder at C on link AC, the array in the table's plane, 3 cm below
    sensor_layout: dict[str, float] = {"r": 0.05, "depth": 0.03}

    def _body(self) -> tuple[Any, str, int, np.ndarray, float]:
        scene = self.world.scene
        return (scene.sim, scene.ROBOT, scene.links[0], np.array([self.geometry.link, 0.0, 0.0]),
                scene.dynamics.time_step)

    def commanded_pose(self) -> np.ndarray:
        """C and link AC's direction from the commanded joints (paper 003, eqs 1-6), at the link's height."""
        g, rho = self.geometry, self.world.command
        c = og.fixed_point(rho[:1], og.forward(rho[None], g), g)[0]
        yaw = np.arctan2(c[1], c[0] - (g.slider2_origin + rho[1]))
        sim, robot, link, _, _ = self._dynamic_body()
        return np.array([c[0], c[1], sim.link_frame(robot, link)[0][2], 0.0, 0.0, yaw])

    def step_duration(self) -> float:
        h, k = self._dynamic_body()[4], int(self.state.k[0])
        return h * physics_steps(float(self.state.dt[0, k - 1]), h) if k > 0 else 0.0

    def _show(self) -> None:
        if self.world is None:  # the dynamic scene's GUI shows the simulation as it runs
            self._render_rgb()

    def _render_rgb(self) -> np.ndarray:
        from paragym.sim.orthoglide_scene import OrthoglideScene

        if self.world is not None:  # the simulated mechanism, not the command
            return self.world.scene.render()
        return self._drawn(lambda gui: OrthoglideScene(self.geometry, gui=gui),
                           lambda scene: scene.set_state(self.state.rho[0].copy(), self.task.points))

    def _close(self) -> None:
        self._close_render_scene()
        if self.world is not None:
            self.world.scene.close()


class Orthoglide2PRRKappaV1Env(Orthoglide2PRRKappaEnv):
    """``paragym/Orthoglide2PRRKappa-v1``: v0's mechanism, paths, spaces and
    reward, with success that requires the tracking the task asks for.

    ## Why v1
    In v0's joint-velocity mode success checked the joint limits and the
    singularity only: the zero action, which leaves the tool where it
    starts, "succeeded" on every path with a tracking error of 0.73 m. The
    two fidelities also took kappa at different points in that mode, and
    the dynamic fidelity rounded each path step to whole physics steps (a
    path of 1.25 s was simulated over 5 s).

    ## Episode End
    As v0, and a step whose tool is more than ``track_tolerance`` (5 mm)
    from its path point is a failure: it costs ``limit_penalty`` and ends
    the episode. In null-space mode the kinematic tool is on the path by
    construction (eq 5); the dynamic fidelity's lag counts. In dynamic
    fidelity a loop open by more than 5 mm (a broken mechanism) is a
    failure too. ``info["failure"]`` names the reason ("joint limit",
    "working mode", "singular", "tracking", "broken"; None while none).

    ## Rewards, Observation Space
    As v0, with kappa (eq 8) and the null vector n taken where the joints
    put the tool, in every mode and fidelity (in kinematic null-space mode
    that is the path point).

    ## Arguments
    As v0, plus ``track_tolerance`` (m). In dynamic fidelity each path step
    is simulated over exactly its duration: where the physics step does not
    divide it, the step is shortened to the fewest equal steps that do.

    ## Starting State, Action Space
    As v0.

    ## Version History
    * v1 (paragym 0.8.0): the rules above; in null-space mode and kinematic
      fidelity its episodes are v0's, bit for bit.
    """

    version = 1


class Orthoglide2PRRKappaVectorEnv(_OrthoglideTask, ParagymVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaEnv` stepped together:
    the same transition (:mod:`paragym.tasks.orthoglide_step`) over N robots.
    Keyword arguments are the single env's."""

    single_class = Orthoglide2PRRKappaEnv

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 **kwargs: Any) -> None:
        if kwargs.get("fidelity", "kinematic") != "kinematic":
            raise ValueError("the native Orthoglide vector env is kinematic: use gymnasium's sync/async vector "
                             "modes for the dynamic fidelity")
        super().__init__(num_envs, max_episode_steps, render_index, **kwargs)

    def _infos(self) -> dict[str, Any]:
        s = self.state
        return self._for_every_robot(kappa=s.kappa.copy(), is_success=~s.failed & (s.k >= s.last))

    def _load_single(self, i: int) -> None:
        one, s = self.single_env.state, self.state
        m = s.last[i] + 1
        one._room(m)
        one.rho[0], one.k[0], one.last[0], one.scenarios[0] = s.rho[i], s.k[i], s.last[i], s.scenarios[i]
        one.path[0, :m] = s.path[i, :m]


class Orthoglide2PRRKappaV1VectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaV1Env` stepped together."""

    single_class = Orthoglide2PRRKappaV1Env

#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = renamed(__name__, {"orthoglide_random_task": "random_scenario"})
