"""The physics engine a built dynamic scene runs on: one interface, two engines.

A dynamic scene (:mod:`paragym.sim.capaman_dynamic` and the others) builds its mechanism once, then at every
control period drives its servos, steps the physics and reads the encoders, frames and loop gaps; a reset poses
its joints again and may swap its obstacles. :class:`Sim` is everything it asks of its engine after the build:
:class:`~paragym.sim.client.PyBulletSim` implements it, and so does :class:`~paragym.sim.mujoco_sim.MuJoCoSim`
(MuJoCo's physics over the scene as PyBullet or a :class:`~paragym.sim.description.SceneDescription` holds it).
The type checker holds both to it (the assignments at the end of this module); ``tests/test_engine.py`` checks
the parameters' names too.

Bodies by name; joints and links by (body, index), -1 a base; lengths in m, angles in rad, forces in N or N m,
times in s; quaternions xyzw.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from paragym.sim.recipes import Recipe, Vector

__all__ = ["Motors", "Sim"]

#: the motors of a call: (body, joints) pairs, their values in this order
Motors = Sequence[tuple[str, Sequence[int]]]


class Sim(Protocol):
    """What a built dynamic scene asks of its engine (module docstring)."""

    #: the physics step (s) the engine integrates with now
    time_step: float

    # --- the scene's bookkeeping ------------------------------------------------------------------------
    @property
    def loops(self) -> dict[tuple[str, str | None, str, str | None], tuple[tuple[float, ...], tuple[float, ...]]]:
        """The loop closures: (body a, link a, body b, link b) -> the two points, each in its link's frame."""
        ...

    @property
    def stops(self) -> dict[tuple[str, str | None], tuple[float, float]]:
        """The joints' hard stops: (body, link) -> (lower, upper)."""
        ...

    @property
    def recipes(self) -> dict[str, Recipe]:
        """How each body was built (:mod:`paragym.sim.recipes`), in order."""
        ...

    @property
    def body_names(self) -> tuple[str, ...]:
        """The bodies in the scene."""
        ...

    @property
    def servo_settings(self) -> dict[tuple[str, int], tuple[float, float, float]]:
        """Each servo's force limit and PyBullet's gains, (body, joint) -> (force, position gain, velocity gain)."""
        ...

    def link_name(self, name: str, index: int) -> str | None: ...

    def link_index(self, name: str, link: str) -> int: ...

    def locate(self, link: str) -> tuple[str, int]: ...

    # --- the set-up (run again where a rebuild asks it) ---------------------------------------------------
    def set_physics(self, gravity: float, time_step: float, solver_iterations: int,
                    erp: float | None = None) -> None: ...

    def servos(self, motors: Motors, force: float, position_gain: float, velocity_gain: float) -> None:
        """The servos of ``motors`` from now on: their force limit, and PyBullet's normalised gains."""
        ...

    def no_self_collision(self, *names: str) -> None: ...

    def passive(self, name: str, joints: Sequence[int], spherical: Sequence[int] = ()) -> None: ...

    def ball_joint(self, name: str, link_a: int, pivot_a: Vector, link_b: int, pivot_b: Vector,
                   other: str | None = None) -> None: ...

    def no_collision(self, name: str) -> None: ...

    def joint_stops(self, name: str, joints: Sequence[int], lower: float, upper: float) -> None: ...

    def on_rebuild(self, setup: Callable[[], None]) -> None: ...

    def friction(self, name: str, links: Sequence[int], lateral: float) -> None: ...

    def contact_friction(self, name: str, link: int) -> float: ...

    # --- obstacles ----------------------------------------------------------------------------------------------
    def add_static(self, name: str, shape: Any, rgba: Vector = (0.7, 0.3, 0.3, 1.0)) -> None: ...

    def add_static_group(self, name: str, shapes: Sequence[Any],
                         rgba: Vector = (0.7, 0.3, 0.3, 1.0)) -> None: ...

    def remove(self, name: str) -> None: ...

    def rebuild(self) -> None: ...

    # --- posing -----------------------------------------------------------------------------------------------
    def reset_joint(self, name: str, joint: int, value: float | Vector) -> None: ...

    def reset_base(self, name: str, position: Vector, quaternion: Vector) -> None: ...

    def place_free(self, part: tuple[str, int], floats: Sequence[tuple[str, int]], position: Vector,
                   quaternion: Vector) -> None: ...

    # --- dynamics -----------------------------------------------------------------------------------------------
    def drive(self, motors: Motors, targets: Vector, rates: Vector) -> None:
        """The servos of ``motors`` chase ``targets`` at ``rates`` from the next step on."""
        ...

    def ramp(self, motors: Motors, start: np.ndarray, goal: np.ndarray, duration: float) -> None:
        """The servos' targets moved linearly from ``start`` to ``goal`` over ``duration``, stepping."""
        ...

    def push(self, name: str, link: int, force: Vector) -> None: ...

    def step(self) -> None: ...

    def set_time_step(self, time_step: float) -> None: ...

    # --- reading ------------------------------------------------------------------------------------------------
    def link_frame(self, name: str, link: str | int) -> tuple[np.ndarray, np.ndarray]: ...

    def link_motion(self, name: str, link: str | int, velocity: bool = False) -> tuple[np.ndarray, ...]: ...

    def motor_positions(self, motors: Motors) -> np.ndarray: ...

    def joint_positions(self, name: str, joints: Sequence[int]) -> np.ndarray: ...

    def motor_forces(self, motors: Motors) -> np.ndarray: ...

    def joint_values(self, name: str) -> list[tuple[float, ...]]: ...

    def loop_residual(self) -> float: ...

    def clearance(self, name: str, others: Sequence[str], max_distance: float,
                  links: Sequence[int] | None = None) -> tuple[float, str | None]: ...

    def render(self, width: int, height: int, target: Vector, distance: float, yaw: float, pitch: float,
               fov: float = 45.0) -> np.ndarray: ...

    def close(self) -> None: ...


if TYPE_CHECKING:  # both engines implement Sim: the type checker fails here where one does not
    from paragym.sim.client import PyBulletSim
    from paragym.sim.mujoco_sim import MuJoCoSim

    def _pybullet(sim: PyBulletSim) -> Sim:
        return sim

    def _mujoco(sim: MuJoCoSim) -> Sim:
        return sim
