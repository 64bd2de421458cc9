"""The CaPaMan task's transition, written once over N robots (paper 000).

The state of N robots is a dataclass of arrays (:class:`CaPaManState`);
:func:`reset` puts the chosen rows at T.P.1 of their scenarios and
:func:`step` moves the active rows. Where the parts are and how far they
are from the obstacles is the *world*'s answer, one of three:

* :class:`GridWorld` (N robots): the closed-form kinematics and paper 000's
  occupancy grid Psi at the cluster points of eq 2 (numpy, all robots at once);
* :class:`SceneWorld` (one robot): PyBullet's exact signed distance in the
  kinematic scene;
* :class:`DynamicWorld` (one robot): the closed chain under PyBullet's
  dynamics; the motors chase the command for a control period and the
  encoders say where the cranks got.

The single env (N = 1, any world) and the native vector env (N robots, the
grid) run this same transition; the arithmetic around the world's answers
(the command, the path, progress, reaching, the observation and the reward)
is one numba kernel per half-step.

One step, for a robot at crank angles alpha with command c and current
target T.P. (the tour T.C.1 -> 2 -> 3 -> 1):

* c = clip(c + a * max_joint_step, 45 deg, 135 deg) (a joint stop);
* kinematic worlds: the motion from alpha to c is checked every
  ``SWEEP_STEP`` (2 deg per crank); at the first sub-step that collides, c
  stops there; alpha = c. Dynamic world: alpha = where the motors got;
* reward (after paper 000's fitness, eqs 3-5): -w_length |d alpha| +
  w_progress (joint distance to the target before - after) - beta [clearance
  < delta] + reach_bonus [target reached] - collision_penalty [collision].
  Terminated on collision or when the tour is complete.

Version 1 (``CaPaManRules.goal_relative``) keeps the motion, the collision
test and the episode's end, and changes what the agent sees and earns
(:data:`OBS_SIZE_V1`): goal-relative coordinates, the obstacles relative to
the tool tip, and a look-ahead of the clearance: how the clearance would
change if each crank alone moved ``LOOKAHEAD`` further (computed only near
an obstacle, where the clearance is under its cap; elsewhere it is 0, as the
capped clearance's change is). The reward adds ``-time_penalty`` per step,
so that standing still for the 400 steps (-4 by default) scores below any
attempt that makes progress, and ``collision_penalty`` defaults to that
whole budget, so that ending an episode by a collision never pays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from paragym.kernels import KernelArrays, KernelOwner
from paragym.mechanisms import capaman
from paragym.sim import mujoco_sim
from paragym.sim.obstacles import ENCODING_SIZE
from paragym.tasks import capaman as scenarios_module
from paragym.tasks.base import (
    check_choice,
    check_control_period,
    check_instance,
    check_number,
    refuse_unknown,
    renamed,
)
from paragym.tasks.capaman import LADDER, MAX_OBSTACLES, TOUR, CaPaManRung, CaPaManScenario
from paragym.tasks.capaman_worlds import World
from paragym.units import DEG

__all__ = ["FAILURES", "LADDER_RULES", "LOOKAHEAD", "REWARD_TERMS", "OBS_SIZE", "OBS_SIZE_V1", "RULES", "SWEEP_STEP",
           "CaPaManParams", "CaPaManRules", "CaPaManState", "decide", "reset", "step"]

#: why a robot's episode failed (0: it has not)
FAILURES = (None, "collision", "broken")
#: the reward's terms (after paper 000's fitness, eqs 3-5), each in the info as ``reward_<name>``: the joint
#: path's length, the progress to the target, v1's time penalty, the clearance under delta, a T.C. reached, a
#: collision; their sum is the reward
REWARD_TERMS = ("length", "progress", "time", "proximity", "reach", "collision")

#: the largest crank motion (rad, each crank) between two collision checks: in a step of 2 deg no point of
#: the 17 parts moves more than 4.7 mm (measured over the joint space, tested), under the 5 mm cell of the
#: occupancy grid, so checking the end of each such step checks the motion at the grid's resolution
SWEEP_STEP = 2 * DEG
_TOUR = np.asarray(TOUR, np.int64)
OBS_SIZE = 3 + 3 + 3 + 3 + MAX_OBSTACLES * ENCODING_SIZE + 1 + 1
#: v1: cranks (3), current and next target T.P. minus the cranks (3 + 3), tip minus target T.C. (3, x5 /m),
#: obstacles relative to the tip (3 x 8, lengths x5 /m), clearance / cap (1), its look-ahead change / cap (3),
#: progress (1)
OBS_SIZE_V1 = 3 + 3 + 3 + 3 + MAX_OBSTACLES * ENCODING_SIZE + 1 + 3 + 1
#: v1: the crank motion (rad) of the clearance look-ahead: 3 deg moves a point of the parts up to 7 mm,
#: more than a cell of the 5 mm occupancy grid, so the grid's look-ahead is not lost to its quantisation
LOOKAHEAD = 3 * DEG
#: v1: lengths in the observation are multiplied by this (1/m): +-20 cm fill the Box
LENGTH_SCALE = 5.0


class KernelArgs(NamedTuple):
    """The parameters the step's kernels read, by name (numba compiles a NamedTuple of floats): the action's
    scale (rad), the reach tolerance (rad), delta (m) and beta, the reward's weights, the clearance cap (m),
    the joint range (rad) and v1's time penalty."""

    max_joint_step: float
    reach_tolerance: float
    delta: float
    beta: float
    w_length: float
    w_progress: float
    reach_bonus: float
    collision_penalty: float
    clearance_cap: float
    alpha_min: float
    alpha_max: float
    time_penalty: float

