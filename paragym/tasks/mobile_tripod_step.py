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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from paragym.mechanisms import mobile_tripod as mt
from paragym.sim.tripod_drive import DriveState, k_drive_step, k_terrain
from paragym.tasks.mobile_tripod import DriveScenario

__all__ = ["OBS_SIZE", "POS_SCALE", "TripodParams", "TripodTaskState", "reset", "step"]

OBS_SIZE = 9 + 3 + 3 + 6
POS_SCALE = 10.0  # m per observation unit


@dataclass(frozen=True)
class TripodParams:
    """The env's arguments that shape the transition (see the env's docstring)."""

    encoder_noise: float = math.radians(1.0)
    max_correction: float = 0.05
    geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY


@dataclass
class TripodTaskState:
    """N robots: their drives, the agent's estimates of the units (N, 3, 3),
    the encoders' readings now and at the last sample (N, 3), the errors,
    and the observation and reward of their last step."""

    drive: DriveState
    estimate: np.ndarray
    eta: np.ndarray
    last_eta: np.ndarray
    unit_error: np.ndarray
    plate_error: np.ndarray
    terminated: np.ndarray
    obs: np.ndarray
    reward: np.ndarray

    @classmethod
    def empty(cls, n: int) -> TripodTaskState:
        return cls(drive=DriveState.empty(n), estimate=np.zeros((n, 3, 3)), eta=np.zeros((n, 3)),
                   last_eta=np.zeros((n, 3)), unit_error=np.zeros(n), plate_error=np.zeros(n),
                   terminated=np.zeros(n, bool), obs=np.zeros((n, OBS_SIZE), np.float32), reward=np.zeros(n))

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
    _advance(state, params, np.zeros((len(state.estimate), 6)), mask, False)
    state.last_eta[rows] = state.eta[rows]


def step(state: TripodTaskState, params: TripodParams, actions: np.ndarray, active: np.ndarray) -> None:
    """Advance the ``active`` robots (N,) one sample with corrections
    ``actions`` (N, 6) inside the Box (the env clips)."""
    _advance(state, params, actions, active, True)


def _advance(state: TripodTaskState, params: TripodParams, actions: np.ndarray, rows: np.ndarray,
             move: bool) -> None:
    s, d = state, state.drive
    _advance_kernel(s.estimate, s.eta, s.last_eta, s.unit_error, s.plate_error, s.terminated, s.obs, s.reward,
                    np.ascontiguousarray(actions, np.float64), rows, move, params.max_correction, d.steps, d.noise,
                    mt.kernel_consts(params.geometry), *d.kernel_args())


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
        dx0, dy0 = estimate[i, 0, 0] - true[i, 0, 0], estimate[i, 0, 1] - true[i, 0, 1]
        dx1, dy1 = estimate[i, 1, 0] - true[i, 1, 0], estimate[i, 1, 1] - true[i, 1, 1]
        dx2, dy2 = estimate[i, 2, 0] - true[i, 2, 0], estimate[i, 2, 1] - true[i, 2, 1]
        unit_error[i] = (math.sqrt(dx0 * dx0 + dy0 * dy0) + math.sqrt(dx1 * dx1 + dy1 * dy1)
                         + math.sqrt(dx2 * dx2 + dy2 * dy2)) / 3.0
        plate_error[i] = math.hypot((dx0 + dx1 + dx2) / 3.0, (dy0 + dy1 + dy2) / 3.0)  # the plate centre's error
        reward[i] = -10.0 * (unit_error[i] + plate_error[i])
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
