"""The mobile tripod's drive: three unicycle drive units, slip, terrain, odometry and encoders (paper 004).

Each drive unit moves as a unicycle along its commanded heading at the
commanded speed; what really happens differs by the scenario's disturbances
(a heading offset, a push, slip velocities, the terrain's slope). Odometry
integrates the wheels' own motion — the commanded speed along the heading
the unit believes it has — and so is blind to all of them. The plate's true
pose and the encoder angles eta follow from the units' true positions by the
forward kinematics (:mod:`paragym.mechanisms.tripod`); the encoders
add uniform noise of +-``encoder_noise``. Sampled at ``rate`` (20 Hz). The
drive's random numbers (the encoder noise of every sample, the slip of
every step) are drawn when it starts, in a fixed order, so that a drive
depends only on its generator's state. The terrain is flat or bumpy (a sum
of Gaussian bumps and holes); PyBullet draws it as a heightfield with the
robot (:class:`paragym.sim.tripod_scene.TripodScene`).

The physics of one sample is written once, as a numba kernel over one robot
of a :class:`DriveState` of N drives (:func:`k_drive_step`); the task's step
(:mod:`paragym.tasks.tripod_step`) calls it for every robot, and
:class:`TripodDrive` is one drive (N = 1) for the planners and the CLI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numba import njit

from paragym.kernels import KernelArrays
from paragym.mechanisms import tripod as mt

__all__ = ["DriveState", "Terrain", "TripodDrive", "k_drive_step", "k_terrain"]


@njit(cache=True, error_model="numpy")
def k_terrain(x, y, bumps, count):
    """Ground height z(x, y) and its gradient: the sum of ``count`` Gaussian
    bumps (x, y, height, 2 radius^2) of ``bumps`` (B, 4), added in order."""
    h, gx, gy = 0.0, 0.0, 0.0
    for b in range(count):
        dx, dy = x - bumps[b, 0], y - bumps[b, 1]
        each = math.exp(-((dx * dx + dy * dy) / bumps[b, 3])) * bumps[b, 2]
        h += each
        c = -2.0 * each / bumps[b, 3]
        gx += c * dx
        gy += c * dy
    return h, gx, gy


@njit(cache=True, error_model="numpy")
def _terrain_all(xy, bumps, out):
    for i in range(xy.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = k_terrain(xy[i, 0], xy[i, 1], bumps, bumps.shape[0])


@dataclass(frozen=True)
class Terrain:
    """Ground height z(x, y) = sum of Gaussian bumps (positive) and holes (negative), m."""

    bumps: tuple[tuple[float, float, float, float], ...] = ()  # (x, y, height, radius)

    @property
    def kernel_bumps(self) -> np.ndarray:
        """The bumps as :func:`k_terrain` takes them (B, 4): x, y, height, 2 radius^2."""
        b = np.array(self.bumps, float).reshape(-1, 4)
        return np.column_stack([b[:, :3], 2 * b[:, 3] ** 2])

    def height_and_gradient(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """z (...) and its gradient (..., 2) at points (..., 2) (:func:`k_terrain`)."""
        xy = np.asarray(xy, float)
        flat = np.ascontiguousarray(xy.reshape(-1, 2))
        out = np.empty((len(flat), 3))
        _terrain_all(flat, self.kernel_bumps, out)
        return out[:, 0].reshape(xy.shape[:-1]), out[:, 1:].reshape(xy.shape)

    def height(self, xy: np.ndarray) -> np.ndarray:
        """z (...) at points (..., 2)."""
        return self.height_and_gradient(xy)[0]


@lru_cache(maxsize=16)
def _start(geometry: mt.TripodGeometry, eta0: float) -> tuple[np.ndarray, np.ndarray]:
    """Leg angles (3,) and unit positions (3, 3) of a tripod at rest on flat
    ground with every leg at ``eta0``, plate level above the origin (the
    same for every drive of a geometry: computed once)."""
    eta = np.full(3, eta0)
    height = -mt.plate_frame_units(eta, geometry)[0, 0, 2]
    eta, units = mt.inverse(np.eye(3)[None], np.array([[0.0, 0.0, height]]), geometry)
    eta.setflags(write=False)
    units.setflags(write=False)
    return eta[0], units[0]


@dataclass
class DriveState(KernelArrays):
    """N drives: the units' true and odometric positions (N, 3, 3), the
    terrain's gradient under the true units (N, 3, 2), the true eta (N, 3),
    time and sample, each drive's command and disturbances, and its random
    numbers (``noise`` (N, S, 3) per sample, ``slip_angle``, ``slip_speed``
    (N, S, 3) per step; S as long as the longest drive)."""

    #: what :func:`k_drive_step` reads and writes, in its order (:class:`paragym.kernels.KernelArrays`)
    KERNEL_FIELDS = ("true", "odometry", "gradient", "eta", "t", "k", "speed", "heading", "heading_error", "push",
                     "bumps", "bump_count", "slip_angle", "slip_speed", "dt")

    true: np.ndarray
    odometry: np.ndarray
    gradient: np.ndarray
    eta: np.ndarray
    t: np.ndarray
    k: np.ndarray
    steps: np.ndarray
    speed: np.ndarray
    heading: np.ndarray
    heading_error: np.ndarray
    push: np.ndarray
    bumps: np.ndarray
    bump_count: np.ndarray
    noise: np.ndarray
    slip_angle: np.ndarray
    slip_speed: np.ndarray
    dt: float = 0.05
    scenarios: list[Any] = field(default_factory=list)

    @classmethod
    def empty(cls, n: int, rate: float = 20.0) -> DriveState:
        z = np.zeros
        return cls(true=z((n, 3, 3)), odometry=z((n, 3, 3)), gradient=z((n, 3, 2)), eta=z((n, 3)), t=z(n),
                   k=z(n, np.int64), steps=z(n, np.int64), speed=z(n), heading=z(n), heading_error=z((n, 3)),
                   push=np.full((n, 1, 3), np.nan), bumps=z((n, 0, 4)), bump_count=z(n, np.int64),
                   noise=z((n, 1, 3)), slip_angle=z((n, 1, 3)), slip_speed=z((n, 1, 3)), dt=1.0 / rate,
                   scenarios=[None] * n)

    def _room(self, samples: int, bumps: int, pushes: int = 1) -> None:
        """Grow the random-number, bump and push arrays to hold ``samples`` samples, ``bumps`` bumps and
        ``pushes`` pushes."""
        extra = samples - self.noise.shape[1]
        if extra > 0:
            self.noise, self.slip_angle, self.slip_speed = (np.pad(a, ((0, 0), (0, extra), (0, 0))) for a in
                                                            (self.noise, self.slip_angle, self.slip_speed))
        extra = bumps - self.bumps.shape[1]
        if extra > 0:
            self.bumps = np.pad(self.bumps, ((0, 0), (0, extra), (0, 0)), constant_values=1.0)
        extra = pushes - self.push.shape[1]
        if extra > 0:
            self.push = np.pad(self.push, ((0, 0), (0, extra), (0, 0)), constant_values=np.nan)
        self.reallocated()

    def start(self, i: int, scenario: Any, rng: np.random.Generator, geometry: mt.TripodGeometry,
              encoder_noise: float, eta0: float = math.radians(40.0)) -> None:
        """Start drive ``i`` on ``scenario`` (a checked
        :class:`paragym.tasks.tripod.TripodScenario`) at rest, the legs
        at ``eta0``, drawing its random numbers from ``rng``: the encoder noise
        of every sample, then (with slip) the slip angles and speeds of every step."""
        steps = int(round(scenario.duration / self.dt))
        bumps = scenario.terrain.kernel_bumps
        pushes = scenario.pushes
        self._room(steps + 1, len(bumps), len(pushes))
        self.scenarios[i] = scenario
        self.steps[i], self.k[i], self.t[i] = steps, 0, 0.0
        self.speed[i], self.heading[i], self.heading_error[i] = scenario.speed, scenario.heading, \
            scenario.heading_error
        self.push[i] = np.nan
        if pushes:
            self.push[i, :len(pushes)] = pushes
        self.bumps[i], self.bump_count[i] = 1.0, len(bumps)
        self.bumps[i, :len(bumps)] = bumps
        eta, units = _start(geometry, float(eta0))
        self.true[i] = units
        self.true[i, :, 2], self.gradient[i] = scenario.terrain.height_and_gradient(units[:, :2])
        self.odometry[i] = self.true[i]
        self.noise[i] = 0.0
        self.noise[i, :steps + 1] = rng.uniform(-encoder_noise, encoder_noise, (steps + 1, 3))
        self.slip_angle[i], self.slip_speed[i] = 0.0, 0.0
        if scenario.slip > 0:
            self.slip_angle[i, :steps] = rng.uniform(0, 2 * np.pi, (steps, 3))
            self.slip_speed[i, :steps] = rng.uniform(0, scenario.slip, (steps, 3))
        self.eta[i], _ = mt.eta(self.true[i], eta, geometry)  # the branch continuous with the legs at eta0





@njit(cache=True, error_model="numpy")
def k_drive_step(i, geo, drive):
    """Advance drive ``i`` of ``drive`` (the tuple of ``DriveState.KERNEL_FIELDS``) one sample; returns the
    odometric increment (the
    same for all three units: the commanded way along the commanded heading).

    Each unit rolls ``speed dt`` along its true heading (heading + its
    error); on a slope the wheel rolls along the ground, so the horizontal way
    is ``speed dt / sqrt(1 + slope^2)``; slip adds its velocity; a push (each of the drive's, in order) moves
    the pushed unit toward the robot's centre; then the terrain sets the
    heights and the gradient, and eta follows (:func:`mt.k_eta`, from the last
    eta so that the branch stays continuous)."""
    true, odometry, gradient, eta, t, k, speed, heading, heading_error, push, bumps, bump_count, slip_angle, \
        slip_speed, dt = drive
    way = speed[i] * dt
    ox, oy = way * math.cos(heading[i]), way * math.sin(heading[i])
    kk = k[i]
    mx, my = np.empty(3), np.empty(3)
    for u in range(3):
        c, s = math.cos(heading[i] + heading_error[i, u]), math.sin(heading[i] + heading_error[i, u])
        slope = gradient[i, u, 0] * c + gradient[i, u, 1] * s
        scale = way / math.sqrt(1.0 + slope * slope)
        v = slip_speed[i, kk, u] * dt
        mx[u] = scale * c + v * math.cos(slip_angle[i, kk, u])
        my[u] = scale * s + v * math.sin(slip_angle[i, kk, u])
    for p in range(push.shape[1]):
        if t[i] < push[i, p, 1] <= t[i] + dt:  # (NaN: no push)
            unit, depth = int(push[i, p, 0]), push[i, p, 2]
            ix = (true[i, 0, 0] + true[i, 1, 0] + true[i, 2, 0]) / 3.0 - true[i, unit, 0]
            iy = (true[i, 0, 1] + true[i, 1, 1] + true[i, 2, 1]) / 3.0 - true[i, unit, 1]
            norm = math.sqrt(ix * ix + iy * iy)
            mx[unit] += depth * ix / norm
            my[unit] += depth * iy / norm
    for u in range(3):
        true[i, u, 0] += mx[u]
        true[i, u, 1] += my[u]
        odometry[i, u, 0] += ox
        odometry[i, u, 1] += oy
    if bump_count[i]:
        for u in range(3):
            true[i, u, 2], gradient[i, u, 0], gradient[i, u, 1] = k_terrain(true[i, u, 0], true[i, u, 1], bumps[i],
                                                                            bump_count[i])
            odometry[i, u, 2] = k_terrain(odometry[i, u, 0], odometry[i, u, 1], bumps[i], bump_count[i])[0]
    t[i] += dt
    k[i] += 1
    mt.k_eta(true[i], eta[i], geo, mt.NEWTON_ITERATIONS, 1e-13, eta[i])
    return ox, oy


#: :func:`_step_one`'s robot, typed as a call from Python types it (a literal 0 would compile :func:`k_drive_step`
#: a second time)
_FIRST = np.int64(0)


@njit(cache=True, error_model="numpy")
def _step_one(geo, drive):
    return k_drive_step(_FIRST, geo, drive)


class TripodDrive:
    """One drive (the N = 1 case of :class:`DriveState`), for the planners,
    the CLI and the tests: ``step()`` advances a sample and returns the
    odometric increments (3, 2) of the units.

    Args:
        scenario: a :class:`paragym.tasks.tripod.TripodScenario`.
        rng: the generator of the drive's random numbers.
        geometry: the tripod's legs and plate.
        eta0: the legs' angle at rest (rad).
        encoder_noise: half-width of the uniform encoder noise (rad; paper: 1 deg).
        rate: samples per second.
    """

    def __init__(self, scenario: Any, rng: np.random.Generator,
                 geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY, eta0: float = math.radians(40.0),
                 encoder_noise: float = math.radians(1.0), rate: float = 20.0) -> None:
        self.scenario, self.rng, self.geometry = scenario, rng, geometry
        self.encoder_noise = encoder_noise
        self.state = DriveState.empty(1, rate)
        self.state.start(0, scenario, rng, geometry, encoder_noise, eta0)
        self._geo = mt.kernel_consts(geometry)

    dt = property(lambda self: self.state.dt)
    steps = property(lambda self: int(self.state.steps[0]))
    k = property(lambda self: int(self.state.k[0]))
    t = property(lambda self: float(self.state.t[0]))
    true = property(lambda self: self.state.true[0], doc="The units' true positions (3, 3), m.")
    odometry = property(lambda self: self.state.odometry[0], doc="The units' odometric positions (3, 3), m.")
    eta = property(lambda self: self.state.eta[0], doc="The true encoder angles (3,), rad.")
    noise = property(lambda self: self.state.noise[0, :self.steps + 1])

    @property
    def encoders(self) -> np.ndarray:
        """The measured eta (3,) of the current sample: the true angles plus uniform noise."""
        return self.state.eta[0] + self.state.noise[0, self.state.k[0]]

    @property
    def rotation(self) -> np.ndarray:
        """The plate's true orientation (3, 3), by the rigid fit of :func:`mobile_tripod.forward`."""
        return mt.forward(self.true[None], eta0=self.eta, geometry=self.geometry)[1][0]

    @property
    def centre(self) -> np.ndarray:
        """The plate's true centre (3,)."""
        return mt.forward(self.true[None], eta0=self.eta, geometry=self.geometry)[2][0]

    def step(self) -> np.ndarray:
        """Advance one sample (:func:`k_drive_step`); returns the odometric increments (3, 2) of the units."""
        ox, oy = _step_one(self._geo, self.state.kernel_arrays())
        return np.array([[ox, oy], [ox, oy], [ox, oy]])
