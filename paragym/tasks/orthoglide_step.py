"""The Orthoglide task's transition, written once over N robots (paper 003).

The state of N robots is a dataclass of arrays (:class:`OrthoglideState`);
:func:`reset` puts the chosen rows at their tasks' optimal start and
:func:`step` moves the active rows one path point on. Both end by evaluating
the rows they touched (kappa, J, n, failure, observation, reward) in one
numba kernel that calls the mechanism's own kernels
(:mod:`paragym.mechanisms.orthoglide`), so that the single env (N = 1) and
the native vector env (N = 4096) run the same code: they are shells over
this module (:mod:`paragym.envs.orthoglide`), like gymnax's and Brax's envs
over their step functions.

One step, for a robot at path point k (table position rho1, path point
p_k, task rate t_k, J and n at k):

* null-space mode (default): rho1 += dt (J^+ t_k + a * max_null_rate * n)_1,
  then rho2, rho3 by inverse kinematics at p_{k+1} (exact tracking; eq 5);
* joint-velocity mode: rho += dt * max_joint_rate * a;
* then at p_{k+1}: the working mode and the joint limits (else failure),
  J, kappa (eq 8) and n; kappa above :data:`KAPPA_LIMIT` is a failure too.
  Reward: -log kappa - w_track * tracking error / 0.01 m, or
  -limit_penalty on failure (on a rung with ``left_penalty``, also that much per path point left, so that
  no failure pays better than finishing); terminated on failure or at the path's end.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numba import njit

from paragym.kernels import KernelArrays, KernelOwner
from paragym.mechanisms import orthoglide as og
from paragym.sim import mujoco_sim
from paragym.tasks import orthoglide as scenarios_module
from paragym.tasks.base import (
    BROKEN_GAP,
    check_choice,
    check_instance,
    check_number,
    refuse_unknown,
)
from paragym.tasks.orthoglide import OrthoglideScenario, start_table_position
from paragym.tasks.orthoglide_worlds import DynamicWorld

__all__ = ["BROKEN_GAP", "FAILURES", "KAPPA_LIMIT", "LADDER_RULES", "LADDER_RULES_V1", "OBS_SIZE", "OBS_SIZE_JOINTS",
           "REWARD_TERMS", "RULES", "OrthoglideParams", "OrthoglideRules", "OrthoglideState", "decide", "kappa_bounds",
           "least_norm_kappa", "reset", "step"]

OBS_SIZE = 3 + 2 + 2 + 1 + 3
#: a rung whose policy drives the joints: :data:`OBS_SIZE`, then the tool's offset from the path point (x, y, in
#: centimetres)
OBS_SIZE_JOINTS = OBS_SIZE + 2
KAPPA_LIMIT = 100.0  # kappa above this counts as a singularity
#: why a robot failed (``OrthoglideState.reason``; 0: it did not): the names ``info["failure"]`` reports
FAILURES = (None, "joint limit", "working mode", "singular", "tracking", "broken")
#: the reward's terms, each in the info as ``reward_<name>``: -log kappa (eq 8), the tracking error's cost, a
#: failure's penalty; the reward is their sum
REWARD_TERMS = ("kappa", "tracking", "failure")
_LIMIT, _MODE, _SINGULAR, _TRACKING, _BROKEN = 1, 2, 3, 4, 5


@dataclass(frozen=True)
class OrthoglideRules:
    """The rules of one version of the task (the env id's class holds one of :data:`RULES`).

    Attributes:
        version: the N of ``-vN``.
        tracking: success requires tracking: kappa and n are taken where the joints put the tool in every
            mode, and a step beyond ``track_tolerance`` fails, as does a broken mechanism (dynamic fidelity).
        exact_time: the dynamic fidelity simulates each path step over exactly its duration (else rounded to
            whole physics steps, with a warning).
        rung: a rung of the difficulty ladder (one of :data:`paragym.tasks.orthoglide.LADDER`): its paths
            are the "random" scenario, and success asks for a mean kappa at most the rung's share of the way
            from 1 to the least-norm motion's (:func:`kappa_bounds`); None: a version of the task, whose success
            asks for no kappa.
        table_below_guides: in dynamic fidelity the table runs beneath the sliders' guides
            (:class:`~paragym.sim.orthoglide_dynamic.OrthoglideDynamicScene`'s ``table_below_guides``); before v2
            it ran at their height and struck the x guide's end on paths that carry it there.
    """

    version: int
    tracking: bool
    exact_time: bool
    rung: scenarios_module.OrthoglideRung | None = None
    table_below_guides: bool = False


#: the engines of the dynamic fidelity (the env's ``engine`` argument): both of :mod:`paragym.sim.mujoco_sim`
ENGINES = mujoco_sim.ENGINES
#: the rules of Orthoglide2PRRKappa-v0, -v1 and -v2
RULES = {0: OrthoglideRules(0, tracking=False, exact_time=False), 1: OrthoglideRules(1, tracking=True, exact_time=True),
         2: OrthoglideRules(2, tracking=True, exact_time=True, table_below_guides=True)}
#: the rules of the ladder's rungs, Orthoglide2PRRKappa-Easy, -Medium and -Hard (v0 each): v1's, on the rung's
#: paths and with its bound on the mean kappa (released before v2: their table runs at the guides' height)
LADDER_RULES = {k: OrthoglideRules(0, tracking=True, exact_time=True, rung=rung)
                for k, rung in enumerate(scenarios_module.LADDER)}
#: the rules of the ladder v1's rungs (-Easy-v1 ...): the ladder v0's, with v2's table beneath the guides
LADDER_RULES_V1 = {k: OrthoglideRules(1, tracking=True, exact_time=True, rung=rung, table_below_guides=True)
                   for k, rung in enumerate(scenarios_module.LADDER)}


@dataclass(frozen=True)
class OrthoglideParams(KernelOwner):
    """The env's arguments (see the env's docstring), checked by :meth:`from_kwargs`."""

    joint_mode: bool = False
    max_null_rate: float = 0.5  # m/s along n per unit of action
    max_joint_rate: float = 0.5  # m/s per unit of action
    w_track: float = 1.0
    limit_penalty: float = 10.0
    geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY
    #: success requires tracking (:attr:`OrthoglideRules.tracking`, v1's rules; module docstring)
    tracking: bool = False
    #: v1: the largest tracking error (m) of a step that counts as tracking; beyond it the robot fails
    track_tolerance: float = 0.005
    scenario: Any = "random"
    action_mode: str = "null_space"
    fidelity: str = "kinematic"
    dynamics: Any = None
    rules: OrthoglideRules = RULES[0]
    #: the dynamic fidelity's engine: None (PyBullet) or MuJoCo's settings (:mod:`paragym.sim.mujoco_sim`)
    engine: Any = None

    @classmethod
    def from_kwargs(cls, rules: OrthoglideRules, scenario: Any = "random", action_mode: str | None = None,
                    max_null_rate: float = 0.5, max_joint_rate: float = 0.5, w_track: float = 1.0,
                    limit_penalty: float = 10.0, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                    fidelity: str = "kinematic", dynamics: Any = None, track_tolerance: float | None = None,
                    engine: Any = "pybullet", **unknown: Any) -> OrthoglideParams:
        """The env's keyword arguments, checked: the one place they are."""
        from paragym.sim.mujoco_sim import check_engine
        from paragym.sim.orthoglide_dynamic import OrthoglideDynamics

        refuse_unknown(unknown, (), "Orthoglide2PRRKappa")
        engine = check_engine(engine, ENGINES, fidelity, alone=True)
        if not rules.tracking and track_tolerance is not None:
            raise ValueError("track_tolerance is an argument of paragym/Orthoglide2PRRKappa-v1 and later, not of v0")
        track_tolerance = check_number("track_tolerance", 0.005 if track_tolerance is None else track_tolerance,
                                       unit=" of metres")
        check_choice("fidelity", fidelity, ("kinematic", "dynamic"))
        check_instance("dynamics", dynamics, OrthoglideDynamics)
        fixed = None if rules.rung is None else rules.rung.actions
        if action_mode is None:
            action_mode = fixed or "null_space"
        check_choice("action_mode", action_mode, ("null_space", "joint_velocity"))
        if fixed is not None and action_mode != fixed:
            raise ValueError(f"action_mode: this rung of the ladder fixes it to {fixed!r}; got {action_mode!r}")
        scenario = scenarios_module.resolve_scenario(scenario, geometry)
        return cls(action_mode == "joint_velocity", float(max_null_rate), float(max_joint_rate), float(w_track),
                   float(limit_penalty), geometry, rules.tracking, track_tolerance, scenario,
                   action_mode, fidelity, dynamics, rules, engine)

    #: a copy or a pickle leaves out the starts the parameters remember (:func:`_starts`): weak references, which
    #: do not pickle, to the scenarios of this process
    not_pickled: ClassVar[tuple[str, ...]] = ("_starts",)

    @cached_property
    def least_norm(self) -> OrthoglideParams:
        """These parameters for the least-norm motion (null-space mode, kinematic, v1's rules): what the zero
        action does in null-space mode, paper 003's case (b); made once."""
        return replace(self, joint_mode=False, action_mode="null_space", fidelity="kinematic", dynamics=None,
                       tracking=RULES[1].tracking, rules=RULES[1])

    @property
    def obs_size(self) -> int:
        """The observation's length: :data:`OBS_SIZE`, and the tool's offset from the path point (2) where a
        rung of the ladder has the policy drive the joints (:data:`OBS_SIZE_JOINTS`)."""
        return OBS_SIZE_JOINTS if self.joint_mode and self.rules.rung is not None else OBS_SIZE

    @cached_property
    def kernel_args(self) -> tuple[Any, ...]:
        """The numbers the kernel takes, as a plain tuple in :class:`KernelParams`' order (made once: a step
        must not rebuild them; numba's dispatcher types a plain tuple in C, a NamedTuple in Python)."""
        g = self.geometry
        return tuple(KernelParams(og.params(g), np.array(g.rho_min), np.array(g.rho_max), self.joint_mode,
                                  self.max_null_rate, self.max_joint_rate, self.w_track, self.limit_penalty,
                                  self.left_penalty, self.tracking, self.track_tolerance))

    @property
    def left_penalty(self) -> float:
        """What a failure costs per path point left, beyond ``limit_penalty``: the rung's
        (:attr:`paragym.tasks.orthoglide.OrthoglideRung.left_penalty`), 0 off the ladder."""
        return 0.0 if self.rules.rung is None else self.rules.rung.left_penalty


class KernelParams(NamedTuple):
    """The parameters :func:`_advance_kernel` reads, by name (numba compiles a NamedTuple): the geometry's
    numbers (``og.params``), the joint limits (m), the action mode and scales, the reward's weights, the
    rules' tracking flag and the tracking tolerance (m)."""

    p: Any
    lo: np.ndarray
    hi: np.ndarray
    joint_mode: bool
    max_null_rate: float
    max_joint_rate: float
    w_track: float
    limit_penalty: float
    left_penalty: float
    tracking: bool
    track_tolerance: float


@dataclass
class OrthoglideState(KernelArrays):
    """N robots: joints, progress along their paths, what was evaluated at
    their path points, and the observation and reward of their last step.

    ``path`` (N, K, 4) holds every robot's path points and rates (x, y, vx,
    vy, table frame) and ``dt`` (N, K - 1) its time steps; ``last`` (N,) is
    each robot's last path index (paths may differ in length: the arrays are
    as long as the longest). ``j`` (N, 6) is J row-major.
    """

    #: the arrays the kernel take, in their order (:class:`paragym.kernels.KernelArrays`)
    KERNEL_FIELDS = ("rho", "k", "last", "path", "dt", "j", "n", "kappa", "err", "failed", "reason", "terminated",
                     "obs", "reward", "terms", "success", "kappa_sum", "mean_kappa", "bound", "broken")

    rho: np.ndarray
    k: np.ndarray
    last: np.ndarray
    path: np.ndarray
    dt: np.ndarray
    j: np.ndarray
    n: np.ndarray
    kappa: np.ndarray
    err: np.ndarray
    failed: np.ndarray
    reason: np.ndarray
    terminated: np.ndarray
    obs: np.ndarray
    reward: np.ndarray
    terms: np.ndarray
    scenarios: list[OrthoglideScenario | None] = field(default_factory=list)
    #: what :meth:`~paragym.tasks.base.Task.evaluate` decided of each robot (its buffers, rewritten each call)
    success: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)
    evaluation: Any = field(default=None, repr=False, compare=False)
    #: the sum of kappa over the path points evaluated so far (N,), and their mean, which success may bound
    kappa_sum: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    mean_kappa: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    #: the highest mean kappa of a success (N,): inf but on a rung of the ladder (:func:`kappa_bounds`)
    bound: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    #: what the simulation measured of each robot's last move, written before the transition decides: a loop open
    #: by more than :data:`BROKEN_GAP` (dynamic fidelity)
    broken: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)

    @classmethod
    def empty(cls, n: int, params: Any = None, points: int = 2) -> OrthoglideState:
        """N robots with room for paths of ``points`` points (it grows on reset)."""
        return cls(rho=np.zeros((n, 3)), k=np.zeros(n, np.int64), last=np.zeros(n, np.int64),
                   path=np.zeros((n, points, 4)), dt=np.zeros((n, points - 1)), j=np.zeros((n, 6)),
                   n=np.zeros((n, 3)), kappa=np.zeros(n), err=np.zeros(n), failed=np.zeros(n, bool),
                   reason=np.zeros(n, np.int64), terminated=np.zeros(n, bool),
                   obs=np.zeros((n, OBS_SIZE if params is None else params.obs_size), np.float32),
                   reward=np.zeros(n),
                   terms=np.zeros((n, len(REWARD_TERMS))), scenarios=[None] * n,
                   success=np.zeros(n, bool), kappa_sum=np.zeros(n), mean_kappa=np.zeros(n),
                   bound=np.full(n, np.inf), broken=np.zeros(n, bool))

    def _room(self, points: int) -> None:
        """Grow the path arrays to hold ``points`` points."""
        extra = points - self.path.shape[1]
        if extra > 0:
            self.path = np.pad(self.path, ((0, 0), (0, extra), (0, 0)))
            self.dt = np.pad(self.dt, ((0, 0), (0, extra)))
            self.reallocated()




