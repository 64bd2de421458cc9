"""The hybrid task's transition, written once over N robots (paper 002).

The state of N robots is a dataclass of arrays (:class:`HybridState`);
:func:`reset` starts the chosen rows on their scenarios' nominal paths and
:func:`step` moves the active rows one sample on. Both end in one numba
kernel that solves the robot with the mechanism's own kernel
(:func:`paragym.mechanisms.hybrid.k_solve`) and writes the observation and
the reward, so that the single env (N = 1) and the native vector env run the
same code (:mod:`paragym.envs.hybrid` are shells over this module).

One step, for a robot at sample k of its nominal path (eq 17, u from 0 to 1
in steps of tau) with split Delta and offset o:

* Delta += a_0 * max_delta_step, clipped to [0, 1] (eqs 19-20);
* k += 1; o = a_1..3 * j_bar (m; zero at the last sample, which must be P1);
* the pose nominal[k] + (o, 0, 0, 0) is solved: nine legs, the two
  singularity measures, eq 13 (limits) and eq 14 (free).

Reward: -w_offset |o| / j_bar - w_delta |dDelta| / max_delta_step
- w_singular * sum of max(0, 2 thr - mu) / (2 thr) over both stages
- w_limit * (legs outside their limits). Terminated at u = 1.

Version 1 (``HybridRules.sees_the_end``) keeps the step, the reward, the
success and the end. In v0 a policy sees one step ahead only, and the learned
agents failed exactly the scenarios where the split must move well before the
end for P1's legs to be within their limits. v1 shows where the path ends and
how far that end is from feasible (:data:`OBS_SIZE_V1`):

* P1, and P1 solved at the current Delta: its nine strokes and both measures
  (a second :func:`~paragym.mechanisms.hybrid.k_solve` per robot-step);
* P1's stroke excess e(Delta) = sum over the legs of how far each stroke is
  beyond its limits (in units of the stroke range, L_max - L_min, halved),
  times 10, and its change if Delta moved one ``max_delta_step`` up or down,
  times 100 (two more leg-only solves).

``w_end`` > 0 (default 0) adds the potential-based shaping
``w_end * (phi(s') - phi(s))`` with ``phi = -e(Delta)`` at P1, and 0 at the
end (Ng, Harada and Russell, 1999): over an episode it sums to
``w_end * e(0.5)``, a constant of the scenario, so it moves credit earlier
without changing which policies are best. It was tried and made PPO worse
(``baselines/ABLATION.md``), so it is off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from paragym.kernels import KernelArrays, KernelOwner
from paragym.mechanisms import hybrid
from paragym.sim import mujoco_sim
from paragym.tasks import hybrid as scenarios_module
from paragym.tasks.base import (
    check_choice,
    check_control_period,
    check_instance,
    check_number,
    refuse_unknown,
    renamed,
)
from paragym.tasks.hybrid import HybridScenario, nominal_rows
from paragym.tasks.hybrid_worlds import DynamicWorld
from paragym.trajectories import nominal_path

__all__ = ["FAILURES", "LADDER_RULES", "OBS_SIZE", "OBS_SIZE_V1", "POSE_SCALE", "REWARD_TERMS", "RULES",
           "SPLIT_LADDER_RULES", "SPLIT_LADDER_RULES_V2", "HybridParams", "HybridRules", "HybridState", "decide",
           "reset", "step"]

#: why a robot's episode failed (``HybridState.reason``, the first reason; 0: it has not)
FAILURES = (None, "broken", "tracking", "leg limit", "singular")
_BROKEN, _TRACKING, _LIMIT, _SINGULAR = 1, 2, 3, 4
#: the reward's terms, each in the info as ``reward_<name>``: the offset from the path, the split's change, the
#: closeness to a singularity, the legs out of their limits, v1's shaping toward a feasible end; their sum is the
#: reward
REWARD_TERMS = ("offset", "delta", "singular", "limit", "end_shaping")

POSE_SCALE = np.array([0.1, 0.1, 0.1, 0.5, 0.5, 0.5])  # m, m, m, rad, rad, rad: observation units
OBS_SIZE = 1 + 6 + 6 + 1 + 9 + 2 + 3
#: v1: v0's observation, then P1 (6), P1's strokes (9) and measures (2) at the current Delta, and its
#: stroke excess with the excess's change one Delta step up and down (3)
OBS_SIZE_V1 = OBS_SIZE + 6 + 9 + 2 + 3


class Weights(NamedTuple):
    """The numbers the step's kernel reads, by name (numba compiles a NamedTuple of floats): the action's
    scales (Delta per step, j_bar in m), the reward's weights, the stroke limits (m), the singularity
    threshold and v1's end-shaping weight."""

    max_delta_step: float
    j_bar: float
    w_offset: float
    w_delta: float
    w_singular: float
    w_limit: float
    l_min: float
    l_max: float
    singularity_threshold: float
    w_end: float

