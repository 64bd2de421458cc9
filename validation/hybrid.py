"""The validation loop for the hybrid robot's plans (paper 002, checked as paper 000 checks CaPaMan).

Paper 002 checked its planned strokes in a CAD model. Here the nine strokes
drive the dynamic PyBullet model, platform E's recorded pose is compared with
the plan, and E's motion goes through the same accelerometer and Kalman
filter validation as CaPaMan's plate (:mod:`paragym.validation.report`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from paragym.sim.hybrid_dynamic import HybridDynamics, HybridDynamicScene, HybridRun
from paragym.validation.motion import RigidMotion, pose_path_motion
from paragym.validation.report import ValidationReport, validate
from paragym.validation.sensors import AccelerometerArray

__all__ = ["HybridPlanned", "HybridValidation", "validate_hybrid"]


class HybridPlanned(Protocol):
    """What the validation needs of a plan (paper 002's planner's ``HybridPlan`` has it; validation imports
    no planner): the path parameter u (K,), the nine strokes (K, 9) m, E's displacements from home (K, 6)
    and E's pose in the base frame (K, 6: x, y, z m, roll, pitch, yaw rad), the split Delta (K,)."""

    u: np.ndarray
    lengths: np.ndarray
    path: np.ndarray
    e_pose: np.ndarray
    delta: np.ndarray


@dataclass(frozen=True)
class HybridValidation:
    """The report, E's largest position and orientation errors against the plan (m, rad), and the run."""

    report: ValidationReport
    position_error: float
    orientation_error: float
    run: HybridRun


def validate_hybrid(plan: HybridPlanned, duration: float = 5.0, dynamics: HybridDynamics | None = None,
                    sensors: AccelerometerArray | None = None, settle: float = 0.3, seed: int = 0,
                    delay: float = 0.0) -> HybridValidation:
    """Execute ``plan`` over ``duration`` s (u = t / duration) on the dynamic
    model and validate E's motion. Sensors default to the paper's layout
    scaled to E (r = 0.06 m, bracket 0.03 m)."""
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be a positive number of seconds; got {duration!r}")
    sensors = sensors or AccelerometerArray.paper_layout(r=0.06, depth=0.03)
    scene = HybridDynamicScene(dynamics=dynamics)
    try:
        run = scene.execute(plan.u, plan.lengths, plan.path[0], float(plan.delta[0]), duration, settle)
    finally:
        scene.close()
    planned = pose_path_motion(plan.u * duration, plan.e_pose, sensors.rate, settle)
    executed = RigidMotion(run.t, run.e_position, run.e_rotation, run.e_velocity, run.e_angular_velocity,
                           run.e_acceleration, run.e_angular_acceleration)
    if delay:
        executed = executed.shifted(delay)
    on_plan = planned.at(np.clip(run.t, 0, planned.t[-1]))
    position_error = float(np.linalg.norm(run.e_position - on_plan.position, axis=1).max())
    rel = np.einsum("nji,njk->nik", on_plan.rotation, run.e_rotation)
    orientation_error = float(np.arccos(np.clip((np.trace(rel, axis1=1, axis2=2) - 1) / 2, -1, 1)).max())
    report = validate(planned, executed, sensors, seed=seed)
    return HybridValidation(report, position_error, orientation_error, run)
