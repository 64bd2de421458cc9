"""The mobile tripod task's transition, written once over N robots (paper 004).

The state of N robots (:class:`TripodTaskState`) is their drives
(:class:`paragym.sim.tripod_drive.DriveState`) and the agent's estimates.
:func:`reset` starts the chosen rows' drives and :func:`step` advances the
active rows one sample, in one numba kernel that runs the drive's physics
(:func:`paragym.sim.tripod_drive.k_drive_step`) and then the estimate, the
observation and the reward, so that the single env (N = 1) and the native
vector env run the same code (:mod:`paragym.envs.mobile_tripod` are shells
over this module).

One step: the drive advances a sample; the estimate moves by the odometric
increment plus the agent's correction (action times ``max_correction``), its
height from the terrain; the encoders read the true eta plus noise. Reward:
-10 (mean unit error + plate centre error), m, the estimate's horizontal unit
positions against the true ones. Terminated at the drive's end.

Version 1 (``TripodParams.version == 1``) changes what the agent does and
sees and earns; the drive and the end are v0's. Before the drive advances,
each unit u of the estimate moves the fraction ``trust_rate * clip(a_u, 0, 1)``
of the way
to where the paper's correction would put it (section 3,
:func:`paragym.mechanisms.mobile_tripod.k_relocate`: on the circles about the
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
from dataclasses import dataclass

import numpy as np
from numba import njit

from paragym.mechanisms import mobile_tripod as mt
from paragym.sim.tripod_drive import DriveState, k_drive_step, k_terrain
from paragym.tasks.mobile_tripod import DriveScenario

__all__ = ["OBS_SIZE", "OBS_SIZE_V1", "OFFSET_SCALE", "POS_SCALE", "RESIDUAL_SCALE",
           "TripodParams", "TripodTaskState", "reset", "step"]

OBS_SIZE = 9 + 3 + 3 + 6
POS_SCALE = 10.0  # m per observation unit
#: v1: the residuals of the estimate's and the odometry's inter-unit distances against the smoothed encoder
#: distances (3 + 3, / RESIDUAL_SCALE), each unit's estimate minus its odometry in the robot's frame (6, /
#: OFFSET_SCALE), the drive's progress t / duration (1), the measured eta (3, rad)
OBS_SIZE_V1 = 3 + 3 + 6 + 1 + 3
RESIDUAL_SCALE = 0.05  # m per observation unit
OFFSET_SCALE = 0.1  # m per observation unit


@dataclass(frozen=True)
class TripodParams:
    """The env's arguments that shape the transition (see the env's docstring)."""

    encoder_noise: float = math.radians(1.0)
    max_correction: float = 0.05
    geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY
    version: int = 0
    smoothing: float = 0.1
    trust_rate: float = 0.2
    relative_reward: bool = True

    @property
    def obs_size(self) -> int:
        return OBS_SIZE if self.version == 0 else OBS_SIZE_V1

    @property
    def action_size(self) -> int:
        return 6 if self.version == 0 else 3


@dataclass
class TripodTaskState:
    """N robots: their drives, the agent's estimates of the units (N, 3, 3),
    the encoders' readings now and at the last sample (N, 3), the smoothed
    encoder distances (N, 3; v1), the errors, and the observation and reward
    of their last step."""

    drive: DriveState
    estimate: np.ndarray
    eta: np.ndarray
    last_eta: np.ndarray
    smoothed: np.ndarray
    unit_error: np.ndarray
    plate_error: np.ndarray
    terminated: np.ndarray
    obs: np.ndarray
    reward: np.ndarray

    @classmethod
    def empty(cls, n: int, obs_size: int = OBS_SIZE) -> TripodTaskState:
        return cls(drive=DriveState.empty(n), estimate=np.zeros((n, 3, 3)), eta=np.zeros((n, 3)),
                   last_eta=np.zeros((n, 3)), smoothed=np.zeros((n, 3)), unit_error=np.zeros(n),
                   plate_error=np.zeros(n), terminated=np.zeros(n, bool), obs=np.zeros((n, obs_size), np.float32),
                   reward=np.zeros(n))

    @property
    def scenarios(self) -> list[DriveScenario | None]:
        return self.drive.scenarios


def reset(state: TripodTaskState, params: TripodParams, rows: np.ndarray, scenarios: list[DriveScenario],
          rngs: list[np.random.Generator]) -> None:
    """Start ``rows`` on checked ``scenarios`` (:func:`paragym.tasks.mobile_tripod.draw_drive`),
    each drawing its drive's random numbers from its generator; every estimate
    starts exact."""
    for i, scenario, rng in zip(rows, scenarios, rngs, strict=True):
        state.drive.start(int(i), scenario, rng, params.geometry, params.encoder_noise)
        state.estimate[i] = state.drive.odometry[i]
    mask = np.zeros(len(state.estimate), bool)
    mask[rows] = True
    state.smoothed[rows] = np.nan  # v1: the first reading starts the average
    _advance(state, params, np.zeros((len(state.estimate), params.action_size)), mask, False)
    state.last_eta[rows] = state.eta[rows]


def step(state: TripodTaskState, params: TripodParams, actions: np.ndarray, active: np.ndarray) -> None:
    """Advance the ``active`` robots (N,) one sample with ``actions`` inside
    the Box (the env clips): corrections (N, 6) in v0, trust in the paper's
    correction per unit (N, 3) in v1."""
    _advance(state, params, actions, active, True)


def _advance(state: TripodTaskState, params: TripodParams, actions: np.ndarray, rows: np.ndarray,
             move: bool) -> None:
    s, d = state, state.drive
    if params.version == 1:
        _advance_v1_kernel(s.estimate, s.eta, s.last_eta, s.smoothed, s.unit_error, s.plate_error, s.terminated,
                           s.obs, s.reward, np.ascontiguousarray(actions, np.float64), rows, move, params.smoothing,
                           params.trust_rate, params.relative_reward,
                           d.steps, d.noise, mt.kernel_consts(params.geometry), *d.kernel_args())
        return
    _advance_kernel(s.estimate, s.eta, s.last_eta, s.unit_error, s.plate_error, s.terminated, s.obs, s.reward,
                    np.ascontiguousarray(actions, np.float64), rows, move, params.max_correction, d.steps, d.noise,
                    mt.kernel_consts(params.geometry), *d.kernel_args())


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
def _score(i, estimate, true, unit_error, plate_error, reward):
    """Robot ``i``'s errors (m) and reward: -10 (mean unit error + plate centre error)."""
    unit_error[i], plate_error[i] = _errors(estimate[i], true[i])
    reward[i] = -10.0 * (unit_error[i] + plate_error[i])