@dataclass(frozen=True)
class HybridRules:
    """The rules of one version of the task (the env id's class holds one of :data:`RULES`).

    Attributes:
        version: the N of ``-vN``.
        sees_the_end: the observation shows P1 and how far it is from feasible (:data:`OBS_SIZE_V1`), and
            ``w_end`` is an argument.
        strict_dynamics: in dynamic fidelity E's orientation is tracked too (``track_angle_tolerance``), a
            broken mechanism ends the episode as a failure, and a ``control_period`` the physics step does
            not divide is refused (else simulated rounded, with a warning).
        rung: a rung of a difficulty ladder (one of :data:`paragym.tasks.hybrid.LADDER` or
            :data:`~paragym.tasks.hybrid.SPLIT_LADDER`): its generator draws the "random" scenario's pairs of
            poses; None: a version of the task.
        split_only: the action is the split's rate alone (shape (1,)): E stays on its nominal path (no offset).
    """

    version: int
    sees_the_end: bool
    strict_dynamics: bool
    rung: scenarios_module.HybridRung | scenarios_module.SplitRung | None = None
    split_only: bool = False


#: the engines of the dynamic fidelity (the env's ``engine`` argument): both of :mod:`paragym.sim.mujoco_sim`
ENGINES = mujoco_sim.ENGINES
#: the rules of HybridSingularityFree-v0, -v1 and -v2
RULES = {0: HybridRules(0, sees_the_end=False, strict_dynamics=False),
         1: HybridRules(1, sees_the_end=True, strict_dynamics=False),
         2: HybridRules(2, sees_the_end=True, strict_dynamics=True)}
#: the rules of the ladder's rungs, HybridSingularityFree-Easy, -Medium and -Hard (v0 each): v2's, on the rung's
#: pairs of poses
LADDER_RULES = {k: HybridRules(0, sees_the_end=True, strict_dynamics=True, rung=rung)
                for k, rung in enumerate(scenarios_module.LADDER)}
#: the rules of the ladder v1's rungs, HybridSingularityFree-Easy, -Medium and -Hard (v1 each): v2's, with the
#: split as the only lever, on the rung's pairs of poses (:data:`paragym.tasks.hybrid.SPLIT_LADDER`)
SPLIT_LADDER_RULES = {k: HybridRules(1, sees_the_end=True, strict_dynamics=True, rung=rung, split_only=True)
                      for k, rung in enumerate(scenarios_module.SPLIT_LADDER)}
#: the rules of the ladder v2's rungs (-Easy-v2 ...): the ladder v1's, on pairs whose certificate keeps every stroke
#: 1 mm inside its limits (:data:`paragym.tasks.hybrid.SPLIT_LADDER_V2`)
SPLIT_LADDER_RULES_V2 = {k: HybridRules(2, sees_the_end=True, strict_dynamics=True, rung=rung, split_only=True)
                         for k, rung in enumerate(scenarios_module.SPLIT_LADDER_V2)}


