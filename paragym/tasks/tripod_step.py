"""The mobile tripod task's transition, written once over N robots (paper 004).

The state of N robots (:class:`TripodState`) is their drives
(:class:`paragym.sim.tripod_drive.DriveState`) and the agent's estimates.
:func:`reset` starts the chosen rows' drives and :func:`step` advances the
active rows one sample, in one numba kernel that runs the drive's physics
(:func:`paragym.sim.tripod_drive.k_drive_step`) and then the estimate, the
observation and the reward, so that the single env (N = 1) and the native
vector env run the same code (:mod:`paragym.envs.tripod` are shells
over this module).

One step: the drive advances a sample; the estimate moves by the odometric
increment plus the agent's correction (action times ``max_correction``), its
height from the terrain; the encoders read the true eta plus noise. Reward:
-10 (mean unit error + plate centre error), m, the estimate's horizontal unit
positions against the true ones. Terminated at the drive's end.

Version 1 (``TripodRules.trust_action``) changes what the agent does and
sees and earns; the drive and the end are v0's. Before the drive advances,
each unit u of the estimate moves the fraction ``trust_rate * clip(a_u, 0, 1)``
of the way
to where the paper's correction would put it (section 3,
:func:`paragym.mechanisms.tripod.k_relocate`: on the circles about the
other two units with the encoder distances of eq 4, exponentially smoothed
with ``smoothing`` per sample as the reference smooths them); then the whole
estimate moves by the odometric increment. A zero or negative action is
odometry alone, and a correction is never accumulated by the action itself.
The observation is in the robot's frame (:data:`OBS_SIZE_V1`). The reward
is v0's minus what odometry alone would earn at the same sample: the
drift that no estimator controls drops out of it, so the optimal policy is
v0's and the zero action earns 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from numba import njit

from paragym.kernels import KernelArrays, KernelOwner
from paragym.mechanisms import tripod as mt
from paragym.sim import mujoco_sim
from paragym.sim.tripod_drive import DriveState, k_drive_step, k_terrain
from paragym.tasks import tripod as scenarios_module
from paragym.tasks.base import (
    check_choice,
    check_control_period,
    check_instance,
    check_number,
    refuse_unknown,
    renamed,
)
from paragym.tasks.tripod import TripodScenario
from paragym.tasks.tripod_worlds import DynamicWorld

__all__ = ["FAILURES", "OBS_SIZE", "OBS_SIZE_V1", "OFFSET_SCALE", "POS_SCALE", "RESIDUAL_SCALE", "REWARD_TERMS",
           "LADDER_RULES", "RULES", "TripodParams", "TripodRules", "TripodState", "decide", "reset", "step"]

#: why a robot's episode failed (0: it has not)
FAILURES = (None, "folded")
#: the reward's terms, each in the info as ``reward_<name>``: the estimate's error, -10 (mean unit error + plate
#: centre error), and (v1's relative reward) what odometry alone would lose; their sum is the reward
REWARD_TERMS = ("estimate", "odometry")

OBS_SIZE = 9 + 3 + 3 + 6
POS_SCALE = 10.0  # m per observation unit
#: v1: the residuals of the estimate's and the odometry's inter-unit distances against the smoothed encoder
#: distances (3 + 3, / RESIDUAL_SCALE), each unit's estimate minus its odometry in the robot's frame (6, /
#: OFFSET_SCALE), the drive's progress t / duration (1), the measured eta (3, rad)
OBS_SIZE_V1 = 3 + 3 + 6 + 1 + 3
RESIDUAL_SCALE = 0.05  # m per observation unit
OFFSET_SCALE = 0.1  # m per observation unit


@dataclass(frozen=True)
class TripodRules:
    """The rules of one version of the task (the env id's class holds one of :data:`RULES`).

    Attributes:
        version: the N of ``-vN``.
        trust_action: the action is per unit trust in the paper's correction, the observation is in the
            robot's frame and the reward is relative to odometry (:data:`OBS_SIZE_V1`); ``trust_rate`` and
            ``relative_reward`` are arguments. Else v0's correction, observation and reward.
        fold_ends: a folded mechanism (a leg at or past horizontal, true eta <= 0) ends the episode as a
            failure, and in dynamic fidelity a physics step that does not divide the sample is refused (else
            simulated rounded, with a warning).
        rung: a rung of the difficulty ladder (one of :data:`paragym.tasks.tripod.LADDER`): its drives are
            the "random" scenario, and in dynamic fidelity the push's force is calibrated to its distance
            (:data:`paragym.tasks.tripod_worlds.PUSH_CALIBRATION`); None: a version of the task.
        converged: the dynamic fidelity's default physics is :meth:`TripodDynamics.converged` (friction that holds
            below its limit) and each unit starts on its wheels (``on_wheels`` of
            :meth:`~paragym.sim.tripod_dynamic.TripodDynamicScene.reset`: none inside the terrain); else
            :class:`TripodDynamics`' own default (30 solver iterations) and the released start.
    """

    version: int
    trust_action: bool
    fold_ends: bool
    rung: scenarios_module.TripodRung | None = None
    converged: bool = False


#: the engines of the dynamic fidelity (the env's ``engine`` argument): both of :mod:`paragym.sim.mujoco_sim`
ENGINES = mujoco_sim.ENGINES
#: the rules of MobileTripodOdometry-v0, -v1, -v2 and -v3
RULES = {0: TripodRules(0, trust_action=False, fold_ends=False), 1: TripodRules(1, trust_action=True, fold_ends=False),
         2: TripodRules(2, trust_action=True, fold_ends=True),
         3: TripodRules(3, trust_action=True, fold_ends=True, converged=True)}
#: the rules of the ladder's rungs, MobileTripodOdometry-Easy, -Medium and -Hard (v0 each): v2's, on the rung's drives
LADDER_RULES = {k: TripodRules(0, trust_action=True, fold_ends=True, rung=rung)
                for k, rung in enumerate(scenarios_module.LADDER)}
#: the rules of the ladder v1's rungs (-Easy-v1 ...): the ladder v0's, at v3's converged physics
LADDER_RULES_V1 = {k: TripodRules(1, trust_action=True, fold_ends=True, rung=rung, converged=True)
                   for k, rung in enumerate(scenarios_module.LADDER)}


@dataclass(frozen=True)
class TripodParams(KernelOwner):
    """The env's arguments (see the env's docstring), checked by :meth:`from_kwargs`."""

    encoder_noise: float = math.radians(1.0)
    max_correction: float = 0.05
    geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY
    #: v1's action, observation and reward (:attr:`TripodRules.trust_action`)
    trust_action: bool = False
    smoothing: float = 0.1
    trust_rate: float = 0.2
    relative_reward: bool = True
    #: v2: a folded mechanism (a leg at or past horizontal, true eta <= 0) ends the episode as a failure
    fold_ends: bool = False
    success_error: float = 0.05
    scenario: Any = "random"
    fidelity: str = "kinematic"
    dynamics: Any = None
    rules: TripodRules = RULES[0]
    #: the dynamic fidelity's engine: None (PyBullet) or MuJoCo's settings (:mod:`paragym.sim.mujoco_sim`)
    engine: Any = None

    @classmethod
    def from_kwargs(cls, rules: TripodRules, scenario: Any = "random", encoder_noise: float = math.radians(1.0),
                    max_correction: float = 0.05, success_error: float = 0.05,
                    geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY, trust_rate: float | None = None,
                    relative_reward: bool | None = None, fidelity: str = "kinematic", dynamics: Any = None,
                    engine: Any = "pybullet", **unknown: Any) -> TripodParams:
        """The env's keyword arguments, checked: the one place they are. A custom drive is checked at reset."""
        from paragym.sim.mujoco_sim import check_engine
        from paragym.sim.tripod_dynamic import TripodDynamics

        refuse_unknown(unknown, (), "MobileTripodOdometry")
        engine = check_engine(engine, ENGINES, fidelity)
        check_choice("fidelity", fidelity, ("kinematic", "dynamic"))
        check_instance("dynamics", dynamics, TripodDynamics)
        if fidelity == "dynamic" and dynamics is None and rules.converged:
            dynamics = TripodDynamics.converged()
        if not rules.trust_action and (trust_rate is not None or relative_reward is not None):
            raise ValueError("trust_rate and relative_reward are v1 arguments: use paragym/MobileTripodOdometry-v1")
        trust_rate = check_number("trust_rate", 0.2 if trust_rate is None else trust_rate, high=1.0)
        relative_reward = True if relative_reward is None else relative_reward
        if isinstance(scenario, str):
            scenarios_module.resolve_scenario(scenario)
        encoder_noise = check_number("encoder_noise", encoder_noise, strict=False, unit=" rad")
        if fidelity == "dynamic":
            check_control_period(DriveState.empty(1).dt, (dynamics or TripodDynamics()).time_step,
                                 refuse=rules.fold_ends, later="paragym/MobileTripodOdometry-v2")
        return cls(encoder_noise, float(max_correction), geometry, rules.trust_action,
                   trust_rate=trust_rate, relative_reward=bool(relative_reward), fold_ends=rules.fold_ends,
                   success_error=success_error, scenario=scenario, fidelity=fidelity, dynamics=dynamics, rules=rules,
                   engine=engine)

    @cached_property
    def kernel_args(self) -> tuple[tuple[float, bool], tuple[float, float, bool]]:
        """What the kernels read of the parameters (made once): the success error and whether a fold ends the
        episode; v1's smoothing, trust rate and relative reward."""
        return ((float(self.success_error), bool(self.fold_ends)),
                (float(self.smoothing), float(self.trust_rate), bool(self.relative_reward)))

    @property
    def obs_size(self) -> int:
        return OBS_SIZE_V1 if self.trust_action else OBS_SIZE

    @property
    def action_size(self) -> int:
        return 3 if self.trust_action else 6