def reset(state: OrthoglideState, params: OrthoglideParams, rows: np.ndarray,
          scenarios: list[OrthoglideScenario]) -> None:
    """Start ``rows`` on ``scenarios`` (checked ones: :func:`paragym.tasks.orthoglide.draw_scenarios`):
    at the admissible table position with the lowest kappa at the first path
    point, the sliders by inverse kinematics; then evaluate them."""
    rho, bound = _starts(params, scenarios)
    state._room(max(len(t.t) for t in scenarios))
    for i, task in zip(rows, scenarios, strict=True):
        m = len(task.t)
        state.path[i, :m, :2], state.path[i, :m, 2:] = task.points, task.velocities
        state.dt[i, :m - 1] = np.diff(task.t)
        state.last[i] = m - 1
        state.scenarios[i] = task
    state.rho[rows], state.k[rows], state.failed[rows], state.reason[rows] = rho, 0, False, 0
    state.kappa_sum[rows] = 0.0
    state.bound[rows] = bound
    mask = np.zeros(len(state.k), bool)
    mask[rows] = True
    _advance(state, params, np.zeros((len(state.k), 3 if params.joint_mode else 1)), mask, False)


#: scenarios whose starts each set of parameters on a rung remembers (:func:`_starts`)
_STARTS_KEPT = 4096