@dataclass(frozen=True)
class CaPaManRules:
    """The rules of one version of the task (the env id's class holds one of :data:`RULES`).

    Attributes:
        version: the N of ``-vN``.
        goal_relative: v1's observation (goal-relative, with the clearance's look-ahead, :data:`OBS_SIZE_V1`)
            and ``time_penalty`` an argument; else v0's observation, and no time penalty.
        reach_tolerance, collision_penalty, time_penalty: the defaults of those arguments.
        rung: a rung of the difficulty ladder (one of :data:`paragym.tasks.capaman.LADDER`): its scenarios
            ("random"), its posts' slots in the observation and the capsule model's collision test
            (``collision="posts"``); None for the released versions.
    """

    version: int
    goal_relative: bool
    reach_tolerance: float
    collision_penalty: float
    time_penalty: float
    rung: CaPaManRung | None = None

    @property
    def max_obstacles(self) -> int:
        """The obstacles' slots of the observation."""
        return MAX_OBSTACLES if self.rung is None else self.rung.max_obstacles


#: the engines of the dynamic fidelity (the env's ``engine`` argument): both of :mod:`paragym.sim.mujoco_sim`
ENGINES = mujoco_sim.ENGINES
#: the rules of CaPaManCollisionFree-v0 and -v1
RULES = {0: CaPaManRules(0, goal_relative=False, reach_tolerance=1 * DEG, collision_penalty=5.0, time_penalty=0.0),
         1: CaPaManRules(1, goal_relative=True, reach_tolerance=3 * DEG, collision_penalty=4.0, time_penalty=0.01)}
#: the rules of the ladder's rungs, CaPaManCollisionFree-Easy, -Medium and -Hard (v0 each): v1's observation,
#: reward and reach tolerance, on the rung's scenarios, with the capsule model's collision test
LADDER_RULES = {k: CaPaManRules(0, goal_relative=True, reach_tolerance=3 * DEG, collision_penalty=4.0,
                                time_penalty=0.01, rung=rung) for k, rung in enumerate(LADDER)}