@dataclass
class TripodState(KernelArrays):
    """N robots: their drives, the agent's estimates of the units (N, 3, 3),
    the encoders' readings now and at the last sample (N, 3), the smoothed
    encoder distances (N, 3; v1), the errors, and the observation and reward
    of their last step."""

    #: the arrays the kernels take, in their order (:class:`paragym.kernels.KernelArrays`)
    KERNEL_FIELDS = ("estimate", "eta_read", "last_eta", "smoothed", "unit_error", "plate_error", "terminated", "obs",
                     "reward", "terms", "folded", "success", "failure")

    drive: DriveState
    estimate: np.ndarray
    eta_read: np.ndarray
    last_eta: np.ndarray
    smoothed: np.ndarray
    unit_error: np.ndarray
    plate_error: np.ndarray
    terminated: np.ndarray
    obs: np.ndarray
    reward: np.ndarray
    #: whether the mechanism has folded in this episode (a leg at or past horizontal: true eta <= 0)
    folded: np.ndarray
    terms: np.ndarray
    #: what :meth:`~paragym.tasks.base.Task.evaluate` decided of each robot (its buffers, rewritten each call)
    success: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), repr=False, compare=False)
    evaluation: Any = field(default=None, repr=False, compare=False)
    failure: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False, compare=False)


    @classmethod
    def empty(cls, n: int, params: TripodParams) -> TripodState:
        """N robots, before their first reset."""
        obs_size = params.obs_size
        return cls(drive=DriveState.empty(n), estimate=np.zeros((n, 3, 3)), eta_read=np.zeros((n, 3)),
                   last_eta=np.zeros((n, 3)), smoothed=np.zeros((n, 3)), unit_error=np.zeros(n),
                   plate_error=np.zeros(n), terminated=np.zeros(n, bool), obs=np.zeros((n, obs_size), np.float32),
                   reward=np.zeros(n), folded=np.zeros(n, bool), terms=np.zeros((n, len(REWARD_TERMS))),
                   success=np.zeros(n, bool),
                   failure=np.zeros(n, np.int64))

    @property
    def scenarios(self) -> list[TripodScenario | None]:
        return self.drive.scenarios