def _starts(params: OrthoglideParams, scenarios: list[OrthoglideScenario]) -> tuple[np.ndarray, np.ndarray]:
    """Where each of ``scenarios`` starts, the sliders rho (M, 3) m, and the rung's bound on its mean kappa (M,)
    (inf off a rung). On a rung the bound costs a whole lap of the least-norm motion and the start a sweep of
    the table, so the parameters remember the last :data:`_STARTS_KEPT`
    scenarios they started, by identity (a weak reference tells a scenario from a new one at a freed address):
    a finite training set (``train_scenarios``) is computed once. Each is computed alone or in a batch alike
    (row by row), so a remembered start is the same bits as a new one."""
    if params.rules.rung is None:  # nothing costly to remember
        return _start_rho(params, scenarios), np.full(len(scenarios), np.inf)
    memo = params.__dict__.setdefault("_starts", {})
    known = [memo.get(id(task)) for task in scenarios]
    new = [i for i, (task, got) in enumerate(zip(scenarios, known, strict=True)) if got is None or got[0]() is not task]
    if len(new) == len(scenarios):  # fresh scenarios (no training set): no gathering
        rho, bound = _start_rho(params, scenarios), kappa_bounds(params, scenarios)
    else:
        rho, bound = np.empty((len(scenarios), 3)), np.empty(len(scenarios))
        for i, got in enumerate(known):
            if got is not None:
                rho[i], bound[i] = got[1], got[2]
        if new:
            tasks = [scenarios[i] for i in new]
            rho[new], bound[new] = _start_rho(params, tasks), kappa_bounds(params, tasks)
    for i in new:
        task = scenarios[i]
        memo.pop(id(task), None)
        memo[id(task)] = (weakref.ref(task), rho[i].copy(), float(bound[i]))
    while len(memo) > _STARTS_KEPT:  # the oldest first
        del memo[next(iter(memo))]
    return rho, bound


