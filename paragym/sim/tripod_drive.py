"""The mobile tripod's drive: three unicycle drive units, slip, terrain, odometry and encoders (paper 004).

Each drive unit moves as a unicycle along its commanded heading at the
commanded speed; what really happens differs by the scenario's disturbances
(a heading offset, a push, slip velocities, the terrain's slope). Odometry
integrates the wheels' own motion — the commanded speed along the heading
the unit believes it has — and so is blind to all of them. The plate's true
pose and the encoder angles eta follow from the units' true positions by the
forward kinematics (:mod:`paragym.mechanisms.mobile_tripod`); the encoders
add uniform noise of +-``encoder_noise``. Sampled at ``rate`` (20 Hz). The
drive's random numbers (the encoder noise of every sample, the slip of
every step) are drawn when it starts, in a fixed order, so that a drive
depends only on its generator's state (and the vector env, which draws the
same arrays per robot, reproduces it exactly). The
terrain is flat or bumpy (a sum of Gaussian bumps and holes); PyBullet draws
it as a heightfield with the robot (:class:`TripodScene`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any

import numpy as np

from paragym.mechanisms import mobile_tripod as mt

__all__ = ["DriveScenario", "Terrain", "TripodDrive", "validate_drive_scenario"]


@dataclass(frozen=True)
class Terrain:
    """Ground height z(x, y) = sum of Gaussian bumps (positive) and holes (negative), m."""

    bumps: tuple[tuple[float, float, float, float], ...] = ()  # (x, y, height, radius)

    @cached_property
    def _arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        b = np.array(self.bumps, float).reshape(-1, 4)
        return b[:, :2], b[:, 2], 2 * b[:, 3] ** 2

    def height(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, float)
        if not self.bumps:
            return np.zeros(xy.shape[:-1])
        centres, heights, width = self._arrays
        d2 = np.sum((xy[..., None, :] - centres) ** 2, axis=-1)
        return np.sum(heights * np.exp(-d2 / width), axis=-1)

    def height_and_gradient(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """z (N,) and its gradient (N, 2) at points (N, 2), in one pass."""
        xy = np.asarray(xy, float)
        if not self.bumps:
            return np.zeros(xy.shape[:-1]), np.zeros(xy.shape)
        centres, heights, width = self._arrays
        rel = xy[..., None, :] - centres
        each = heights * np.exp(-np.sum(rel * rel, axis=-1) / width)
        return each.sum(axis=-1), np.sum((-2.0 * each / width)[..., None] * rel, axis=-2)

    def slope(self, xy: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """dz/ds along unit horizontal directions (N, 2) at points (N, 2)."""
        if not self.bumps:
            return np.zeros(np.shape(xy)[:-1])
        h = 1e-4
        both = self.height(np.stack([xy + h * direction, xy - h * direction]))
        return (both[0] - both[1]) / (2 * h)


@dataclass(frozen=True)
class DriveScenario:
    """A drive: speed (m/s), heading (rad), distance (m), and disturbances.

    ``heading_error`` (3,) rad: each unit's true heading minus the one it
    believes; ``push`` (unit, time s, inward distance m) or None;
    ``slip`` m/s: the largest random slip velocity of each unit per sample
    (uniform in [0, slip] in a random direction); ``terrain``.
    """

    name: str
    speed: float = 0.66
    heading: float = 0.0
    distance: float = 20.0
    heading_error: tuple[float, float, float] = (0.0, 0.0, 0.0)
    push: tuple[int, float, float] | None = None
    slip: float = 0.0
    terrain: Terrain = field(default_factory=Terrain)
    seed: int | None = None

    @property
    def duration(self) -> float:
        return self.distance / self.speed


def validate_drive_scenario(scenario: DriveScenario, name: str = "scenario", dt: float = 0.05) -> DriveScenario:
    """Refuse (ValueError/TypeError naming the field) a drive that could not be
    simulated: non-finite or non-positive speed or distance, a drive shorter
    than one sample, heading errors that are not three finite angles within
    +-90 deg, a push on a unit other than 0, 1, 2 or at a time outside the
    drive, a negative or non-finite slip, terrain bumps that are not
    (x, y, height, radius) with a radius of at least 1 mm (a thinner one
    underflows the Gaussian) and a height within +-0.5 m."""
    if not isinstance(scenario, DriveScenario):
        raise TypeError(f"{name} must be a DriveScenario; got {type(scenario).__name__}")

    def real(value: Any, what: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            raise TypeError(f"{name}.{what} must be a real number; got {value!r}")
        if not np.isfinite(value):
            raise ValueError(f"{name}.{what} must be finite; got {value!r}")
        return float(value)

    if real(scenario.speed, "speed") <= 0:
        raise ValueError(f"{name}.speed must be > 0 m/s; got {scenario.speed!r}")
    if real(scenario.distance, "distance") <= 0:
        raise ValueError(f"{name}.distance must be > 0 m; got {scenario.distance!r}")
    if scenario.distance / scenario.speed < dt:
        raise ValueError(f"{name} lasts {scenario.distance / scenario.speed:.3g} s, less than one sample ({dt} s)")
    real(scenario.heading, "heading")
    errors = np.asarray(scenario.heading_error, dtype=object)
    if errors.shape != (3,):
        raise ValueError(f"{name}.heading_error must be three angles (rad); got {scenario.heading_error!r}")
    for k, value in enumerate(errors):
        if abs(real(value, f"heading_error[{k}]")) > np.pi / 2:
            raise ValueError(f"{name}.heading_error[{k}] must lie within +-pi/2 rad; got {value!r}")
    if scenario.push is not None:
        if not isinstance(scenario.push, tuple | list) or len(scenario.push) != 3:
            raise ValueError(f"{name}.push must be (unit, time s, inward distance m) or None; got {scenario.push!r}")
        unit, when, how_far = scenario.push
        if isinstance(unit, bool) or not isinstance(unit, int | np.integer) or unit not in (0, 1, 2):
            raise ValueError(f"{name}.push unit must be 0, 1 or 2; got {unit!r}")
        if not 0 <= real(when, "push time") <= scenario.duration:
            raise ValueError(f"{name}.push time must lie within the drive, 0-{scenario.duration:.3g} s; got {when!r}")
        if abs(real(how_far, "push distance")) > 1.0:
            raise ValueError(f"{name}.push distance must be within +-1 m; got {how_far!r}")
    if real(scenario.slip, "slip") < 0:
        raise ValueError(f"{name}.slip must be >= 0 m/s; got {scenario.slip!r}")
    if not isinstance(scenario.terrain, Terrain):
        raise TypeError(f"{name}.terrain must be a Terrain; got {type(scenario.terrain).__name__}")
    for k, bump in enumerate(scenario.terrain.bumps):
        if len(bump) != 4:
            raise ValueError(f"{name}.terrain.bumps[{k}] must be (x, y, height, radius); got {bump!r}")
        for j, what in enumerate(("x", "y", "height", "radius")):
            real(bump[j], f"terrain.bumps[{k}].{what}")
        if not bump[3] >= 1e-3:
            raise ValueError(f"{name}.terrain.bumps[{k}] radius must be at least 1 mm; got {bump[3]!r}")
        if not abs(bump[2]) <= 0.5:
            raise ValueError(f"{name}.terrain.bumps[{k}] height must lie within +-0.5 m; got {bump[2]!r}")
    return scenario


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


class TripodDrive:
    """Steps the true units, the odometry and the encoders of one drive.

    Args:
        scenario: the drive and its disturbances.
        rng: for the encoder noise and the slip.
        geometry: the tripod.
        eta0: the legs' initial angle (rad), equal for the three.
        encoder_noise: half-width of the uniform encoder noise (rad; paper: 1 deg).
        rate: sampling rate (Hz; paper: 20).
    """

    def __init__(self, scenario: DriveScenario, rng: np.random.Generator,
                 geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY, eta0: float = math.radians(40.0),
                 encoder_noise: float = math.radians(1.0), rate: float = 20.0) -> None:
        self.scenario, self.rng, self.geometry = scenario, rng, geometry
        self.encoder_noise, self.dt = encoder_noise, 1.0 / rate
        eta, units = _start(geometry, float(eta0))
        self.eta = eta.copy()
        self.true = units.copy()
        self.true[:, 2], gradient = scenario.terrain.height_and_gradient(self.true[:, :2])
        self._gradient = gradient
        self.odometry = self.true.copy()
        self.t = 0.0
        self.steps = int(round(scenario.duration * rate))
        self.k = 0
        # the whole drive's random numbers, in this order: encoder noise per sample, slip per step
        self.noise = rng.uniform(-encoder_noise, encoder_noise, (self.steps + 1, 3))
        if scenario.slip > 0:
            self.slip_angle = rng.uniform(0, 2 * np.pi, (self.steps, 3))
            self.slip_speed = rng.uniform(0, scenario.slip, (self.steps, 3))
        self._pose()

    def _pose(self) -> None:
        self.eta = mt.eta_one(self.true, self.eta, self.geometry)  # the branch continuous with the last sample

    @property
    def rotation(self) -> np.ndarray:
        """The plate's true orientation (3, 3), by the rigid fit of :func:`mobile_tripod.forward`."""
        return mt.forward(self.true[None], eta0=self.eta, geometry=self.geometry)[1][0]

    @property
    def centre(self) -> np.ndarray:
        """The plate's true centre (3,)."""
        return mt.forward(self.true[None], eta0=self.eta, geometry=self.geometry)[2][0]

    @property
    def encoders(self) -> np.ndarray:
        """The measured eta (3,) of the current sample: the true angles plus uniform noise."""
        return self.eta + self.noise[self.k]

    def step(self) -> np.ndarray:
        """Advance one sample; returns the odometric increments (3, 2) of the units."""
        sc, dt = self.scenario, self.dt
        way = sc.speed * dt
        ox, oy = way * math.cos(sc.heading), way * math.sin(sc.heading)
        odo = np.array([[ox, oy], [ox, oy], [ox, oy]])
        # on a slope the wheel rolls along the ground: less horizontal way than it counts
        grad = self._gradient.tolist()
        move = []
        for i, err in enumerate(sc.heading_error):  # three units, in floats (cheaper than numpy at this size)
            c, s = math.cos(sc.heading + err), math.sin(sc.heading + err)
            slope = grad[i][0] * c + grad[i][1] * s
            scale = way / math.sqrt(1.0 + slope * slope)
            move.append([scale * c, scale * s])
        move = np.array(move)
        if sc.slip > 0:
            a = self.slip_angle[self.k]
            move += (self.slip_speed[self.k] * dt)[:, None] * np.stack([np.cos(a), np.sin(a)], 1)
        if sc.push is not None and self.t < sc.push[1] <= self.t + dt:
            unit, _, depth = sc.push
            inward = self.true[:, :2].mean(axis=0) - self.true[unit, :2]  # toward the robot's centre
            move[unit] += depth * inward / np.linalg.norm(inward)
        self.true[:, :2] += move
        self.odometry[:, :2] += odo
        if sc.terrain.bumps:
            heights, gradient = sc.terrain.height_and_gradient(np.concatenate([self.true[:, :2],
                                                                               self.odometry[:, :2]]))
            self.true[:, 2], self.odometry[:, 2], self._gradient = heights[:3], heights[3:], gradient[:3]
        self.t += dt
        self.k += 1
        self._pose()
        return odo
