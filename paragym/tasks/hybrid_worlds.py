"""The hybrid's worlds (paper 002): where its robot moves besides the kinematic model.

:class:`DynamicWorld` is the robots under PyBullet's dynamics (one in a single env), :class:`MuJoCoWorld` N
robots under MuJoCo's alone (the native dynamic vector env's, and its N = 1 case); the transition
(:mod:`paragym.tasks.hybrid_step`) commands it and evaluates the robot where
it got. Episode validation reads the validated body from it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from paragym.mechanisms import hybrid
from paragym.mechanisms.geometry import euler_matrix, matrix_euler, pose6
from paragym.sim.client import physics_steps
from paragym.sim.hybrid_dynamic import drive_together, state_together
from paragym.sim.mujoco_sim import rollout_pool

#: the state and parameters the worlds read are the transition's (paragym.tasks.hybrid_step), typed Any
#: here: the transition imports the worlds, not the other way
__all__ = ["DynamicWorld", "MuJoCoWorld"]


class DynamicWorld:
    """Robots under PyBullet's dynamics (:class:`paragym.sim.hybrid_dynamic.HybridDynamicScene`, one per robot;
    a single env has one), or MuJoCo's over the PyBullet scene.

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
    joint open by more than that is a broken mechanism (``broken``). Each
    of these is an array over the robots."""

    def __init__(self, scenes: list[Any], control_period: float, track_tolerance: float,
                 angle_tolerance: float | None = None, broken_gap: float | None = None) -> None:
        self.scenes, self.control_period, self.track_tolerance = scenes, control_period, track_tolerance
        self.angle_tolerance, self.broken_gap = angle_tolerance, broken_gap
        n = len(scenes)
        self.tracked = np.ones(n, bool)
        #: E's position error (m) and orientation error (rad: the angle of the rotation from its commanded to its
        #: simulated attitude) after the last step, per robot
        self.tracking_error, self.orientation_error = np.zeros(n), np.zeros(n)
        self.broken = np.zeros(n, bool)
        #: the last step's commanded displacement of E from home (N, 6): the pose the actuators were driven to
        self.command = np.zeros((n, 6))
        self._work = np.empty((5, 6, 6))

    @property
    def scene(self) -> Any:
        """Robot 0's scene (what KF validation judges, and draws)."""
        return self.scenes[0]

    def reset(self, state: Any, rows: np.ndarray) -> None:
        """Put the simulated robots ``rows`` at their state's (solved) start pose, at rest."""
        for i in rows.tolist():
            self.scenes[i].reset(state.pose[i], float(state.delta[i]))
        self.tracked[rows], self.tracking_error[rows], self.orientation_error[rows] = True, 0.0, 0.0
        self.broken[rows] = False
        self.command[rows] = state.pose[rows]

    def _drive(self, strokes: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, ...]:
        """Drive robots ``rows`` to ``strokes`` (M, 9), one after the other; T_A, T_E (M, 4, 4), the strokes
        (M, 9) and the largest ball-joint gap (M,) (m; 0 where no gap breaks the mechanism) where they got."""
        out: list[list[Any]] = [[], [], [], []]
        for i, target in zip(rows.tolist(), strokes, strict=True):
            scene = self.scenes[i]
            scene.drive(target, self.control_period)
            for part, value in zip(out, (*scene.measure(), scene.closure_error() if self.broken_gap else 0.0),
                                   strict=True):
                part.append(value)
        return tuple(np.array(part) for part in out)

    def move(self, state: Any, rows: np.ndarray) -> None:
        """Drive robots ``rows`` to their commanded strokes (``state.lengths``) and measure."""
        if not rows.size:
            return
        consts = hybrid.kernel_consts(self.scene.geometry)
        self.command[rows] = state.pose[rows]
        t_as, t_es, strokes, gaps = self._drive(state.lengths[rows], rows)
        for k, i in enumerate(rows.tolist()):
            t_a, t_e = t_as[k], t_es[k]
            t_t = np.linalg.solve(t_a, t_e)
            # the rotations as views, as the step's kernel passes them: k_measure compiled once for both
            state.mu_h[i], state.mu_t[i] = hybrid.k_measure(
                t_a[:3, :3], np.ascontiguousarray(t_a[:3, 3]), t_t[:3, :3], np.ascontiguousarray(t_t[:3, 3]),
                *consts[:5], consts[-1], True, np.empty(9), self._work)
            state.lengths[i] = strokes[k]
            state.pose[i, :3] = t_e[:3, 3] - consts[6][:3]
            state.pose[i, 3:] = matrix_euler(t_e[:3, :3])
            state.offset[i] = state.pose[i, :3] - state.nominal[i, state.k[i], :3]
            self.tracking_error[i] = float(np.linalg.norm(state.pose[i, :3] - self.command[i, :3]))
            turn = euler_matrix(*self.command[i, 3:]).T @ t_e[:3, :3]
            self.orientation_error[i] = float(np.arccos(np.clip((np.trace(turn) - 1) / 2, -1.0, 1.0)))
            self.tracked[i] = self.tracking_error[i] <= self.track_tolerance and (
                self.angle_tolerance is None or self.orientation_error[i] <= self.angle_tolerance)
            self.broken[i] = self.broken_gap is not None and gaps[k] > self.broken_gap

    def close(self) -> None:
        for scene in self.scenes:
            scene.close()

    # --- what KF validation reads (paragym.validation.episode), of robot 0 ---
    def body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """Platform E, judged at its centre."""
        scene = self.scene
        return (scene.sim, *scene.e_platform, np.zeros(3), scene.sim.time_step)

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """E's pose of the step: the nominal path plus the action's offset."""
        t_e = hybrid.pose_matrix(hybrid.home_pose(params.geometry) + self.command[0])[0]
        return pose6(t_e[:3, 3], t_e[:3, :3])

    def step_duration(self, state: Any, params: Any) -> float:
        h = self.scene.sim.time_step  # the engine's physics step
        return h * physics_steps(self.control_period, h)


class MuJoCoWorld(DynamicWorld):
    """N robots under MuJoCo's dynamics, MuJoCo alone (``engine.mirror`` False: each scene described as data,
    no PyBullet): their actuators driven together in MuJoCo's ``rollout`` on threads (one per core this process
    may use), each control period from a cold solver start
    (:func:`paragym.sim.hybrid_dynamic.drive_together`); measured as :class:`DynamicWorld` measures, a ball
    joint's gap as MuJoCo's loop closures have it. The native dynamic vector env's world, and for N = 1 the
    single env's."""

    def __init__(self, scenes: list[Any], control_period: float, track_tolerance: float,
                 angle_tolerance: float | None = None, broken_gap: float | None = None) -> None:
        super().__init__(scenes, control_period, track_tolerance, angle_tolerance, broken_gap)
        self._pool = rollout_pool(len(scenes))

    def _drive(self, strokes: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, ...]:
        scenes = [self.scenes[i] for i in rows.tolist()]
        drive_together(scenes, strokes, self.control_period, self._pool)
        return state_together(scenes)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.close()
            self._pool = None
        super().close()


if TYPE_CHECKING:  # the type checker holds the worlds that simulate to what episode validation reads
    from paragym.tasks.base import SimulatedWorld

    _dynamicworld: type[SimulatedWorld] = DynamicWorld
    _mujocoworld: type[SimulatedWorld] = MuJoCoWorld