def _start_rho(params: OrthoglideParams, scenarios: list[OrthoglideScenario]) -> np.ndarray:
    """The sliders (M, 3) m at the admissible table position with the lowest kappa at each scenario's first
    point (:func:`~paragym.tasks.orthoglide.start_table_position`)."""
    first = np.array([t.points[0] for t in scenarios])
    kap, r1 = start_table_position(first, params.geometry)
    if not np.all(np.isfinite(kap)):
        raise ValueError("scenario's first point is outside the reachable set")
    return og.inverse(r1, first, params.geometry)[0]


def least_norm_kappa(params: OrthoglideParams, scenarios: list[OrthoglideScenario]) -> np.ndarray:
    """The mean kappa over the path points of each of ``scenarios`` (M,) under the least-norm motion from the
    env's start (:attr:`OrthoglideParams.least_norm`: the zero action in null-space mode, kinematic), run by this
    module's own transition; inf where that motion fails."""
    own = params.least_norm
    n = len(scenarios)
    # the shadow states of the last few numbers of robots are kept on the parameters, so that their kernels are
    # typed once, not at every reset (a millisecond each)
    shadows = own.__dict__.setdefault("_least_norm_shadows", {})
    shadow = shadows.pop(n, None) or OrthoglideState.empty(n)
    shadows[n] = shadow  # the most recent last
    if len(shadows) > 16:
        del shadows[next(iter(shadows))]
    reset(shadow, own, np.arange(n), scenarios)
    shadow.call(_run_to_end, (shadow.kernel_arrays(), own.kernel_args), own)
    return np.where(shadow.failed, np.inf, shadow.mean_kappa)