def reset(state: TripodState, params: TripodParams, rows: np.ndarray, scenarios: list[TripodScenario],
          rngs: list[np.random.Generator]) -> None:
    """Start ``rows`` on checked ``scenarios`` (:func:`paragym.tasks.tripod.draw_scenarios`),
    each drawing its drive's random numbers from its generator; every estimate
    starts exact."""
    for i, scenario, rng in zip(rows, scenarios, rngs, strict=True):
        state.drive.start(int(i), scenario, rng, params.geometry, params.encoder_noise)
        state.estimate[i] = state.drive.odometry[i]
    mask = np.zeros(len(state.estimate), bool)
    mask[rows] = True
    state.smoothed[rows] = np.nan  # v1: the first reading starts the average
    state.folded[rows] = False
    _advance(state, params, np.zeros((len(state.estimate), params.action_size)), mask, False)
    state.last_eta[rows] = state.eta_read[rows]


def step(state: TripodState, params: TripodParams, actions: np.ndarray, active: np.ndarray,
         world: DynamicWorld | None = None) -> None:
    """Advance the ``active`` robots (N,) one sample with ``actions`` inside
    the Box (the env clips): corrections (N, 6) in v0, trust in the paper's
    correction per unit (N, 3) in v1. ``world``: the dynamics of one robot
    (dynamic fidelity), which advances the drive before the estimate moves
    (:class:`DynamicWorld`)."""
    if world is None:
        _advance(state, params, actions, active, True)
    else:
        moved = world.move(state)
        _advance(state, params, actions, active, True, moved, world.increment)