@dataclass(frozen=True)
class HybridParams(KernelOwner):
    """The env's arguments (see the env's docstring), checked by :meth:`from_kwargs`."""

    max_delta_step: float = 0.05
    j_bar: float = 0.02
    w_offset: float = 0.1
    w_delta: float = 0.05
    w_singular: float = 1.0
    w_limit: float = 1.0
    geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY
    tau: float = 0.01
    #: v1's observation of the path's end (:attr:`HybridRules.sees_the_end`)
    sees_the_end: bool = False
    w_end: float = 0.0
    scenario: Any = "random"
    fidelity: str = "kinematic"
    dynamics: Any = None
    control_period: float = 0.05
    track_tolerance: float = 0.005
    track_angle_tolerance: float = math.radians(1.0)
    rules: HybridRules = RULES[0]
    #: the dynamic fidelity's engine: None (PyBullet) or MuJoCo's settings (:mod:`paragym.sim.mujoco_sim`)
    engine: Any = None

    @classmethod
    def from_kwargs(cls, rules: HybridRules, scenario: Any = "random", max_delta_step: float = 0.05,
                    j_bar: float = 0.02, w_offset: float = 0.1, w_delta: float = 0.05, w_singular: float = 1.0,
                    w_limit: float = 1.0, geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY,
                    tau: float = 0.01, w_end: float | None = None, fidelity: str = "kinematic",
                    dynamics: Any = None, control_period: float = 0.05, track_tolerance: float = 0.005,
                    track_angle_tolerance: float | None = None, engine: Any = "pybullet",
                    **unknown: Any) -> HybridParams:
        """The env's keyword arguments, checked: the one place they are."""
        from paragym.sim.hybrid_dynamic import HybridDynamics
        from paragym.sim.mujoco_sim import check_engine

        refuse_unknown(unknown, (), "HybridSingularityFree")
        check_choice("fidelity", fidelity, ("kinematic", "dynamic"))
        check_instance("dynamics", dynamics, HybridDynamics)
        control_period = check_number("control_period", control_period)
        track_tolerance = check_number("track_tolerance", track_tolerance)
        scenario = scenarios_module.resolve_scenario(scenario)
        if not rules.sees_the_end and w_end is not None:
            raise ValueError("w_end (the shaping toward a feasible end) is an argument of HybridSingularityFree-v1")
        w_end = check_number("w_end", 0.0 if w_end is None else w_end, strict=False)
        for name, value in (("max_delta_step", max_delta_step), ("j_bar", j_bar), ("tau", tau)):
            check_number(name, value)
        if track_angle_tolerance is not None and not rules.strict_dynamics:
            raise ValueError("track_angle_tolerance is an argument of paragym/HybridSingularityFree-v2")
        angle = check_number("track_angle_tolerance",
                             math.radians(1.0) if track_angle_tolerance is None else track_angle_tolerance,
                             unit=" (rad)")
        if fidelity == "dynamic":
            dynamics = dynamics or HybridDynamics.fast()
            check_control_period(control_period, dynamics.time_step, refuse=rules.strict_dynamics,
                                 later="paragym/HybridSingularityFree-v2")
        engine = check_engine(engine, ENGINES, fidelity, alone=True)
        if engine is not None:  # a new fidelity: nothing released to keep
            check_control_period(control_period, engine.time_step, refuse=True)
        return cls(float(max_delta_step), float(j_bar), float(w_offset), float(w_delta), float(w_singular),
                   float(w_limit), geometry, float(tau), rules.sees_the_end, w_end, scenario, fidelity,
                   dynamics, control_period, track_tolerance, angle, rules, engine)

    @property
    def obs_size(self) -> int:
        """The observation's length in this version."""
        return OBS_SIZE_V1 if self.sees_the_end else OBS_SIZE

    @cached_property
    def kernel_args(self) -> tuple:
        """The numbers the kernel takes (made once: a step must not rebuild them)."""
        g = self.geometry
        weights = Weights(float(self.max_delta_step), float(self.j_bar), float(self.w_offset), float(self.w_delta),
                          float(self.w_singular), float(self.w_limit), float(g.l_min), float(g.l_max),
                          float(g.singularity_threshold), float(self.w_end))
        return (hybrid.kernel_consts(g), weights, POSE_SCALE)


