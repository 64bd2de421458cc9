"""``paragym/MobileTripodOdometry-v0``: estimate where the mobile tripod's drive units are (paper 004)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import mobile_tripod as mt
from paragym.sim.tripod_drive import TripodDrive
from paragym.tasks.mobile_tripod import DriveScenario, draw_drive, drive_scenario, resolve_drive

__all__ = ["MobileTripodOdometryEnv", "MobileTripodOdometryVectorEnv", "drive_scenario"]

OBS_SIZE = 9 + 3 + 3 + 6
POS_SCALE = 10.0  # m per observation unit


class MobileTripodOdometryEnv(ParagymEnv):
    """Keep track of where a mobile parallel robot's three drive units really are.

    ## Description
    Paper 004 (Shoval and Shoham): three drive units carry legs of fixed
    length to an upper plate; encoders at the upper revolute joints measure
    the legs' angles eta, which fix the distances between the units (eq 4),
    while odometry, blind to slip, pushes and bumps, drifts (eq 5). The
    robot drives its commanded path; the agent is the estimator.

    ## Action Space
    ``Box(-1, 1, (6,))``: a correction of the estimated horizontal unit
    positions, times ``max_correction`` (5 cm), added after the odometric
    prediction.
    An action outside the Box is clipped to it (the rule of every paragym env,
    :func:`paragym.envs.base.check_action`); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``.

    ## Observation Space
    ``Box(-100, 100, (21,))``: odometric unit positions (9, / 10 m), measured
    eta (3, rad), the command (speed m/s, cos and sin of the heading), the
    previous estimate of the units' horizontal positions (6, / 10 m).

    ## Rewards
    ``-10 (mean unit error + plate centre error)`` per step (m): the estimate's
    units against the true ones, and the plate's centre fitted to the
    estimate against the true centre.

    ## Starting State
    At rest, the legs at 40 deg, every estimate exact; ``info["scenario"]``.

    ## Episode End
    After the drive (20 m at 0.66 m/s: 606 samples at 20 Hz). ``is_success``:
    the final mean unit error under ``success_error`` (5 cm).

    ## Arguments
    ``scenario``: one of initial_heading, push, random_slip, rough_terrain,
    random (default); ``encoder_noise`` (rad, 1 deg); ``max_correction`` (m);
    ``success_error`` (m); ``geometry`` (r, p: 5 ft each by default).

    ## Version History
    * v0: initial release.
      Since paragym 0.2.0 a custom scenario that cannot run (NaN, outside
      the workspace, malformed) and non-dict ``options`` are refused at reset
      with a ValueError or TypeError naming them; every episode that ran
      before runs the same (tested against recorded rollouts). Since paragym
      0.3.0 the native vector env runs every drive the single env runs (it
      refused drives of more than 8 terrain bumps, or longer than its first).
    """

    def __init__(self, scenario: str | DriveScenario = "random", render_mode: str | None = None,
                 encoder_noise: float = math.radians(1.0), max_correction: float = 0.05,
                 success_error: float = 0.05, geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY) -> None:
        super().__init__(render_mode)
        if isinstance(scenario, str):  # a custom drive is checked at reset, as before
            resolve_drive(scenario)
        if not (np.isfinite(encoder_noise) and encoder_noise >= 0):
            raise ValueError(f"encoder_noise must be >= 0 rad; got {encoder_noise!r}")
        self.scenario_arg, self.geometry = scenario, geometry
        self.encoder_noise, self.max_correction, self.success_error = encoder_noise, max_correction, success_error
        self.action_space = spaces.Box(-1.0, 1.0, (6,), np.float32)
        self.observation_space = spaces.Box(-100.0, 100.0, (OBS_SIZE,), np.float32)

    def _reset_task(self, options: dict[str, Any]) -> dict[str, Any]:
        scenario = draw_drive(options.get("scenario", self.scenario_arg), self.np_random)
        self.scenario = scenario
        self.drive = TripodDrive(scenario, self.np_random, self.geometry, encoder_noise=self.encoder_noise)
        self._estimate = self.drive.odometry.copy()
        self._eta = self.drive.encoders
        self._k = 0
        self._errors()
        info = self._info()
        info["scenario"] = scenario
        return info

    def _apply_action(self, action: np.ndarray) -> None:
        if self._k >= self.drive.steps:
            raise RuntimeError("the episode has ended: call reset()")
        inc = self.drive.step()
        self._k += 1
        self._estimate[:, :2] += inc + np.clip(action, -1, 1).reshape(3, 2) * self.max_correction
        self._estimate[:, 2] = self.scenario.terrain.height(self._estimate[:, :2])
        self._last_eta, self._eta = self._eta, self.drive.encoders
        self._errors()

    def _errors(self) -> None:
        diff = self._estimate[:, :2] - self.drive.true[:, :2]
        self._unit_error = float(np.sqrt((diff * diff).sum(axis=1)).mean())
        centre = diff.sum(axis=0) / 3.0  # the plate's centre error: the units' mean error
        self._plate_error = float(math.hypot(centre[0], centre[1]))

    def _observe(self) -> np.ndarray:
        sc = self.scenario
        obs = np.concatenate([self.drive.odometry.ravel() / POS_SCALE, self._eta,
                              [sc.speed, math.cos(sc.heading), math.sin(sc.heading)],
                              self._estimate[:, :2].ravel() / POS_SCALE])
        return np.clip(obs, -100, 100).astype(np.float32)

    def _reward(self) -> float:
        return -10.0 * (self._unit_error + self._plate_error)

    def _terminated(self) -> bool:
        return self._k >= self.drive.steps

    def _detected_fault(self) -> tuple[int, str] | None:
        """The paper's reading of eq 4 against eq 5 for the current estimate:
        which unit looks faulty, and whether eta says it went inward or outward."""
        if self._k == 0:
            return None
        target = mt.encoder_distances_one(self._eta, self.geometry)
        diff = [abs(a - b) for a, b in zip(mt.distances_one(self._estimate), target, strict=True)]
        order = sorted(range(3), key=diff.__getitem__)
        if diff[order[1]] <= 0.03 or diff[order[0]] >= 0.03:
            return None
        k = order[0]  # eta grows when a unit moves inward (eta measured down from the plate)
        return k, "inward (bump or push)" if self._eta[k] > self._last_eta[k] else "outward (hole or slip)"

    def _info(self) -> dict[str, Any]:
        return {"true_units": self.drive.true.copy(), "estimate": self._estimate.copy(),
                "odometry": self.drive.odometry.copy(), "eta": self._eta.copy(), "unit_error": self._unit_error,
                "plate_error": self._plate_error, "detected_fault": self._detected_fault(), "t": self.drive.t,
                "is_success": self._terminated() and self._unit_error < self.success_error}

    def _render_rgb(self) -> np.ndarray:
        from paragym.sim.tripod_model import TripodScene

        return self._drawn(lambda gui: TripodScene(self.scenario.terrain, gui=gui),
                           lambda scene: scene.set_state(self.drive.true, self.drive.centre, self.drive.rotation,
                                                         self.geometry))

    def _show(self) -> None:
        self._render_rgb()

    def _close(self) -> None:
        self._close_render_scene()


MAX_BUMPS = 8  # the bump arrays' first size: the most a built-in scenario has (rough_terrain); they grow


class MobileTripodOdometryVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryEnv` stepped together:
    the drives (unicycle units, slope, slip, pushes, terrain), the encoders
    (a batched Newton solve of eq 4 = eq 5) and the estimates, for all robots
    in numpy (:mod:`paragym.envs.vector`; the same numbers as the single env).
    Each reset builds the robot's :class:`TripodDrive` (which draws the drive's
    random numbers) and copies its state in. Scenarios with more than eight
    terrain bumps are refused."""

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 **kwargs: Any) -> None:
        super().__init__(num_envs, MobileTripodOdometryEnv(**kwargs), max_episode_steps, render_index)
        n = self.num_envs
        self.geometry = self.single_env.geometry
        self._drives: list[TripodDrive | None] = [None] * n
        self._steps = np.zeros(n, np.int64)
        self._k = np.zeros(n, np.int64)
        self._t = np.zeros(n)
        self._speed, self._heading = np.zeros(n), np.zeros(n)
        self._heading_error = np.zeros((n, 3))
        self._push = np.full((n, 3), np.nan)  # unit, time, depth (NaN: none)
        self._bumps = np.zeros((n, MAX_BUMPS, 2))
        self._bump_height = np.zeros((n, MAX_BUMPS))
        self._bump_width = np.ones((n, MAX_BUMPS))
        self._n_bumps = np.zeros(n, np.int64)
        self._true, self._odometry, self._estimate = np.zeros((n, 3, 3)), np.zeros((n, 3, 3)), np.zeros((n, 3, 3))
        self._gradient = np.zeros((n, 3, 2))
        self._eta_true, self._eta = np.zeros((n, 3)), np.zeros((n, 3))
        self._noise: np.ndarray | None = None
        self._slip_angle: np.ndarray | None = None
        self._slip_speed: np.ndarray | None = None

    def _make_room(self, samples: int, bumps: int) -> None:
        """Grow the per-robot arrays of noise samples and terrain bumps to hold
        a drive of ``samples`` samples over ``bumps`` bumps (any drive the
        single env runs runs here: the arrays are as long as the longest)."""
        if self._noise is None or samples > self._noise.shape[1]:
            old = self._noise
            self._noise = np.zeros((self.num_envs, samples, 3))
            grown = [np.zeros_like(self._noise), np.zeros_like(self._noise)]
            if old is not None:
                for new, was in zip((self._noise, *grown), (old, self._slip_angle, self._slip_speed), strict=True):
                    new[:, :was.shape[1]] = was
            self._slip_angle, self._slip_speed = grown
            # views with one row per (robot, sample), for gathers by flat index
            self._noise_rows, self._slip_angle_rows, self._slip_speed_rows = (
                arr.reshape(-1, 3) for arr in (self._noise, self._slip_angle, self._slip_speed))
        if bumps > self._bumps.shape[1]:
            extra = bumps - self._bumps.shape[1]
            self._bumps = np.pad(self._bumps, ((0, 0), (0, extra), (0, 0)))
            self._bump_height = np.pad(self._bump_height, ((0, 0), (0, extra)))
            self._bump_width = np.pad(self._bump_width, ((0, 0), (0, extra)), constant_values=1.0)

    def _reset_rows(self, rows: np.ndarray, options: dict[str, Any]) -> None:
        e = self.single_env
        choice = resolve_drive(options.get("scenario", e.scenario_arg))
        for i in rows:
            sc = draw_drive(choice, self._rngs[i])
            drive = TripodDrive(sc, self._rngs[i], self.geometry, encoder_noise=e.encoder_noise)
            self._make_room(drive.steps + 1, len(sc.terrain.bumps))
            self._dt = drive.dt  # the rate every drive samples at (TripodDrive's default, 20 Hz)
            self._drives[i] = drive
            self._steps[i], self._k[i], self._t[i] = drive.steps, 0, drive.t
            self._speed[i], self._heading[i], self._heading_error[i] = sc.speed, sc.heading, sc.heading_error
            self._push[i] = sc.push if sc.push is not None else (np.nan, np.nan, np.nan)
            b = np.array(sc.terrain.bumps, float).reshape(-1, 4)
            self._bumps[i], self._bump_height[i], self._bump_width[i] = 0.0, 0.0, 1.0
            self._bumps[i, :len(b)], self._bump_height[i, :len(b)] = b[:, :2], b[:, 2]
            self._bump_width[i, :len(b)] = 2 * b[:, 3] ** 2
            self._n_bumps[i] = len(b)
            self._true[i], self._odometry[i], self._gradient[i] = drive.true, drive.odometry, drive._gradient
            self._eta_true[i] = drive.eta
            self._noise[i, :drive.steps + 1] = drive.noise
            if sc.slip > 0:
                self._slip_angle[i, :drive.steps], self._slip_speed[i, :drive.steps] = drive.slip_angle, \
                    drive.slip_speed
            else:
                self._slip_speed[i] = 0.0
            self._eta[i] = drive.encoders
            self._estimate[i] = drive.odometry
        self._errors()

    def _terrain(self, xy: np.ndarray, rows: np.ndarray | slice = slice(None), slopes: int = 3
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Heights (M, P) at points (M, P, 2) of robots ``rows``' terrains and
        the gradients (M, slopes, 2) at the first ``slopes`` points: only
        robots with bumps, one bump column at a time (the sums in the single
        env's order), in place where the arithmetic allows."""
        heights, gradient = np.zeros(xy.shape[:2]), np.zeros((xy.shape[0], slopes, 2))
        n_bumps = self._n_bumps[rows]
        bumpy = np.flatnonzero(n_bumps)
        if bumpy.size:
            robots = np.arange(self.num_envs)[rows][bumpy]
            x, y = xy[bumpy, :, 0], xy[bumpy, :, 1]
            h, gx, gy = np.zeros(x.shape), np.zeros((len(x), slopes)), np.zeros((len(x), slopes))
            for b in range(int(n_bumps[bumpy].max())):
                dx, dy = x - self._bumps[robots, b, :1], y - self._bumps[robots, b, 1:]
                width = self._bump_width[robots, b, None]
                each = dx * dx
                each += dy * dy
                each /= width
                np.negative(each, out=each)
                np.exp(each, out=each)
                each *= self._bump_height[robots, b, None]
                h += each
                c = -2.0 * each[:, :slopes]
                c /= width
                gx += c * dx[:, :slopes]
                gy += c * dy[:, :slopes]
            heights[bumpy], gradient[bumpy, :, 0], gradient[bumpy, :, 1] = h, gx, gy
        return heights, gradient

    def _apply(self, actions: np.ndarray, active: np.ndarray) -> None:
        # the robots that step: a slice (views, no copies) in the usual case that all of them do
        sel: np.ndarray | slice = slice(None) if active.all() else np.flatnonzero(active)
        dt, k = self._dt, self._k[sel].copy()  # a copy: self._k moves on below
        idx = np.arange(self.num_envs)[sel]
        speed, heading = self._speed[sel], self._heading[sel]
        odo = (speed * dt)[:, None] * np.stack([np.cos(heading), np.sin(heading)], -1)  # (M, 2), all three units
        ang = heading[:, None] + self._heading_error[sel]
        cos, sin = np.cos(ang), np.sin(ang)
        grad = self._gradient[sel]
        slope = grad[..., 0] * cos + grad[..., 1] * sin
        scale = speed[:, None] * dt / np.sqrt(1.0 + slope * slope)
        at = idx * self._noise.shape[1] + k  # flat row of (robot, sample): one gather instead of two indices
        a, v = self._slip_angle_rows.take(at, axis=0), self._slip_speed_rows.take(at, axis=0) * dt
        move = np.stack([scale * cos + v * np.cos(a), scale * sin + v * np.sin(a)], -1)
        t = self._t[sel]
        pushed = np.flatnonzero((t < self._push[sel, 1]) & (self._push[sel, 1] <= t + dt))
        for j in pushed:  # at most one step per drive
            i = idx[j]
            unit, depth = int(self._push[i, 0]), self._push[i, 2]
            inward = self._true[i, :, :2].mean(axis=0) - self._true[i, unit, :2]
            move[j, unit] += depth * inward / np.linalg.norm(inward)
        true, odometry, est = self._true[sel], self._odometry[sel], self._estimate[sel]
        true[:, :, :2] += move
        odometry[:, :, :2] += odo[:, None]
        est[:, :, :2] += odo[:, None] + np.clip(actions[sel], -1, 1).reshape(-1, 3, 2) * self.single_env.max_correction
        # the terrain under the true units, the odometry and the estimate: one call for all nine points
        heights, gradient = self._terrain(np.concatenate([true[:, :, :2], odometry[:, :, :2], est[:, :, :2]], axis=1),
                                          sel)
        true[:, :, 2], odometry[:, :, 2], est[:, :, 2] = heights[:, :3], heights[:, 3:6], heights[:, 6:]
        self._true[sel], self._odometry[sel], self._gradient[sel] = true, odometry, gradient[:, :3]
        self._estimate[sel] = est
        self._t[sel] = t + dt
        self._eta_true[sel] = mt.eta_rows(true, self._eta_true[sel], self.geometry)
        self._k[sel] = k + 1
        self._eta[sel] = self._eta_true[sel] + self._noise_rows.take(at + 1, axis=0)
        self._errors()

    def _errors(self) -> None:
        dx = self._estimate[:, :, 0] - self._true[:, :, 0]
        dy = self._estimate[:, :, 1] - self._true[:, :, 1]
        d = np.sqrt(dx * dx + dy * dy)
        self._unit_error = (d[:, 0] + d[:, 1] + d[:, 2]) / 3.0
        cx, cy = (dx[:, 0] + dx[:, 1] + dx[:, 2]) / 3.0, (dy[:, 0] + dy[:, 1] + dy[:, 2]) / 3.0
        self._plate_error = np.hypot(cx, cy)

    def _observe(self) -> np.ndarray:
        obs = np.concatenate([self._odometry.reshape(-1, 9) / POS_SCALE, self._eta, self._speed[:, None],
                              np.cos(self._heading)[:, None], np.sin(self._heading)[:, None],
                              self._estimate[:, :, :2].reshape(-1, 6) / POS_SCALE], axis=1)
        return np.clip(obs, -100, 100).astype(np.float32)

    def _reward(self) -> np.ndarray:
        return -10.0 * (self._unit_error + self._plate_error)

    def _terminated(self) -> np.ndarray:
        return self._k >= self._steps

    def _infos(self) -> dict[str, Any]:
        return self._for_every_robot(
            unit_error=self._unit_error.copy(),
            is_success=self._terminated() & (self._unit_error < self.single_env.success_error))

    def _load_single(self, i: int) -> None:
        e = self.single_env
        drive = self._drives[i]
        drive.true, drive.eta = self._true[i].copy(), self._eta_true[i].copy()
        e.scenario, e.drive = drive.scenario, drive