_NONE = np.zeros(0, bool)
_NO_INCREMENT = np.zeros((0, 3, 2))


def _advance(state: TripodState, params: TripodParams, actions: np.ndarray, rows: np.ndarray,
             move: bool, moved: np.ndarray = _NONE, increment: np.ndarray = _NO_INCREMENT) -> None:
    """``moved`` and ``increment``: a dynamic world advanced the drives already (which of them, and each
    unit's odometric increment (N, 3, 2)); empty, the kernel advances them (:func:`k_drive_step`)."""
    d = state.drive
    external = len(moved) > 0
    actions, rows = np.ascontiguousarray(actions, np.float64), np.ascontiguousarray(rows, np.bool_)
    moved, increment = np.ascontiguousarray(moved, np.bool_), np.ascontiguousarray(increment, np.float64)
    geo = mt.kernel_consts(params.geometry)
    judge, trust = params.kernel_args
    key = (actions.ndim, rows.ndim, moved.ndim, increment.ndim)
    if params.trust_action:
        state.call(_advance_v1_kernel, (state.kernel_arrays(), actions, rows, move, trust, external, moved, increment,
                                        d.steps, d.noise, geo, d.kernel_arrays(), judge), params, key)
        return
    state.call(_advance_kernel, (state.kernel_arrays(), actions, rows, move, external, moved, increment,
                                 params.max_correction, d.steps, d.noise, geo, d.kernel_arrays(), judge), params, key)


@njit(cache=True, error_model="numpy")
def _errors(units, true):
    """The mean horizontal unit error and the plate centre's error (m) of ``units`` (3, 3) against ``true``."""
    dx0, dy0 = units[0, 0] - true[0, 0], units[0, 1] - true[0, 1]
    dx1, dy1 = units[1, 0] - true[1, 0], units[1, 1] - true[1, 1]
    dx2, dy2 = units[2, 0] - true[2, 0], units[2, 1] - true[2, 1]
    unit = (math.sqrt(dx0 * dx0 + dy0 * dy0) + math.sqrt(dx1 * dx1 + dy1 * dy1)
            + math.sqrt(dx2 * dx2 + dy2 * dy2)) / 3.0
    return unit, math.hypot((dx0 + dx1 + dx2) / 3.0, (dy0 + dy1 + dy2) / 3.0)


@njit(cache=True, error_model="numpy")
def _score(i, estimate, true, unit_error, plate_error, reward, terms):
    """Robot ``i``'s errors (m) and reward: -10 (mean unit error + plate centre error), its first term."""
    unit_error[i], plate_error[i] = _errors(estimate[i], true[i])
    terms[i, 0], terms[i, 1] = -10.0 * (unit_error[i] + plate_error[i]), 0.0
    reward[i] = terms[i, 0]