@dataclass(frozen=True)
class CaPaManParams(KernelOwner):
    """The env's arguments (see the env's docstring), checked by :meth:`from_kwargs`."""

    max_joint_step: float = 2 * DEG
    reach_tolerance: float = 1 * DEG
    delta: float = 0.01
    beta: float = 0.1
    w_length: float = 1.0
    w_progress: float = 2.0
    reach_bonus: float = 1.0
    collision_penalty: float = 5.0
    clearance_cap: float = 0.05
    geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY
    #: v1's observation and look-ahead (:attr:`CaPaManRules.goal_relative`)
    goal_relative: bool = False
    time_penalty: float = 0.0
    scenario: Any = "random"
    fidelity: str = "kinematic"
    collision: str = "pybullet"
    control_period: float = 0.02
    dynamics: Any = None
    rules: CaPaManRules = RULES[0]
    #: the dynamic fidelity's engine: None (PyBullet) or MuJoCo's settings (:mod:`paragym.sim.mujoco_sim`)
    engine: Any = None

    @classmethod
    def from_kwargs(cls, rules: CaPaManRules, scenario: Any = "random", fidelity: str = "kinematic",
                    max_joint_step: float = 2 * DEG, reach_tolerance: float | None = None, delta: float = 0.01,
                    beta: float = 0.1, w_length: float = 1.0, w_progress: float = 2.0, reach_bonus: float = 1.0,
                    collision_penalty: float | None = None, clearance_cap: float = 0.05,
                    control_period: float = 0.02, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                    collision: str | None = None, time_penalty: float | None = None, dynamics: Any = None,
                    engine: Any = "pybullet", **unknown: Any) -> CaPaManParams:
        """The env's keyword arguments, checked: the one place they are. Whether a custom scenario can run
        needs PyBullet: it is checked at reset."""
        from paragym.sim.capaman_dynamic import CaPaManDynamics
        from paragym.sim.mujoco_sim import check_engine

        refuse_unknown(unknown, (), "CaPaManCollisionFree")
        check_instance("dynamics", dynamics, CaPaManDynamics)
        reach_tolerance = rules.reach_tolerance if reach_tolerance is None else reach_tolerance
        collision_penalty = rules.collision_penalty if collision_penalty is None else collision_penalty
        time_penalty = rules.time_penalty if time_penalty is None else time_penalty
        if not rules.goal_relative and time_penalty != 0.0:
            raise ValueError("time_penalty is a v1 argument: use paragym/CaPaManCollisionFree-v1")
        time_penalty = check_number("time_penalty", time_penalty, strict=False)
        check_choice("fidelity", fidelity, ("kinematic", "dynamic"))
        engine = check_engine(engine, ENGINES, fidelity, alone=True)
        alone = engine is not None and not engine.mirror  # MuJoCo alone: the clearance is the task's kernel's
        native = "grid" if rules.rung is None else "posts"  # a rung: the capsule model of its posts
        if collision is None:
            collision = native if fidelity == "kinematic" and rules.rung is not None or alone else "pybullet"
        check_choice("collision", collision, ("pybullet", native))
        if fidelity == "dynamic" and alone != (collision == native):
            raise ValueError(f"collision={collision!r}: in the dynamic fidelity, PyBullet's scene measures the "
                             f"clearance (collision='pybullet'), and MuJoCo alone (engine=MuJoCoSettings(mirror="
                             f"False)) the task's kernel (collision={native!r})")
        control_period = check_number("control_period", control_period, unit=" of seconds")
        scenarios_module.resolve_scenario(scenario)
        for name, value in (("max_joint_step", max_joint_step), ("reach_tolerance", reach_tolerance),
                            ("clearance_cap", clearance_cap)):
            check_number(name, value)
        if fidelity == "dynamic":
            check_control_period(control_period, (dynamics or CaPaManDynamics()).time_step, refuse=False)
            if engine is not None:  # a new fidelity: nothing released to keep
                check_control_period(control_period, engine.time_step, refuse=True)
        return cls(float(max_joint_step), float(reach_tolerance), float(delta), float(beta), float(w_length),
                   float(w_progress), float(reach_bonus), float(collision_penalty), float(clearance_cap), geometry,
                   rules.goal_relative, time_penalty, scenario, fidelity, collision, control_period,
                   dynamics, rules, engine)

    @property
    def max_obstacles(self) -> int:
        """The obstacles' slots of the observation (:attr:`CaPaManRules.max_obstacles`)."""
        return self.rules.max_obstacles

    @property
    def obs_size(self) -> int:
        """v0: :data:`OBS_SIZE`; v1: :data:`OBS_SIZE_V1`; a rung: v1's with its own number of post slots."""
        return OBS_SIZE_V1 + (self.max_obstacles - MAX_OBSTACLES) * ENCODING_SIZE if self.goal_relative else OBS_SIZE

    @property
    def substeps(self) -> int:
        """Sub-steps of one step's motion, each checked for collision (1 at the default max_joint_step)."""
        return max(1, math.ceil(self.max_joint_step / SWEEP_STEP - 1e-9))

    @cached_property
    def kernel_args(self) -> KernelArgs:
        """The numbers :func:`_finish_kernel` and :func:`_command` take, by name (made once)."""
        g = self.geometry
        return KernelArgs(float(self.max_joint_step), float(self.reach_tolerance), float(self.delta),
                          float(self.beta), float(self.w_length), float(self.w_progress), float(self.reach_bonus),
                          float(self.collision_penalty), float(self.clearance_cap), float(g.alpha_min),
                          float(g.alpha_max), float(self.time_penalty))


