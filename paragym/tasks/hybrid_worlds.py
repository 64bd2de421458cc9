"""The hybrid's worlds (paper 002): where its robot moves besides the kinematic model.

:class:`DynamicWorld` is one robot under PyBullet's dynamics; the transition
(:mod:`paragym.tasks.hybrid_step`) commands it and evaluates the robot where
it got. Episode validation reads the validated body from it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from paragym.mechanisms import hybrid
from paragym.mechanisms.geometry import euler_matrix, matrix_euler, pose6
from paragym.sim.client import physics_steps

#: the state and parameters the worlds read are the transition's (paragym.tasks.hybrid_step), typed Any
#: here: the transition imports the worlds, not the other way
__all__ = ["DynamicWorld"]


class DynamicWorld:
    """One robot under PyBullet's dynamics (:class:`paragym.sim.hybrid_dynamic.HybridDynamicScene`).

    A step drives the nine actuators from their last targets to the strokes
    of the commanded pose, linearly over ``control_period`` s of simulated
    time, under their force limits. The robot is then measured: T_A and T_E
    from the platforms' simulated poses, the strokes from the actuators'
    joints, the singularity measures from the simulated stages
    (:func:`paragym.mechanisms.hybrid.k_measure`). The state's pose becomes
    E's simulated pose and its offset E's simulated position minus the
    nominal path, so that the reward's offset term sees a platform that sags
    or lags. ``tracked`` is False once E's position is more than
    ``track_tolerance`` (m) from the commanded one, or, with
    ``angle_tolerance`` (rad; v2), E's orientation more than that from the
    commanded one: that step is not free (in kinematic fidelity both errors
    are 0, so the definition is the same). ``broken_gap`` (m; v2): a ball
    joint open by more than that is a broken mechanism (``broken``)."""

    def __init__(self, scene: Any, control_period: float, track_tolerance: float,
                 angle_tolerance: float | None = None, broken_gap: float | None = None) -> None:
        self.scene, self.control_period, self.track_tolerance = scene, control_period, track_tolerance
        self.angle_tolerance, self.broken_gap = angle_tolerance, broken_gap
        self.tracked = np.ones(1, bool)
        self.tracking_error = 0.0
        #: E's orientation error (rad): the angle of the rotation from its commanded to its simulated attitude
        self.orientation_error = 0.0
        self.broken = False
        #: the last step's commanded displacement of E from home (6,): the pose the actuators were driven to
        self.command = np.zeros(6)
        self._work = np.empty((5, 6, 6))

    def reset(self, state: Any) -> None:
        """Put the simulated robot at the state's (solved) start pose, at rest."""
        self.scene.reset(state.pose[0], float(state.delta[0]))
        self.tracked[0], self.tracking_error, self.orientation_error, self.broken = True, 0.0, 0.0, False
        self.command = state.pose[0].copy()

    def move(self, state: Any) -> None:
        """Drive to the commanded strokes (``state.lengths``) and measure."""
        g = self.scene.geometry
        self.command = state.pose[0].copy()
        self.scene.drive(state.lengths[0], self.control_period)
        t_a, t_e, strokes = self.scene.measure()
        t_t = np.linalg.solve(t_a, t_e)
        consts = hybrid.kernel_consts(g)
        state.mu_h[0], state.mu_t[0] = hybrid.k_measure(
            np.ascontiguousarray(t_a[:3, :3]), np.ascontiguousarray(t_a[:3, 3]), np.ascontiguousarray(t_t[:3, :3]),
            np.ascontiguousarray(t_t[:3, 3]), *consts[:5], consts[-1], True, np.empty(9), self._work)
        state.lengths[0] = strokes
        state.pose[0, :3] = t_e[:3, 3] - consts[6][:3]
        state.pose[0, 3:] = matrix_euler(t_e[:3, :3])
        state.offset[0] = state.pose[0, :3] - state.nominal[0, state.k[0], :3]
        self.tracking_error = float(np.linalg.norm(state.pose[0, :3] - self.command[:3]))
        turn = euler_matrix(*self.command[3:]).T @ t_e[:3, :3]
        self.orientation_error = float(np.arccos(np.clip((np.trace(turn) - 1) / 2, -1.0, 1.0)))
        self.tracked[0] = self.tracking_error <= self.track_tolerance and (
            self.angle_tolerance is None or self.orientation_error <= self.angle_tolerance)
        self.broken = self.broken_gap is not None and self.scene.closure_error() > self.broken_gap

    def close(self) -> None:
        self.scene.close()

    # --- what KF validation reads (paragym.validation.episode) ---
    def body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """Platform E, judged at its centre."""
        scene = self.scene
        return (scene.sim, *scene.e_platform, np.zeros(3), scene.sim.time_step)

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """E's pose of the step: the nominal path plus the action's offset."""
        t_e = hybrid.pose_matrix(hybrid.home_pose(params.geometry) + self.command)[0]
        return pose6(t_e[:3, 3], t_e[:3, :3])

    def step_duration(self, state: Any, params: Any) -> float:
        h = self.scene.sim.time_step  # the engine's physics step
        return h * physics_steps(self.control_period, h)