@njit(cache=True, error_model="numpy")
def _advance_kernel(estimate, eta_read, last_eta, unit_error, plate_error, terminated, obs, reward, actions, rows,
                    move, max_correction, steps, noise, geo, true, odometry, gradient, eta, t, k, speed, heading,
                    heading_error, push, bumps, bump_count, slip_angle, slip_speed, dt):
    """The transition of every robot with ``rows[i]`` (module docstring)."""
    row = np.empty(OBS_SIZE)  # one robot's observation before the clip, reused
    for i in range(len(k)):
        if not rows[i]:
            continue
        if move and k[i] < steps[i]:
            ox, oy = k_drive_step(i, geo, true, odometry, gradient, eta, t, k, speed, heading, heading_error, push,
                                  bumps, bump_count, slip_angle, slip_speed, dt)
            for u in range(3):
                estimate[i, u, 0] += ox + actions[i, 2 * u] * max_correction
                estimate[i, u, 1] += oy + actions[i, 2 * u + 1] * max_correction
                estimate[i, u, 2] = k_terrain(estimate[i, u, 0], estimate[i, u, 1], bumps[i], bump_count[i])[0]
            for u in range(3):
                last_eta[i, u] = eta_read[i, u]
        for u in range(3):
            eta_read[i, u] = eta[i, u] + noise[i, k[i], u]
        _score(i, estimate, true, unit_error, plate_error, reward)
        terminated[i] = k[i] >= steps[i]
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
def _advance_v1_kernel(estimate, eta_read, last_eta, smoothed, unit_error, plate_error, terminated, obs, reward,
                       actions, rows, move, smoothing, trust_rate, relative, steps, noise, geo, true, odometry,
                       gradient, eta, t, k, speed, heading, heading_error, push, bumps, bump_count, slip_angle,
                       slip_speed, dt):
    """Version 1's transition of every robot with ``rows[i]`` (module docstring)."""
    row = np.empty(OBS_SIZE_V1)
    plate = np.empty((3, 3))
    for i in range(len(k)):
        if not rows[i]:
            continue
        if move and k[i] < steps[i]:
            for u in range(3):  # the agent's trust in the paper's correction, unit by unit, on what it saw
                w = trust_rate * min(1.0, max(0.0, actions[i, u]))
                if w > 0.0:
                    x, y = mt.k_relocate(estimate[i], u, smoothed[i])
                    estimate[i, u, 0] += w * (x - estimate[i, u, 0])
                    estimate[i, u, 1] += w * (y - estimate[i, u, 1])
            ox, oy = k_drive_step(i, geo, true, odometry, gradient, eta, t, k, speed, heading, heading_error, push,
                                  bumps, bump_count, slip_angle, slip_speed, dt)
            for u in range(3):
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
        _score(i, estimate, true, unit_error, plate_error, reward)
        if relative:  # v1: against odometry alone (the same optimum, less variance)
            odo_unit, odo_plate = _errors(odometry[i], true[i])
            reward[i] += 10.0 * (odo_unit + odo_plate)
        terminated[i] = k[i] >= steps[i]
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