def kappa_bounds(params: OrthoglideParams, scenarios: list[OrthoglideScenario]) -> np.ndarray:
    """A rung's highest mean kappa of a success on each of ``scenarios``: the rung's ``share`` of the way from 1
    (an isotropic mechanism) to the least-norm motion's mean kappa (:func:`least_norm_kappa`), so that the zero
    action never meets it and a table placed well does."""
    rung = params.rules.rung
    if rung is None:
        raise ValueError("kappa bounds are a rung's: these rules have none")
    share = rung.share
    return 1.0 + share * (least_norm_kappa(params, scenarios) - 1.0)


def step(state: OrthoglideState, params: OrthoglideParams, actions: np.ndarray, active: np.ndarray,
         world: DynamicWorld | None = None) -> None:
    """Move the ``active`` robots (N,) one path point on with ``actions``
    (N, 1) or (N, 3), inside the Box (the env clips), and evaluate them.
    ``world``: the dynamics of the robots (dynamic fidelity): the step's
    joints are the motors' command, and the robot is evaluated where the
    simulation put it (:class:`DynamicWorld`)."""
    if world is None:
        _advance(state, params, actions, active, True, _ALL)
        return
    rows = np.flatnonzero(active)
    k = state.k[rows]
    durations = np.where(k < state.last[rows], state.dt[rows, np.minimum(k, state.dt.shape[1] - 1)], 0.0)
    state.rho[rows] = world.command[rows]  # the controller integrates its own command; the encoders feed the motors
    _advance(state, params, actions, active, True, _COMMAND)
    world.move(state, rows, durations)
    state.broken[rows] = world.gap[rows] > BROKEN_GAP  # what the simulation measured, before the decision
    _advance(state, params, actions, active, True, _EVALUATE)