@dataclass
class HybridState(KernelArrays):
    """N robots: where they are on their nominal paths (``u`` (K,) is shared:
    every path has the same samples), the split, the offset, what the last
    solve found, and the observation and reward of their last step."""

    #: the arrays the kernel take, in their order (:class:`paragym.kernels.KernelArrays`)
    KERNEL_FIELDS = ("u", "nominal", "k", "delta", "d_delta", "offset", "all_free", "pose", "lengths", "mu_h",
                     "mu_t", "within", "free", "terminated", "obs", "reward", "phi", "reason", "terms",
                     "success", "tracked", "broken")

    u: np.ndarray
    nominal: np.ndarray
    k: np.ndarray
    delta: np.ndarray
    d_delta: np.ndarray
    offset: np.ndarray
    all_free: np.ndarray
    pose: np.ndarray
    lengths: np.ndarray
    mu_h: np.ndarray
    mu_t: np.ndarray
    within: np.ndarray
    free: np.ndarray
    terminated: np.ndarray
    obs: np.ndarray
    reward: np.ndarray
    phi: np.ndarray
    #: the first reason each robot's episode failed (an index into :data:`FAILURES`; 0: none yet)
    reason: np.ndarray
    terms: np.ndarray
    scenarios: list[HybridScenario | None] = field(default_factory=list)
    #: what :meth:`~paragym.tasks.base.Task.evaluate` decided of each robot (its buffers, rewritten each call)
    success: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)
    evaluation: Any = field(default=None, repr=False, compare=False)
    #: what the simulation measured of each robot's last move, written before the transition decides (dynamic
    #: fidelity, :class:`~paragym.tasks.hybrid_worlds.DynamicWorld`): E tracked its command, the mechanism whole
    tracked: np.ndarray = field(default_factory=lambda: np.ones(0, bool), repr=False, compare=False)
    broken: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)


    @classmethod
    def empty(cls, n: int, params: HybridParams) -> HybridState:
        """N robots at rest, before their first reset."""
        tau, obs_size = params.tau, params.obs_size
        u = nominal_path(np.zeros(6), np.zeros(6), tau)[0]
        return cls(u=u, nominal=np.zeros((n, len(u), 6)), k=np.zeros(n, np.int64), delta=np.full(n, 0.5),
                   d_delta=np.zeros(n), offset=np.zeros((n, 3)), all_free=np.ones(n, bool), pose=np.zeros((n, 6)),
                   lengths=np.zeros((n, 9)), mu_h=np.zeros(n), mu_t=np.zeros(n), within=np.zeros(n, bool),
                   free=np.zeros(n, bool), terminated=np.zeros(n, bool), obs=np.zeros((n, obs_size), np.float32),
                   reward=np.zeros(n), phi=np.zeros(n), reason=np.zeros(n, np.int64),
                   terms=np.zeros((n, len(REWARD_TERMS))), scenarios=[None] * n,
                   success=np.zeros(n, bool), tracked=np.ones(n, bool), broken=np.zeros(n, bool))


def reset(state: HybridState, params: HybridParams, rows: np.ndarray, scenarios: list[HybridScenario]) -> None:
    """Start ``rows`` on ``scenarios`` (checked ones: :func:`paragym.tasks.hybrid.draw_scenarios`)
    at u = 0, Delta = 0.5, no offset; then solve them."""
    for i, scenario in zip(rows, scenarios, strict=True):
        state.scenarios[i] = scenario
    p0 = np.array([sc.p0 for sc in scenarios])
    p1 = np.array([sc.p1 for sc in scenarios])
    state.nominal[rows] = nominal_rows(p0, p1, params.tau)
    state.k[rows], state.delta[rows], state.d_delta[rows] = 0, 0.5, 0.0
    state.offset[rows], state.all_free[rows], state.reason[rows] = 0.0, True, 0
    mask = np.zeros(len(state.k), bool)
    mask[rows] = True
    _advance(state, params, np.zeros((len(state.k), 4)), mask, False)


def step(state: HybridState, params: HybridParams, actions: np.ndarray, active: np.ndarray,
         world: DynamicWorld | None = None) -> None:
    """Move the ``active`` robots (N,) one sample on with ``actions`` (N, 4), or (N, 1) where the rules are
    ``split_only``, inside the Box (the env clips), and solve them. ``world``: the dynamics
    of one robot (dynamic fidelity): the step's commanded pose is solved for
    its strokes, the simulated actuators chase them, and the robot is then
    evaluated where the simulation put it (:class:`DynamicWorld`; N robots in MuJoCo alone)."""
    if params.rules.split_only:  # the split's rate alone: E stays on its path (offset 0)
        actions = np.concatenate([actions, np.zeros((len(actions), 3))], axis=1)
    if world is None:
        _advance(state, params, actions, active, True, _ALL)
        return
    _advance(state, params, actions, active, True, _COMMAND)
    rows = np.flatnonzero(active)
    world.move(state, rows)
    state.tracked[rows], state.broken[rows] = world.tracked[rows], world.broken[rows]  # measured, then decided
    _advance(state, params, actions, active, True, _EVALUATE)


