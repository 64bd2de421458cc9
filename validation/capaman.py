"""The validation loop for CaPaMan plans: execute in the dynamic simulation, validate.

The generic parts (:mod:`paragym.validation.motion`, ``sensors``, ``kalman``,
``report``) know nothing of CaPaMan; this module joins them to the planner's
trajectory and the dynamic PyBullet model (paper 000, section 5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from paragym.mechanisms import capaman
from paragym.sim.capaman_dynamic import CaPaManDynamics, CaPaManDynamicScene, ExecutedMotion
from paragym.trajectories import JointTrajectory, RigidMotion
from paragym.validation.report import Tolerances, ValidationReport, validate
from paragym.validation.sensors import AccelerometerArray

__all__ = ["CaPaManValidation", "planned_motion", "validate_capaman"]


def planned_motion(trajectory: JointTrajectory, rate: float,
                   geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                   settle: float = 0.0, h: float = 1e-5) -> RigidMotion:
    """The plate's planned motion (about H) sampled at ``rate`` Hz.

    Pose from the closed-form direct kinematics of alpha(t); twist from the
    analytic Jacobian and the trajectory's analytic alpha_dot:
    ``[v; omega] = J(alpha) alpha_dot``; accelerations
    ``J(alpha) alpha_ddot + dJ/dt alpha_dot`` with dJ/dt by a central
    difference along the trajectory (step ``h`` s). ``settle`` s of rest are
    appended (the executed run holds its last targets that long).
    """
    t = np.arange(0.0, trajectory.duration + settle + 0.5 / rate, 1.0 / rate)
    lo, hi = geometry.alpha_min, geometry.alpha_max
    alpha = np.clip(trajectory.position(t), lo, hi)
    rate1, rate2 = trajectory.velocity(t), trajectory.acceleration(t)
    pose = capaman.forward(alpha, geometry, validate=False)
    j, _ = capaman.jacobian(alpha, geometry, validate=False)
    j_plus, _ = capaman.jacobian(np.clip(trajectory.position(t + h), lo, hi), geometry, validate=False)
    j_minus, _ = capaman.jacobian(np.clip(trajectory.position(t - h), lo, hi), geometry, validate=False)
    twist = np.einsum("nij,nj->ni", j, rate1)
    acc = np.einsum("nij,nj->ni", j, rate2) + np.einsum("nij,nj->ni", (j_plus - j_minus) / (2 * h), rate1)
    return RigidMotion(t, pose.position, pose.rotation, twist[:, :3], twist[:, 3:], acc[:, :3], acc[:, 3:])


@dataclass(frozen=True)
class CaPaManValidation:
    """A plan executed and validated: the report, both motions, the run's facts."""

    report: ValidationReport
    planned: RigidMotion
    executed: RigidMotion
    run: ExecutedMotion


def validate_capaman(trajectory: JointTrajectory, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                     dynamics: CaPaManDynamics | None = None, sensors: AccelerometerArray | None = None,
                     tolerances: Tolerances | None = None, settle: float = 0.5, seed: int = 0,
                     delay: float = 0.0, scene: CaPaManDynamicScene | None = None) -> CaPaManValidation:
    """Execute ``trajectory`` on the dynamic CaPaMan and validate it against
    the plan. ``delay`` (s) shifts the executed record in time (a test of
    the verdict: a late execution must fail). ``scene`` may be reused."""
    sensors = sensors or AccelerometerArray.paper_layout()
    own = scene is None
    scene = scene or CaPaManDynamicScene(geometry, dynamics)
    try:
        run = scene.execute(trajectory, settle=settle)
    finally:
        if own:
            scene.close()
    executed: RigidMotion = run
    if delay:
        executed = executed.shifted(delay)
    planned = planned_motion(trajectory, sensors.rate, geometry, settle=settle)
    report = validate(planned, executed, sensors, tolerances=tolerances, seed=seed)
    return CaPaManValidation(report, planned, executed, run)