@dataclass
class CaPaManState(KernelArrays):
    """N robots: task points T.P. and task configurations T.C. (N, 3, 3), the
    obstacles' encoding, crank angles, command and tool tip (N, 3), the tour's
    progress, path length, last step's length and progress, the clearance
    (m) and its nearest part, the clearance's look-ahead (N, 3; v1), and the
    observation and reward of the last step."""

    #: the arrays the kernels take, in their order (:class:`paragym.kernels.KernelArrays`)
    KERNEL_FIELDS = ("tp", "tc", "code", "alpha", "tip", "reached", "path_length", "step_length", "progress",
                     "just_reached", "clearance", "terminated", "obs", "reward", "lookahead", "terms", "collision",
                     "failure", "success", "target_index", "broken")

    tp: np.ndarray
    tc: np.ndarray
    code: np.ndarray
    alpha: np.ndarray
    command: np.ndarray
    tip: np.ndarray
    reached: np.ndarray
    path_length: np.ndarray
    step_length: np.ndarray
    progress: np.ndarray
    just_reached: np.ndarray
    clearance: np.ndarray
    lookahead: np.ndarray
    terminated: np.ndarray
    obs: np.ndarray
    reward: np.ndarray
    terms: np.ndarray
    near: list[str | None] = field(default_factory=list)
    scenarios: list[CaPaManScenario | None] = field(default_factory=list)
    #: what :meth:`~paragym.tasks.base.Task.evaluate` decided of each robot (its buffers, rewritten each call)
    success: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)
    evaluation: Any = field(default=None, repr=False, compare=False)
    failure: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False, compare=False)
    collision: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)
    target_index: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False, compare=False)
    #: what the world measured of each robot's last move before the transition decided: a loop open by more than
    #: its world's ``BROKEN_GAP`` (the dynamics; False in the kinematic fidelity)
    broken: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)


    @classmethod
    def empty(cls, n: int, params: CaPaManParams) -> CaPaManState:
        """N robots, before their first reset."""
        z, obs_size = np.zeros, params.obs_size
        return cls(tp=z((n, 3, 3)), tc=z((n, 3, 3)), code=z((n, params.max_obstacles * ENCODING_SIZE)), alpha=z((n, 3)),
                   command=z((n, 3)), tip=z((n, 3)), reached=z(n, np.int64), path_length=z(n), step_length=z(n),
                   progress=z(n), just_reached=z(n, bool), clearance=z(n), lookahead=z((n, 3)),
                   terminated=z(n, bool), obs=z((n, obs_size), np.float32), reward=z(n),
                   terms=z((n, len(REWARD_TERMS))), near=[None] * n,
                   scenarios=[None] * n, success=z(n, bool), failure=z(n, np.int64), collision=z(n, bool),
                   target_index=z(n, np.int64), broken=z(n, bool))

    @property
    def target(self) -> np.ndarray:
        """The index of each robot's current target T.P. (N,)."""
        return _TOUR[np.minimum(self.reached, len(TOUR) - 1)]


