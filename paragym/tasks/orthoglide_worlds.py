"""The Orthoglide's worlds (paper 003): where its robot moves besides the kinematic model.

:class:`DynamicWorld` is the robots under PyBullet's dynamics (one in a single env), :class:`MuJoCoWorld` N
robots under MuJoCo's alone (the native dynamic vector env's, and its N = 1 case); the transition
(:mod:`paragym.tasks.orthoglide_step`) commands it and evaluates the robot
where it got. Episode validation reads the validated body from it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from paragym.mechanisms import orthoglide as og
from paragym.sim.client import physics_steps
from paragym.sim.mujoco_sim import rollout_pool
from paragym.sim.orthoglide_dynamic import drive_together, state_together

#: the state and parameters the worlds read are the transition's (paragym.tasks.orthoglide_step), typed Any
#: here: the transition imports the worlds, not the other way
__all__ = ["DynamicWorld", "MuJoCoWorld"]


class DynamicWorld:
    """Robots under physics (:class:`paragym.sim.orthoglide_dynamic.OrthoglideDynamicScene`, one per robot, in
    PyBullet or MuJoCo; a single env has one).

    A step's joints (the least-norm motion and the agent's null-space motion,
    or the agent's joint rates, added to the last command, as a controller
    integrates its own reference) become the three motors' targets, reached
    linearly over the path's time step; the encoders then replace the
    state's joints. The evaluation takes the tool point from them (the
    forward kinematics of the measured joints, where the closed chain put
    C): J, kappa and n there, and the tracking error from the path point,
    which the reward's ``w_track`` term charges in both action modes (in
    kinematic null-space mode it is 0 by construction, so the definition is
    the same). ``gap`` is each robot's gap at the pin C after its last step (m)."""

    def __init__(self, scenes: list[Any], exact_time: bool = False) -> None:
        self.scenes = scenes
        #: each robot's last command to its motors (N, 3) (m)
        self.command = np.zeros((len(scenes), 3))
        self.gap = np.zeros(len(scenes))
        #: simulate each path step over exactly its duration (v1), else over whole physics steps (v0: the
        #: duration rounded to the physics step)
        self.exact_time = exact_time

    @property
    def scene(self) -> Any:
        """Robot 0's scene (what KF validation judges, and draws)."""
        return self.scenes[0]

    def reset(self, state: Any, rows: np.ndarray) -> None:
        """Put the simulated robots ``rows`` at their state's joints, at rest."""
        for i in rows.tolist():
            self.scenes[i].reset(state.rho[i])
        self.command[rows] = state.rho[rows]
        self.gap[rows] = 0.0

    def _drive(self, rows: np.ndarray, durations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Drive robots ``rows`` to their commands over ``durations`` (M,) (s; 0: no drive), one after the other;
        the encoders (M, 3) and the gaps at C (M,) where they got."""
        rho, gap = np.empty((len(rows), 3)), np.empty(len(rows))
        for k, (i, duration) in enumerate(zip(rows.tolist(), durations, strict=True)):
            scene = self.scenes[i]
            if duration > 0:
                scene.drive(self.command[i], float(duration), exact=self.exact_time)
            rho[k], gap[k] = scene.rho, scene.closure_error()
        return rho, gap

    def move(self, state: Any, rows: np.ndarray, durations: np.ndarray) -> None:
        """Drive robots ``rows`` to their commanded joints (``state.rho``) over ``durations`` (M,) (s) and read
        the encoders."""
        if not rows.size:
            return
        self.command[rows] = state.rho[rows]
        state.rho[rows], self.gap[rows] = self._drive(rows, durations)

    def close(self) -> None:
        for scene in self.scenes:
            scene.close()

    # --- what KF validation reads (paragym.validation.episode), of robot 0 ---
    def body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """The tool holder at C on link AC."""
        scene = self.scene
        return (scene.sim, scene.ROBOT, scene.links[0], np.array([scene.geometry.link, 0.0, 0.0]),
                scene.base_step)

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """C and link AC's direction from the commanded joints (paper 003, eqs 1-6), at the link's height."""
        g, rho = params.geometry, self.command[0]
        c = og.fixed_point(rho[:1], og.forward(rho[None], g), g)[0]
        yaw = np.arctan2(c[1], c[0] - (g.slider2_origin + rho[1]))
        sim, robot, link, _, _ = self.body()
        return np.array([c[0], c[1], sim.link_frame(robot, link)[0][2], 0.0, 0.0, yaw])

    def step_duration(self, state: Any, params: Any) -> float:
        h, k = self.scene.base_step, int(state.k[0])
        return h * physics_steps(float(state.dt[0, k - 1]), h) if k > 0 else 0.0


class MuJoCoWorld(DynamicWorld):
    """N robots under MuJoCo's dynamics, MuJoCo alone (``engine.mirror`` False: each scene described as data, no
    PyBullet): the robots whose path steps take the same physics steps driven together in MuJoCo's ``rollout``
    on threads, each control period from a cold solver start
    (:func:`paragym.sim.orthoglide_dynamic.drive_together`); the gap at C as MuJoCo's loop closure has it. The
    native dynamic vector env's world, and for N = 1 the single env's."""

    def __init__(self, scenes: list[Any], exact_time: bool = False) -> None:
        super().__init__(scenes, exact_time)
        self._pool = rollout_pool(len(scenes))

    def _drive(self, rows: np.ndarray, durations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        moving = durations > 0
        if moving.any():
            drive_together([self.scenes[i] for i in rows[moving].tolist()], self.command[rows[moving]],
                           durations[moving], self.exact_time, self._pool)
        return state_together([self.scenes[i] for i in rows.tolist()])

    def close(self) -> None:
        if self._pool is not None:
            self._pool.close()
            self._pool = None
        super().close()


if TYPE_CHECKING:  # the type checker holds the worlds that simulate to what episode validation reads
    from paragym.tasks.base import SimulatedWorld

    _dynamicworld: type[SimulatedWorld] = DynamicWorld
    _mujocoworld: type[SimulatedWorld] = MuJoCoWorld