_ALL, _COMMAND, _EVALUATE = 0, 1, 2  # the kernel's stages: all of a step, its command only, its evaluation only
#: :func:`_run_to_end`'s move and stage for the transition, typed as a call from Python types them (literals would
#: compile the transition a second time)
_MOVE, _WHOLE_STEP = np.bool_(True), np.int64(_ALL)


@njit(cache=True)
def decide(k: int, last: int, failed: bool, mean_kappa: float, bound: float) -> bool:
    """Whether a robot has succeeded: the path's end reached (``k >= last``) with no failure on the way and a
    mean kappa over its path points of at most ``bound`` (inf but on a rung of the ladder). The one
    place the task decides success: the transition calls it for every robot it evaluates, and
    :meth:`~paragym.tasks.orthoglide_task.OrthoglideTask.evaluate` reports what it decided."""
    return k >= last and not failed and mean_kappa <= bound


@njit(cache=True, error_model="numpy")
def _run_to_end(arrays, params):
    """Step every robot with the zero action (null-space mode) until its episode ends: the whole of
    :func:`least_norm_kappa`'s loop in one call, each pass the transition's own kernel over the robots still
    running, so that the numbers are those of stepping them one call a pass."""
    terminated = arrays[11]
    zeros = np.zeros((len(terminated), 1))
    active = ~terminated
    while active.any():
        _advance_kernel(arrays, zeros, active, _MOVE, _WHOLE_STEP, params)
        active = ~terminated
    return 0


def _advance(state: OrthoglideState, params: OrthoglideParams, actions: np.ndarray, rows: np.ndarray,
             move: bool, stage: int = _ALL) -> None:
    actions, rows = np.ascontiguousarray(actions, np.float64), np.ascontiguousarray(rows, np.bool_)
    state.call(_advance_kernel, (state.kernel_arrays(), actions, rows, move, stage, params.kernel_args), params,
               (actions.ndim, rows.ndim))