_ALL, _COMMAND, _EVALUATE = 0, 1, 2  # the kernel's stages: all of a step, its command only, its evaluation only


@njit(cache=True)
def decide(terminated: bool, all_free: bool) -> bool:
    """Whether a robot has succeeded: u = 1 reached with every pose of the episode free (eq 14; in dynamic
    fidelity tracked, and the mechanism whole in v2). The one place the task decides success: the transition
    calls it for every robot it evaluates, and :meth:`~paragym.tasks.hybrid_task.HybridTask.evaluate` reports
    what it decided."""
    return terminated and all_free


def _advance(state: HybridState, params: HybridParams, actions: np.ndarray, rows: np.ndarray,
             move: bool, stage: int = _ALL) -> None:
    actions, rows = np.ascontiguousarray(actions, np.float64), np.ascontiguousarray(rows, np.bool_)
    state.call_split(_advance_kernel, (state.kernel_arrays(), actions, rows, move, params.sees_the_end, stage,
                                       *params.kernel_args), 2, params, (actions.ndim, rows.ndim))


@njit(cache=True, error_model="numpy", nogil=True)
def _advance_kernel(arrays, actions, rows, move, sees_the_end, stage, consts, w, scale):
    """The transition of every robot with ``rows[i]`` (module docstring). ``arrays``: the state's, in
    ``KERNEL_FIELDS``' order; ``consts``: the geometry, :func:`paragym.mechanisms.hybrid.kernel_consts`.
    ``w``: max_delta_step, j_bar, w_offset, w_delta, w_singular, w_limit,
    L_min, L_max, singularity threshold, w_end (v1). ``stage``: 0 the whole
    step; 1 the command only (move and solve the commanded pose's strokes);
    2 the evaluation only, of the pose, strokes, measures and offset a
    simulation wrote into the state (dynamic fidelity: :class:`DynamicWorld`)."""
    u, nominal, k, delta, d_delta, offset, all_free, pose, lengths, mu_h, mu_t, within, free, terminated, obs, \
        reward, phi, reason, terms, success, tracked, broken = arrays
    base, plat, top, axes, tri_base, pinv_t, home, sc = consts
    last = len(u) - 1
    work = np.empty((7, 6, 6))
    paired = stage == 0 and sees_the_end  # the whole step, and the observation shows P1
    mu_h_end, mu_t_end = 0.0, 0.0
    size = obs.shape[1]
    row = np.empty(size)  # one robot's observation before the clip, reused
    end_lengths = np.empty(9)
    for i in range(len(k)):
        if not rows[i]:
            continue
        if stage != 2:
            if move and k[i] < last:
                new = min(1.0, max(0.0, delta[i] + actions[i, 0] * w.max_delta_step))
                d_delta[i] = new - delta[i]
                delta[i] = new
                k[i] += 1
                for c in range(3):
                    offset[i, c] = 0.0 if k[i] == last else actions[i, 1 + c] * w.j_bar
            for c in range(6):
                pose[i, c] = nominal[i, k[i], c] + (offset[i, c] if c < 3 else 0.0)
            if paired:  # the pose and P1 at the same split: their four measures in one call
                mu_h[i], mu_t[i], mu_h_end, mu_t_end = hybrid.k_solve_pair(
                    pose[i], nominal[i, last], delta[i], base, plat, top, axes, tri_base, pinv_t, home, sc,
                    lengths[i], end_lengths, work)
            else:
                mu_h[i], mu_t[i] = hybrid.k_solve(pose[i], delta[i], base, plat, top, axes, tri_base, pinv_t, home,
                                                  sc, hybrid.MEASURES, lengths[i], work)
            if stage == 1:
                continue
        out = 0
        for c in range(9):
            if lengths[i, c] < w.l_min or lengths[i, c] > w.l_max:
                out += 1
        within[i] = out == 0
        free[i] = within[i] and mu_h[i] >= w.singularity_threshold and mu_t[i] >= w.singularity_threshold
        all_free[i] = all_free[i] and free[i]
        if stage == 2:  # what the simulation measured: E off its command, or the mechanism broken
            if reason[i] == 0:  # the first reason the episode fails: the dynamics' first
                reason[i] = _BROKEN if broken[i] else 0 if tracked[i] else _TRACKING
            all_free[i] = all_free[i] and tracked[i] and not broken[i]
        if move and reason[i] == 0:  # the first reason the episode fails (a dynamic one was noted before)
            reason[i] = _LIMIT if not within[i] else 0 if free[i] else _SINGULAR
        at_end = k[i] >= last
        terminated[i] = at_end or (stage == 2 and broken[i])  # a broken mechanism ends the episode as a failure
        success[i] = decide(terminated[i], all_free[i])
        thr = 2 * w.singularity_threshold
        close = max(0.0, thr - mu_h[i]) / thr + max(0.0, thr - mu_t[i]) / thr
        norm = math.sqrt(offset[i, 0] * offset[i, 0] + offset[i, 1] * offset[i, 1] + offset[i, 2] * offset[i, 2])
        # the reward and its terms (REWARD_TERMS): offset, delta, singular, limit, end shaping (v1, below)
        terms[i, 0], terms[i, 1] = -w.w_offset * norm / w.j_bar, -(w.w_delta * abs(d_delta[i]) / w.max_delta_step)
        terms[i, 2], terms[i, 3], terms[i, 4] = -(w.w_singular * close), -(w.w_limit * out), 0.0
        reward[i] = terms[i, 0] + terms[i, 1] + terms[i, 2] + terms[i, 3]
        # observation: u, the nominal pose now and next, Delta, the strokes, both measures, the offset
        nxt = min(k[i] + 1, last)
        row[0] = u[k[i]]
        for c in range(6):
            row[1 + c] = nominal[i, k[i], c] / scale[c]
            row[7 + c] = nominal[i, nxt, c] / scale[c]
        row[13] = delta[i]
        for c in range(9):
            row[14 + c] = 2 * (lengths[i, c] - w.l_min) / (w.l_max - w.l_min) - 1
        row[23], row[24] = mu_h[i], mu_t[i]
        for c in range(3):
            row[25 + c] = offset[i, c] / w.j_bar
        if sees_the_end:  # where the path ends: P1 solved at the current split, its excess, the shaping
            if not paired:
                mu_h_end, mu_t_end = hybrid.k_solve(nominal[i, last], delta[i], base, plat, top, axes, tri_base,
                                                    pinv_t, home, sc, hybrid.MEASURES, end_lengths, work)
            excess = _excess(end_lengths, w)
            new_phi = 0.0 if at_end else -excess
            if move:
                terms[i, 4] = w.w_end * (new_phi - phi[i])
                reward[i] += terms[i, 4]
            phi[i] = new_phi
            for c in range(6):
                row[28 + c] = nominal[i, last, c] / scale[c]
            for c in range(9):
                row[34 + c] = 2 * (end_lengths[c] - w.l_min) / (w.l_max - w.l_min) - 1
            row[43], row[44] = mu_h_end, mu_t_end
            row[45] = 10 * excess
            for j, sign in ((46, 1.0), (47, -1.0)):
                moved = min(1.0, max(0.0, delta[i] + sign * w.max_delta_step))
                hybrid.k_solve(nominal[i, last], moved, base, plat, top, axes, tri_base, pinv_t, home, sc,
                               hybrid.LEGS_ONLY, end_lengths, work)
                row[j] = 100 * (_excess(end_lengths, w) - excess)
        for c in range(size):
            obs[i, c] = min(10.0, max(-10.0, row[c]))


@njit(cache=True)
def _excess(lengths, w):
    """How far the nine strokes are beyond their limits, summed, in units of half the stroke range."""
    total = 0.0
    for c in range(9):
        x = 2 * (lengths[c] - w.l_min) / (w.l_max - w.l_min) - 1
        total += max(0.0, abs(x) - 1.0)
    return total

#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = renamed(__name__, {"HybridTaskState": "HybridState"})


