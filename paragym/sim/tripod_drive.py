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
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any

import numpy as np

from paragym.mechanisms import mobile_tripod as mt

__all__ = ["Terrain", "TripodDrive"]


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

    def __init__(self, scenario: Any, rng: np.random.Generator,
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