@njit(cache=True, error_model="numpy")
def _advance_kernel(arrays, actions, rows, move, stage, params):
    """The transition of every robot with ``rows[i]`` (see the module docstring):
    move it if ``move``, then evaluate it at its path point. ``stage``: 0 the
    whole step; 1 the move only (the motors' command); 2 the evaluation only,
    of joints a simulation measured (:class:`DynamicWorld`): J and kappa at
    the tool point those joints give, and the tracking error in either mode.
    ``tracking`` (v1): J and kappa at the tool point in joint-velocity mode too,
    and a tracking error beyond ``track_tolerance`` fails the robot."""
    rho, k, last, path, dt, j, n, kappa, err, failed, reason, terminated, obs, reward, terms, success, kappa_sum, \
        mean_kappa, bound, broken = arrays
    p, lo, hi, joint_mode, max_null_rate, max_joint_rate, w_track, limit_penalty, left_penalty, tracking, \
        track_tolerance = params
    for i in range(len(k)):
        if not rows[i]:
            continue
        if stage != 2 and move and k[i] < last[i]:
            h = dt[i, k[i]]
            if joint_mode:
                for c in range(3):
                    rho[i, c] = rho[i, c] + h * max_joint_rate * actions[i, c]
                k[i] += 1
            else:  # eq 5, then exact tracking
                kk = k[i]
                k[i] += 1
                rho[i, 0], rho[i, 1], rho[i, 2] = og.k_null_space_step(
                    rho[i, 0], (j[i, 0], j[i, 1], j[i, 2], j[i, 3], j[i, 4], j[i, 5]), n[i, 0],
                    (path[i, kk, 2], path[i, kk, 3]), actions[i, 0] * max_null_rate, h,
                    (path[i, k[i], 0], path[i, k[i], 1]), p)
        if stage == 1:
            continue
        px, py = path[i, k[i], 0], path[i, k[i], 1]
        err[i] = 0.0
        track = joint_mode or stage == 2
        tx, ty = px, py
        if track:
            tx, ty = og.k_forward(rho[i, 0], rho[i, 1], rho[i, 2], p)
            err[i] = math.hypot(tx - px, ty - py)
            if stage == 2 or tracking:  # evaluated where the joints put the tool
                px, py = tx, ty
        mode = og.k_inverse(rho[i, 0], px, py, p)[2]
        inside = True
        for c in range(3):
            inside = inside and lo[c] <= rho[i, c] <= hi[c]
        if mode and inside:
            (j[i, 0], j[i, 1], j[i, 2], j[i, 3], j[i, 4], j[i, 5], kappa[i],
             n[i, 0], n[i, 1], n[i, 2]) = og.k_jacobian(rho[i, 0], px, py, p)
            if not kappa[i] < KAPPA_LIMIT:
                failed[i] = True
                if reason[i] == 0:
                    reason[i] = _SINGULAR
        else:
            kappa[i] = math.inf
            j[i, :] = math.nan
            n[i, :] = 0.0
            failed[i] = True
            if reason[i] == 0:
                reason[i] = _MODE if inside else _LIMIT
        if tracking and track and not err[i] <= track_tolerance:
            failed[i] = True
            if reason[i] == 0:
                reason[i] = _TRACKING
        if stage == 2 and tracking and broken[i] and not failed[i]:  # the mechanism came apart
            failed[i], reason[i] = True, _BROKEN
        terminated[i] = failed[i] or k[i] >= last[i]
        kappa_sum[i] += kappa[i]
        mean_kappa[i] = kappa_sum[i] / (k[i] + 1)
        success[i] = decide(k[i], last[i], failed[i], mean_kappa[i], bound[i])
        if failed[i]:  # the reward and its terms (REWARD_TERMS): kappa, tracking, failure
            terms[i, 0], terms[i, 1], terms[i, 2] = 0.0, 0.0, -(limit_penalty + left_penalty * (last[i] - k[i]))
            reward[i] = terms[i, 2]
        else:
            terms[i, 0], terms[i, 2] = -math.log(kappa[i]), 0.0
            terms[i, 1] = -(w_track * err[i] / 0.01 if track else 0.0)
            reward[i] = terms[i, 0] + terms[i, 1]
        px, py = path[i, k[i], 0], path[i, k[i], 1]
        # observation: rho normalised to [-1, 1], the path point now and next, log kappa, n; clipped to +-10
        nxt = min(k[i] + 1, last[i])
        row = (2 * (rho[i, 0] - lo[0]) / (hi[0] - lo[0]) - 1, 2 * (rho[i, 1] - lo[1]) / (hi[1] - lo[1]) - 1,
               2 * (rho[i, 2] - lo[2]) / (hi[2] - lo[2]) - 1, px, py, path[i, nxt, 0], path[i, nxt, 1],
               math.log(kappa[i]) if kappa[i] < 2.2e4 else 10.0, n[i, 0], n[i, 1], n[i, 2])
        for c in range(11):
            v = row[c]
            obs[i, c] = 10.0 if v != v else min(10.0, max(-10.0, v))
        if obs.shape[1] > 11:  # a rung that drives the joints: the tool's offset from the path point (cm)
            for c, v in ((11, 100.0 * (tx - px)), (12, 100.0 * (ty - py))):
                obs[i, c] = 10.0 if v != v else min(10.0, max(-10.0, v))