def reset(state: CaPaManState, params: CaPaManParams, rows: np.ndarray, scenarios: list[CaPaManScenario],
          world: World, probe: World | None = None) -> None:
    """Start ``rows`` at T.P.1 of their (checked) ``scenarios``. ``probe``:
    the kinematic world of v1's look-ahead when ``world`` is the dynamics."""
    g = params.geometry
    for i, scenario in zip(rows, scenarios, strict=True):
        state.scenarios[i] = scenario
        world.set_obstacles(i, scenario)
        if probe is not None and probe is not world:
            probe.set_obstacles(i, scenario)
    # the task points, configurations and obstacles' codes of every row in one array each (as many rows reset
    # at once as a native env's episodes end together)
    state.tp[rows] = np.array([s.task_points for s in scenarios], float).reshape(-1, 3, 3)
    state.tc[rows] = [np.array(s.task_configs) if s.task_configs else capaman.forward(s.alpha, g).tip
                      for s in scenarios]
    state.code[rows] = 0.0
    for i, scenario in zip(rows, scenarios, strict=True):
        for k, o in enumerate(scenario.obstacles):
            state.code[i, k * ENCODING_SIZE:(k + 1) * ENCODING_SIZE] = o.encode()
    state.alpha[rows] = state.tp[rows, 0]
    state.command[rows] = state.alpha[rows]
    state.reached[rows] = 0
    state.path_length[rows], state.step_length[rows], state.progress[rows] = 0.0, 0.0, 0.0
    state.just_reached[rows], state.broken[rows] = False, False
    _place(state, world, rows, state.alpha[rows])
    _look_ahead(state, params, world if probe is None else probe, rows, pose_back=probe is None)
    mask = np.zeros(len(state.alpha), bool)
    mask[rows] = True
    _finish(state, params, mask, state.alpha, False)


def step(state: CaPaManState, params: CaPaManParams, actions: np.ndarray, active: np.ndarray, world: World,
         probe: World | None = None) -> None:
    """Move the ``active`` robots (N,) with ``actions`` (N, 3) inside the Box
    (the env clips). ``probe``: as in :func:`reset`."""
    every = bool(active.all())
    rows = np.arange(len(active)) if every else np.flatnonzero(active)
    old = state.alpha.copy()
    actions = np.ascontiguousarray(actions, np.float64)
    command = state.call(_command, (state.command, actions, params.kernel_args), params, (actions.ndim,))
    broken: np.ndarray | bool = False
    if world.moves:  # the dynamics: the world moves the robots, checked by contact
        new = world.move(rows, command[rows])
        broken = world.broken[rows]
    else:
        n = params.substeps
        moving = rows
        for k in range(1, n):  # the motion checked on the way, SWEEP_STEP apart
            on_the_way = old[moving] + (command[moving] - old[moving]) * (k / n)
            clearance, _, _ = world.place(moving, on_the_way)
            hit = clearance <= 0.0
            command[moving[hit]] = on_the_way[hit]  # the mechanism stops where a sub-step first collides
            moving = moving[~hit]
            if not moving.size:
                break
        new = command if every else command[rows]
    if every:
        state.command[:], state.alpha[:] = command, new
    else:
        state.command[rows], state.alpha[rows] = command[rows], new
    _place(state, world, rows, new)
    state.broken[rows] = broken  # what the world measured, before the decision
    _look_ahead(state, params, world if probe is None else probe, rows, pose_back=probe is None)
    _finish(state, params, active, old, True)


def _look_ahead(state: CaPaManState, params: CaPaManParams, world: World, rows: np.ndarray,
                pose_back: bool = True) -> None:
    """v1: the change of each robot's clearance if one crank alone moved
    :data:`LOOKAHEAD` further (inside the joint range), for the robots whose
    clearance is under the cap (elsewhere 0). A kinematic PyBullet scene is
    posed back where the robot is when ``pose_back`` (it is the env's own and
    is drawn; a probe that only answers the look-ahead is not)."""
    if not params.goal_relative:
        return
    state.lookahead[rows] = 0.0
    near = rows[state.clearance[rows] < params.clearance_cap]
    if not near.size:
        return
    g = params.geometry
    probes = np.repeat(state.alpha[near][:, None], 3, axis=1)  # (M, 3, 3): crank k moved in probes[:, k]
    for k in range(3):
        probes[:, k, k] = np.minimum(probes[:, k, k] + LOOKAHEAD, g.alpha_max)
    ahead = world.ahead(near, probes, state.alpha[near], pose_back)
    state.lookahead[near] = np.minimum(ahead, params.clearance_cap) - state.clearance[near, None]


