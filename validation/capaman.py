"""The validation loop for CaPaMan plans: execute in the dynamic simulation, validate.

The generic parts (:mod:`paragym.validation.motion`, ``sensors``, ``kalman``,
``report``) know nothing of CaPaMan; this module joins them to the planner's
trajectory and the dynamic PyBullet model (paper 000, section 5).
"""

from __future__ import annotations

from dataclasses import dataclass

from paragym.mechanisms import capaman
from paragym.sim.capaman_dynamic import CaPaManDynamics, CaPaManDynamicScene, ExecutedMotion
from paragym.trajectories import JointTrajectory
from paragym.validation.motion import RigidMotion, capaman_planned_motion
from paragym.validation.report import Tolerances, ValidationReport, validate
from paragym.validation.sensors import AccelerometerArray

__all__ = ["CaPaManValidation", "validate_capaman"]


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
    planned = capaman_planned_motion(trajectory, sensors.rate, geometry, settle=settle)
    report = validate(planned, executed, sensors, tolerances=tolerances, seed=seed)
    return CaPaManValidation(report, planned, executed, run)