@njit(cache=True)
def decide(terminated: bool, unit_error: float, folded: bool, success_error: float, fold_ends: bool) -> bool:
    """Whether a robot has succeeded: the drive's end reached with the estimate's mean unit error below
    ``success_error`` and, where a fold ends the episode (v2), the mechanism never folded. The one place the task
    decides success: the transition calls it for every robot it evaluates, and
    :meth:`~paragym.tasks.tripod_task.TripodTask.evaluate` reports what it decided."""
    return terminated and unit_error < success_error and not (fold_ends and folded)


@njit(cache=True)
def _end(i, move, eta, folded, terminated, unit_error, success, failure, judge):
    """Robot ``i``'s end of a step: whether the mechanism folded (a leg at or past horizontal, true eta <= 0),
    which ends the episode where the rules say so; the failure (the fold) and the success."""
    success_error, fold_ends = judge
    if move and min(eta[i, 0], eta[i, 1], eta[i, 2]) <= 0.0:
        folded[i] = True
    if fold_ends and folded[i]:
        terminated[i] = True
    failure[i] = 1 if folded[i] else 0
    success[i] = decide(terminated[i], unit_error[i], folded[i], success_error, fold_ends)


@njit(cache=True, error_model="numpy")
def _advance_kernel(arrays, actions, rows, move, external, moved, increment, max_correction, steps, noise, geo, drive,
                    judge):
    """The transition of every robot with ``rows[i]`` (module docstring), ending in :func:`_end` (``judge``: the
    success error and whether a fold ends the episode). ``external``: the drives were
    advanced already (robots ``moved``, odometric ``increment`` per unit): the dynamic fidelity. ``arrays``:
    the state's, in ``KERNEL_FIELDS``' order; ``drive``: the drives', ``DriveState.KERNEL_FIELDS``' order."""
    estimate, eta_read, last_eta, smoothed, unit_error, plate_error, terminated, obs, reward, terms, folded, success, \
        failure = arrays
    true, odometry, gradient, eta, t, k, speed, heading, heading_error, push, bumps, bump_count, slip_angle, \
        slip_speed, dt = drive
    row = np.empty(OBS_SIZE)  # one robot's observation before the clip, reused
    for i in range(len(k)):
        if not rows[i]:
            continue
        if move and (moved[i] if external else k[i] < steps[i]):
            ox, oy = 0.0, 0.0
            if not external:
                ox, oy = k_drive_step(i, geo, drive)
            for u in range(3):
                if external:
                    ox, oy = increment[i, u, 0], increment[i, u, 1]
                estimate[i, u, 0] += ox + actions[i, 2 * u] * max_correction
                estimate[i, u, 1] += oy + actions[i, 2 * u + 1] * max_correction
                estimate[i, u, 2] = k_terrain(estimate[i, u, 0], estimate[i, u, 1], bumps[i], bump_count[i])[0]
            for u in range(3):
                last_eta[i, u] = eta_read[i, u]
        for u in range(3):
            eta_read[i, u] = eta[i, u] + noise[i, k[i], u]
        _score(i, estimate, true, unit_error, plate_error, reward, terms)
        terminated[i] = k[i] >= steps[i]
        _end(i, move, eta, folded, terminated, unit_error, success, failure, judge)
        # observation: odometric units (/ 10 m), measured eta, the command, the estimate's xy (/ 10 m)
        for u in range(3):
            for c in range(3):
                row[3 * u + c] = odometry[i, u, c] / POS_SCALE
            row[9 + u] = eta_read[i, u]
            row[15 + 2 * u], row[16 + 2 * u] = estimate[i, u, 0] / POS_SCALE, estimate[i, u, 1] / POS_SCALE
        row[12], row[13], row[14] = speed[i], math.cos(heading[i]), math.sin(heading[i])
        for c in range(OBS_SIZE):
            obs[i, c] = min(100.0, max(-100.0, row[c]))