def _place(state: CaPaManState, world: World, rows: np.ndarray, alpha: np.ndarray) -> None:
    clearance, tip, near = world.place(rows, alpha)
    state.clearance[rows], state.tip[rows] = clearance, tip
    for i, part in zip(rows.tolist(), near, strict=True):
        state.near[i] = part


def _finish(state: CaPaManState, params: CaPaManParams, rows: np.ndarray, old: np.ndarray, move: bool) -> None:
    arrays, rows = state.kernel_arrays(), np.ascontiguousarray(rows, np.bool_)
    old, key = np.ascontiguousarray(old, np.float64), (old.ndim, rows.ndim)
    state.call(_finish_kernel, (arrays, old, rows, move, params.kernel_args, _TOUR), params, key)
    if params.goal_relative:
        state.call(_observe_v1, (arrays, rows, params.kernel_args, _TOUR), params, key)


@njit(cache=True)
def decide(reached: int, n_tour: int, collision: bool, broken: bool) -> tuple[int, bool]:
    """A robot's failure (1: a collision, 2: a broken mechanism, 0: none) and whether it has succeeded: the tour
    T.C.1 -> 2 -> 3 -> 1 complete (``reached >= n_tour``) with no failure. The one place the task decides
    success: the transition's kernel calls it for every robot it evaluates, with what the world measured, and
    :meth:`~paragym.tasks.capaman_task.CaPaManTask.evaluate` reports what it decided."""
    failure = 1 if collision else 2 if broken else 0
    return failure, reached >= n_tour and failure == 0


@njit(cache=True, error_model="numpy")
def _command(command, actions, p):
    """The new commands (N, 3): c + a * max_joint_step, inside the joint range."""
    out = np.empty_like(command)
    for i in range(command.shape[0]):
        for c in range(3):
            out[i, c] = min(p.alpha_max, max(p.alpha_min, command[i, c] + actions[i, c] * p.max_joint_step))
    return out


