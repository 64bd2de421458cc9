"""The mobile tripod's worlds (paper 004): where its robot drives besides the kinematic drive model.

:class:`DynamicWorld` is one robot's drive under PyBullet's dynamics, which
replaces :func:`paragym.sim.tripod_drive.k_drive_step` sample by sample for
the transition (:mod:`paragym.tasks.tripod_step`). Episode validation reads
the validated body from it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from paragym.mechanisms import tripod as mt
from paragym.mechanisms.geometry import pose6
from paragym.sim.client import physics_steps
from paragym.sim.tripod_drive import k_terrain

#: the state and parameters the worlds read are the transition's (paragym.tasks.tripod_step), typed Any
#: here: the transition imports the worlds, not the other way
__all__ = ["DynamicWorld"]


#: the ladder's push under dynamics (:attr:`paragym.tasks.tripod_step.TripodRules.rung`): (force N, the pushed
#: unit's mean displacement m) for a 0.1 s push on flat ground, over the three units at headings 0 and 90 deg
#: (``benchmarks/tripod_push.py``). The released ids' push, ``push_force`` x depth, holds only near the paper's
#: 2.5 cm: friction holds the unit below about 400 N and it slides ever further above, so a 20 cm push folded
#: the tripod. A rung pushes with the force whose displacement is the push's distance, read off this table and
#: scaled by ``push_force`` / 14,000.
PUSH_CALIBRATION = ((400.0, 0.026), (500.0, 0.064), (600.0, 0.118), (700.0, 0.19), (800.0, 0.277),
                    (900.0, 0.378), (1000.0, 0.493), (1100.0, 0.624), (1200.0, 0.769), (1300.0, 0.933),
                    (1400.0, 1.113))


def calibrated_push_force(depth: float, push_force: float) -> float:
    """The force (N) of a ladder rung's push of ``depth`` m (:data:`PUSH_CALIBRATION`), for a dynamics whose
    ``push_force`` is given (N/m; 14,000 the default)."""
    forces, moves = np.array(PUSH_CALIBRATION).T
    return float(np.interp(abs(depth), moves, forces)) * math.copysign(1.0, depth) * push_force / 14000.0


class DynamicWorld:
    """One robot's drive under the dynamic fidelity's physics (:class:`paragym.sim.tripod_dynamic.TripodDynamicScene`:
    PyBullet's, or MuJoCo's where ``engine`` is its settings, :mod:`paragym.sim.mujoco_sim`).

    It replaces :func:`paragym.sim.tripod_drive.k_drive_step` sample by
    sample: the units drive for one sample's time on their wheels; the true
    units become the simulated ones, eta the leg encoders', and each unit's
    odometry moves by its own wheel encoders' travel along the heading it
    believes (so the units' odometric increments differ: ``increment``
    (1, 3, 2)). The scenario's disturbances act through the physics: its
    heading errors misalign the units, each of its pushes is a force of
    ``push_force`` x depth N on the pushed unit toward the robot's centre for
    0.1 s (on a ladder's rung, ``calibrated_push``: :func:`calibrated_push_force`), its slip (a slippery
    floor) sets each unit's wheel friction every
    second from the drive's own slip numbers (no new draws: a seed gives the
    same encoder noise in both fidelities): a slip speed s (m/s) lowers it
    from ``friction`` toward ``slip_friction``, reached at 1 cm/s, the
    paper's; and its terrain is the ground's heightfield over the drive's
    path.
    """

    def __init__(self, geometry: mt.TripodGeometry, dynamics: Any, gui: bool = False,
                 calibrated_push: bool = False, engine: Any = None, on_wheels: bool = False) -> None:
        from paragym.sim.tripod_dynamic import TripodDynamics

        self.geometry, self.dynamics, self.gui = geometry, dynamics or TripodDynamics(), gui
        self.calibrated_push, self.engine, self.on_wheels = calibrated_push, engine, on_wheels
        self._pushing = 0  # which of the drive's pushes acts
        self.scene: Any = None
        self._terrain: Any = None
        self.increment = np.zeros((1, 3, 2))
        self._push_left = 0

    def reset(self, state: Any) -> None:
        """Build the scene for the drive's terrain (kept when it is the same) and put the robot at its start."""
        from paragym.sim.tripod_dynamic import TripodDynamicScene

        d = state.drive
        scenario = d.scenarios[0]
        heading, reach = float(d.heading[0]), scenario.distance + 4.0  # the path, and the robot's span about it
        ends = np.array([[0.0, 0.0], [reach * math.cos(heading), reach * math.sin(heading)]])
        region = (float(ends[:, 0].min() - 4), float(ends[:, 0].max() + 4), float(ends[:, 1].min() - 4),
                  float(ends[:, 1].max() + 4))
        if self.scene is None or (scenario.terrain, region if scenario.terrain.bumps else None) != self._terrain:
            if self.scene is not None:
                self.scene.close()
            self.scene = TripodDynamicScene(scenario.terrain, self.geometry, self.dynamics, self.gui, region,
                                            self.engine)
            self._terrain = (scenario.terrain, region if scenario.terrain.bumps else None)
        self.scene.reset(d.true[0], d.eta[0], float(d.heading[0]), d.heading_error[0], self.on_wheels)
        self.scene.set_friction(np.full(3, self.dynamics.friction))
        self._push_left = 0
        self.increment[:] = 0.0

    def move(self, state: Any) -> np.ndarray:
        """Advance the drive one sample if it has not ended; returns which robots moved (1,)."""
        d, dyn = state.drive, self.dynamics
        if d.k[0] >= d.steps[0]:
            return np.zeros(1, bool)
        scenario, k = d.scenarios[0], int(d.k[0])
        if scenario.slip > 0 and k % int(round(1.0 / d.dt)) == 0:
            share = np.minimum(1.0, d.slip_speed[0, k] / 0.01)
            self.scene.set_friction(dyn.friction - (dyn.friction - dyn.slip_friction) * share)
        push = None
        for p in range(d.push.shape[1]):  # a push that starts in this sample replaces one still acting
            if d.t[0] < d.push[0, p, 1] <= d.t[0] + d.dt:  # (NaN: no push)
                self._push_left, self._pushing = int(round(0.1 / self.scene.base_step)), p
        if self._push_left:
            unit, depth = int(d.push[0, self._pushing, 0]), d.push[0, self._pushing, 2]
            inward = d.true[0].mean(axis=0) - d.true[0, unit]
            inward[2] = 0.0
            force = calibrated_push_force(depth, dyn.push_force) if self.calibrated_push else dyn.push_force * depth
            push = (unit, force * inward / np.linalg.norm(inward))
        used = min(physics_steps(d.dt, self.scene.base_step), self._push_left)
        travel = self.scene.drive(float(d.speed[0]), d.dt, push, used)
        self._push_left -= used
        heading = float(d.heading[0])
        self.increment[0, :, 0], self.increment[0, :, 1] = travel * math.cos(heading), travel * math.sin(heading)
        bumps, count = d.bumps[0], int(d.bump_count[0])
        true = self.scene.units_true
        for u in range(3):
            d.odometry[0, u, :2] += self.increment[0, u]
            d.odometry[0, u, 2] = k_terrain(d.odometry[0, u, 0], d.odometry[0, u, 1], bumps, count)[0]
            d.true[0, u, :2] = true[u, :2]
            d.true[0, u, 2], d.gradient[0, u, 0], d.gradient[0, u, 1] = k_terrain(true[u, 0], true[u, 1], bumps,
                                                                                 count)
        d.eta[0] = self.scene.eta
        d.t[0] += d.dt
        d.k[0] += 1
        return np.ones(1, bool)

    def close(self) -> None:
        if self.scene is not None:
            self.scene.close()

    # --- what KF validation reads (paragym.validation.episode) ---
    _commanded_eta: np.ndarray | None = None

    def body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """The upper plate, judged at its centre."""
        scene = self.scene
        return scene.sim, scene.ROBOT, scene.plate_link, np.zeros(3), scene.base_step

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """The plate the policy claims: fitted to its estimated units, on the legs' angles they imply (paper
        004, eqs 4-5; least squares where no legs reach). The robot drives the commanded path whatever the
        policy does; the policy is the estimator."""
        if state.drive.k[0] == 0 or self._commanded_eta is None:  # a new episode: the legs as they start
            self._commanded_eta = state.drive.eta[0].copy()
        units = state.estimate[0] + [0.0, 0.0, self.dynamics.unit_height]
        self._commanded_eta = mt.eta(units[None], self._commanded_eta[None], self.geometry)[0][0]
        rotation, centre = mt.plate_fit(units, self._commanded_eta, self.geometry)
        return pose6(centre[0], rotation[0])

    def step_duration(self, state: Any, params: Any) -> float:
        h = self.scene.base_step
        return h * physics_steps(state.drive.dt, h)


if TYPE_CHECKING:  # the type checker holds the worlds that simulate to what episode validation reads
    from paragym.tasks.base import SimulatedWorld

    _dynamicworld: type[SimulatedWorld] = DynamicWorld