@njit(cache=True, error_model="numpy")
def _advance_v1_kernel(arrays, actions, rows, move, trust, external, moved, increment, steps, noise, geo, drive,
                       judge):
    """Version 1's transition of every robot with ``rows[i]`` (module docstring); ``arrays``, ``drive``,
    ``external``, ``moved``, ``increment``, ``judge``: as :func:`_advance_kernel`'s; ``trust``: the smoothing, the
    trust rate and whether the reward is relative to odometry."""
    smoothing, trust_rate, relative = trust
    estimate, eta_read, last_eta, smoothed, unit_error, plate_error, terminated, obs, reward, terms, folded, success, \
        failure = arrays
    true, odometry, gradient, eta, t, k, speed, heading, heading_error, push, bumps, bump_count, slip_angle, \
        slip_speed, dt = drive
    row = np.empty(OBS_SIZE_V1)
    plate = np.empty((3, 3))
    for i in range(len(k)):
        if not rows[i]:
            continue
        if move and (moved[i] if external else k[i] < steps[i]):
            for u in range(3):  # the agent's trust in the paper's correction, unit by unit, on what it saw
                w = trust_rate * min(1.0, max(0.0, actions[i, u]))
                if w > 0.0:
                    x, y = mt.k_relocate(estimate[i], u, smoothed[i])
                    estimate[i, u, 0] += w * (x - estimate[i, u, 0])
                    estimate[i, u, 1] += w * (y - estimate[i, u, 1])
            ox, oy = 0.0, 0.0
            if not external:
                ox, oy = k_drive_step(i, geo, drive)
            for u in range(3):
                if external:
                    ox, oy = increment[i, u, 0], increment[i, u, 1]
                estimate[i, u, 0] += ox
                estimate[i, u, 1] += oy
                estimate[i, u, 2] = k_terrain(estimate[i, u, 0], estimate[i, u, 1], bumps[i], bump_count[i])[0]
                last_eta[i, u] = eta_read[i, u]
        for u in range(3):
            eta_read[i, u] = eta[i, u] + noise[i, k[i], u]
            plate[u, 0], plate[u, 1], plate[u, 2] = mt.k_unit(eta_read[i, u], u, geo)
        measured = mt.k_distances(plate)
        for c in range(3):  # exponential smoothing of the encoder distances (the first reading starts it)
            smoothed[i, c] = measured[c] if math.isnan(smoothed[i, c]) else \
                smoothed[i, c] + smoothing * (measured[c] - smoothed[i, c])
        _score(i, estimate, true, unit_error, plate_error, reward, terms)
        if relative:  # v1: against odometry alone (the same optimum, less variance)
            odo_unit, odo_plate = _errors(odometry[i], true[i])
            terms[i, 1] = 10.0 * (odo_unit + odo_plate)
            reward[i] += terms[i, 1]
        terminated[i] = k[i] >= steps[i]
        _end(i, move, eta, folded, terminated, unit_error, success, failure, judge)
        # observation, in the robot's frame (x along the commanded heading)
        own = mt.k_distances(estimate[i])
        odo = mt.k_distances(odometry[i])
        ch, sh = math.cos(heading[i]), math.sin(heading[i])
        for c in range(3):
            row[c] = (own[c] - smoothed[i, c]) / RESIDUAL_SCALE
            row[3 + c] = (odo[c] - smoothed[i, c]) / RESIDUAL_SCALE
            ex, ey = estimate[i, c, 0] - odometry[i, c, 0], estimate[i, c, 1] - odometry[i, c, 1]
            row[6 + 2 * c] = (ch * ex + sh * ey) / OFFSET_SCALE
            row[7 + 2 * c] = (-sh * ex + ch * ey) / OFFSET_SCALE
            row[13 + c] = eta_read[i, c]
        row[12] = k[i] / max(steps[i], 1)
        for c in range(OBS_SIZE_V1):
            obs[i, c] = min(100.0, max(-100.0, row[c]))


#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = renamed(__name__, {"TripodTaskState": "TripodState"})