@njit(cache=True, error_model="numpy")
def _finish_kernel(arrays, old, rows, move, p, tour):
    """After the world has placed the robots of ``rows``: the step's length and
    progress toward the target, reaching, the reward, the end and the observation; a move that broke the
    mechanism (``broken``, the world's measurement) ends the episode as a failure and costs what a collision
    does. ``arrays``: the state's, in ``KERNEL_FIELDS``' order; ``p``: :class:`KernelArgs`."""
    tp, tc, code, alpha, tip, reached, path_length, step_length, progress, just_reached, clearance, terminated, \
        obs, reward, lookahead, terms, collision_, failure, success, target_index, broken = arrays
    n_tour = len(tour)
    mid, half = (p.alpha_max + p.alpha_min) / 2, (p.alpha_max - p.alpha_min) / 2
    for i in range(alpha.shape[0]):
        if not rows[i]:
            continue
        collision = clearance[i] <= 0.0
        if move:
            t = tour[min(reached[i], n_tour - 1)]
            d0, d1, d2 = alpha[i, 0] - old[i, 0], alpha[i, 1] - old[i, 1], alpha[i, 2] - old[i, 2]
            step_length[i] = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            path_length[i] += step_length[i]
            b0, b1, b2 = tp[i, t, 0] - old[i, 0], tp[i, t, 1] - old[i, 1], tp[i, t, 2] - old[i, 2]
            a0, a1, a2 = tp[i, t, 0] - alpha[i, 0], tp[i, t, 1] - alpha[i, 1], tp[i, t, 2] - alpha[i, 2]
            after = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
            progress[i] = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2) - after
            just_reached[i] = after <= p.reach_tolerance and not collision
            if just_reached[i]:
                reached[i] += 1
        # the reward and its terms (REWARD_TERMS): length, progress, time, proximity, reach, collision
        terms[i, 0], terms[i, 1] = -p.w_length * step_length[i], p.w_progress * progress[i]
        terms[i, 2] = -p.time_penalty if move else 0.0
        terms[i, 3] = -p.beta if clearance[i] < p.delta else 0.0
        terms[i, 4] = p.reach_bonus if just_reached[i] else 0.0
        came_apart = move and broken[i]
        # a broken mechanism costs a collision's penalty where the episode had not ended already
        terms[i, 5] = -p.collision_penalty if collision or (came_apart and reached[i] < n_tour) else 0.0
        reward[i] = terms[i, 0] + terms[i, 1] + terms[i, 2] + terms[i, 3] + terms[i, 4] + terms[i, 5]
        terminated[i] = collision or reached[i] >= n_tour or came_apart
        collision_[i], target_index[i] = collision, tour[min(reached[i], n_tour - 1)]
        failure[i], success[i] = decide(reached[i], n_tour, collision, came_apart)
        # observation: cranks, tip, target T.P. and T.C., obstacles, clearance, progress
        t = tour[min(reached[i], n_tour - 1)]
        for c in range(3):
            obs[i, c] = min(1.0, max(-1.0, (alpha[i, c] - mid) / half))
            obs[i, 3 + c] = tip[i, c]
            obs[i, 6 + c] = (tp[i, t, c] - mid) / half
            obs[i, 9 + c] = tc[i, t, c]
        for c in range(code.shape[1]):
            obs[i, 12 + c] = code[i, c]
        obs[i, 12 + code.shape[1]] = max(clearance[i], -p.clearance_cap)
        obs[i, 13 + code.shape[1]] = reached[i] / n_tour


@njit(cache=True, error_model="numpy")
def _observe_v1(arrays, rows, p, tour):
    """v1's observation of the robots of ``rows`` (:data:`OBS_SIZE_V1`)."""
    tp, tc, code, alpha, tip, reached, path_length, step_length, progress, just_reached, clearance, terminated, \
        obs, reward, lookahead, terms, collision_, failure, success, target_index, broken = arrays
    n_tour = len(tour)
    mid, half, cap = (p.alpha_max + p.alpha_min) / 2, (p.alpha_max - p.alpha_min) / 2, p.clearance_cap
    m = code.shape[1] // 8
    for i in range(alpha.shape[0]):
        if not rows[i]:
            continue
        t = tour[min(reached[i], n_tour - 1)]
        t_next = tour[min(reached[i] + 1, n_tour - 1)]
        for c in range(3):
            obs[i, c] = min(1.0, max(-1.0, (alpha[i, c] - mid) / half))
            obs[i, 3 + c] = min(1.0, max(-1.0, (tp[i, t, c] - alpha[i, c]) / half))
            obs[i, 6 + c] = min(1.0, max(-1.0, (tp[i, t_next, c] - alpha[i, c]) / half))
            obs[i, 9 + c] = min(1.0, max(-1.0, (tc[i, t, c] - tip[i, c]) * LENGTH_SCALE))
        for k in range(m):
            b = 12 + 8 * k
            present = code[i, 8 * k]
            obs[i, b], obs[i, b + 1] = present, code[i, 8 * k + 1]
            for c in range(3):
                rel = (code[i, 8 * k + 2 + c] - tip[i, c]) * LENGTH_SCALE if present > 0 else 0.0
                obs[i, b + 2 + c] = min(1.0, max(-1.0, rel))
                obs[i, b + 5 + c] = min(1.0, max(-1.0, code[i, 8 * k + 5 + c] * LENGTH_SCALE))
        b = 12 + 8 * m
        obs[i, b] = min(1.0, max(-1.0, clearance[i] / cap))
        for c in range(3):
            obs[i, b + 1 + c] = min(1.0, max(-1.0, lookahead[i, c] / cap))
        obs[i, b + 4] = reached[i] / n_tour

#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = renamed(__name__, {"CaPaManTaskState": "CaPaManState"})


