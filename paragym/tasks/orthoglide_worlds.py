"""The Orthoglide's worlds (paper 003): where its robot moves besides the kinematic model.

:class:`DynamicWorld` is one robot under PyBullet's dynamics; the transition
(:mod:`paragym.tasks.orthoglide_step`) commands it and evaluates the robot
where it got. Episode validation reads the validated body from it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from paragym.mechanisms import orthoglide as og
from paragym.sim.client import physics_steps

#: the state and parameters the worlds read are the transition's (paragym.tasks.orthoglide_step), typed Any
#: here: the transition imports the worlds, not the other way
__all__ = ["DynamicWorld"]


class DynamicWorld:
    """One robot under physics (:class:`paragym.sim.orthoglide_dynamic.OrthoglideDynamicScene`, in PyBullet or
    MuJoCo).

    A step's joints (the least-norm motion and the agent's null-space motion,
    or the agent's joint rates, added to the last command, as a controller
    integrates its own reference) become the three motors' targets, reached
    linearly over the path's time step; the encoders then replace the
    state's joints. The evaluation takes the tool point from them (the
    forward kinematics of the measured joints, where the closed chain put
    C): J, kappa and n there, and the tracking error from the path point,
    which the reward's ``w_track`` term charges in both action modes (in
    kinematic null-space mode it is 0 by construction, so the definition is
    the same)."""

    def __init__(self, scene: Any, exact_time: bool = False) -> None:
        self.scene = scene
        self.command = np.zeros(3)
        #: simulate each path step over exactly its duration (v1), else over whole physics steps (v0: the
        #: duration rounded to the physics step)
        self.exact_time = exact_time

    def reset(self, state: Any) -> None:
        """Put the simulated robot at the state's joints, at rest."""
        self.scene.reset(state.rho[0])
        self.command = state.rho[0].copy()

    def move(self, state: Any, duration: float) -> None:
        """Drive to the commanded joints over ``duration`` s and read the encoders."""
        self.command = state.rho[0].copy()
        if duration > 0:
            self.scene.drive(self.command, duration, exact=self.exact_time)
        state.rho[0] = self.scene.rho

    def close(self) -> None:
        self.scene.close()

    # --- what KF validation reads (paragym.validation.episode) ---
    def body(self) -> tuple[Any, str, int, np.ndarray, float]:
        """The tool holder at C on link AC."""
        scene = self.scene
        return (scene.sim, scene.ROBOT, scene.links[0], np.array([scene.geometry.link, 0.0, 0.0]),
                scene.base_step)

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """C and link AC's direction from the commanded joints (paper 003, eqs 1-6), at the link's height."""
        g, rho = params.geometry, self.command
        c = og.fixed_point(rho[:1], og.forward(rho[None], g), g)[0]
        yaw = np.arctan2(c[1], c[0] - (g.slider2_origin + rho[1]))
        sim, robot, link, _, _ = self.body()
        return np.array([c[0], c[1], sim.link_frame(robot, link)[0][2], 0.0, 0.0, yaw])

    def step_duration(self, state: Any, params: Any) -> float:
        h, k = self.scene.base_step, int(state.k[0])
        return h * physics_steps(float(state.dt[0, k - 1]), h) if k > 0 else 0.0


