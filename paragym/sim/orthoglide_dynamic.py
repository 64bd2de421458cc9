"""The 2PRR + table of paper 003 in PyBullet, dynamic fidelity: a closed chain under motors.

One multibody in the horizontal plane: the table on a prismatic joint along
its direction d (rho1), slider A on a prismatic joint along x (rho2) and
slider B along y (rho3), each driven by a position-controlled motor with a
force limit; link AC turns on A and link BC on B about vertical revolute
joints, both passive; the tool point C closes the loop as a point-to-point
constraint between the two links' far ends. Nothing of the analytic model
is imposed after the start: the joints go where the motors, the links'
inertia and the closure take them, and the encoders (the prismatic joints'
positions) are what the env reads.

Masses, force limits and gains are assumptions (paper 003 gives none), set in
:class:`OrthoglideDynamics`. The time step is 5 ms (two steps of the paths'
10 ms samples) and the solver runs 30 iterations: one closure (3 rows) on a
5-dof tree costs little. The motors reach a
ramped target one physics step late, so the tool lags the path by the
distance it travels in one step: on the paper's circle (0.25 m/s) 1.26 mm at
5 ms, against 0.25 mm at 1 ms and 150 iterations, with kappa within 0.001 of
the kinematic one either way (``tests/test_dynamic_fidelity.py`` checks
both).

The table is a 1.1 m plate. Up to v1 it runs at the height of the sliders'
guides, and a path that carries it to the x guide's end stops it there
against the guide (a contact of about 424 N, the motor's force and more):
the tool then leaves the path. From v2 (``table_below_guides``) it runs 2 cm
lower, beneath them, as a machine's table passes under the gantry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym.mechanisms import orthoglide as og
from paragym.mechanisms.geometry import PartShape, quat_to_matrix
from paragym.sim.client import LinkSpec, exact_time_step
from paragym.sim.mujoco_sim import ramp_together, read_together, scene_sim, simulate_in
from paragym.sim.obstacles import Box

__all__ = ["OrthoglideDynamicScene", "OrthoglideDynamics", "drive_together", "state_together"]


@dataclass(frozen=True)
class OrthoglideDynamics:
    """Physical parameters (SI), assumed: a 5 kg table, 1 kg sliders, 1 m
    aluminium links of 0.8 kg, 300 N linear motors that correct a position
    error at 100 /s; the time step and the solver's iterations."""

    table_mass: float = 5.0
    slider_mass: float = 1.0
    link_mass: float = 0.8
    motor_force: float = 300.0  # N, per prismatic motor
    bandwidth: float = 100.0  # 1/s: the motors correct a position error at this rate (below the force limit)
    velocity_gain: float = 1.0
    time_step: float = 5e-3  # s
    solver_iterations: int = 30
    gravity: float = 9.81

    @property
    def position_gain(self) -> float:
        """PyBullet's position gain: its motor asks for the velocity gain x
        (target - position) / time step, so the gain is the bandwidth times the
        step, and the motor behaves the same whatever the step."""
        return self.bandwidth * self.time_step

    @classmethod
    def fine(cls) -> OrthoglideDynamics:
        """1 ms and 150 iterations: the reference the default settings are checked against."""
        return cls(time_step=1e-3, solver_iterations=150)


class OrthoglideDynamicScene:
    """A PyBullet world with one dynamic 2PRR + table (module docstring)."""

    ROBOT = "orthoglide"

    #: the table's height (m): at the guides' height (0.04 below the sliders; v0 and v1), where it can strike
    #: the x guide's end, or beneath them (v2)
    TABLE_Z = {False: -0.04, True: -0.06}

    #: the links that slide along a fixed guide: their prismatic joints are the guides, so in a model file they
    #: touch nothing (:func:`paragym.sim.export.mjcf`). PyBullet's rigid contact with the guide's face carries no
    #: load; MuJoCo's soft one does, with friction along the slide (an overconstrained slider)
    RIDING = ("slider_a", "slider_b")
    #: MuJoCo's servos (:func:`paragym.sim.export.servo_gains`): 100 /s at its 1 ms step, the rate at which
    #: PyBullet's motors correct an error (:attr:`OrthoglideDynamics.bandwidth`); the export's default rings
    #: (the dynamics guide)
    EXPORT_SERVO_BANDWIDTH = 0.1

    def __init__(self, geometry: og.OrthoglideGeometry = og.DEFAULT_GEOMETRY,
                 dynamics: OrthoglideDynamics | None = None, gui: bool = False,
                 table_below_guides: bool = False, engine: Any = None) -> None:
        self.geometry = g = geometry
        self.dynamics = d = dynamics or OrthoglideDynamics()
        self.sim = scene_sim(gui, engine)
        dx, dy = g.direction
        half = g.link / 2
        bar = PartShape("link", "box", (half, 0.012, 0.008))
        links = [
            LinkSpec("table", None, "prismatic", (*g.table_origin, self.TABLE_Z[table_below_guides]),
                     axis=(dx, dy, 0.0),
                     shape=PartShape("table", "box", (0.55, 0.55, 0.01)), shape_offset=(0.1, 0.55, 0.0),
                     rgba=(0.75, 0.75, 0.6, 1.0), mass=d.table_mass),
            LinkSpec("slider_a", None, "prismatic", (g.slider2_origin, 0.0, 0.0), axis=(1.0, 0.0, 0.0),
                     shape=PartShape("slider_a", "box", (0.05, 0.03, 0.02)), rgba=(0.2, 0.45, 0.8, 1.0),
                     mass=d.slider_mass),
            LinkSpec("link_a", "slider_a", "revolute", (0.0, 0.0, 0.03), axis=(0.0, 0.0, 1.0), shape=bar,
                     shape_offset=(half, 0.0, 0.0), rgba=(0.3, 0.3, 0.3, 1.0), mass=d.link_mass),
            LinkSpec("slider_b", None, "prismatic", (0.0, g.slider3_origin, 0.0), axis=(0.0, 1.0, 0.0),
                     shape=PartShape("slider_b", "box", (0.03, 0.05, 0.02)), rgba=(0.2, 0.45, 0.8, 1.0),
                     mass=d.slider_mass),
            LinkSpec("link_b", "slider_b", "revolute", (0.0, 0.0, 0.05), axis=(0.0, 0.0, 1.0), shape=bar,
                     shape_offset=(half, 0.0, 0.0), rgba=(0.35, 0.35, 0.4, 1.0), mass=d.link_mass),
        ]
        self.sim.add_static("guide_x", Box((g.slider2_origin + 0.75, -0.03, -0.03), (0.85, 0.01, 0.01)),
                            (0.4, 0.4, 0.4, 1))
        self.sim.add_static("guide_y", Box((-0.03, g.slider3_origin + 0.75, -0.03), (0.01, 0.85, 0.01)),
                            (0.4, 0.4, 0.4, 1))
        self.sim.add_tree_body(self.ROBOT, links)
        idx = lambda name: self.sim.link_index(self.ROBOT, name)  # noqa: E731
        self.motors = [idx("table"), idx("slider_a"), idx("slider_b")]
        self.links = [idx("link_a"), idx("link_b")]
        sim = self.sim
        sim.set_physics(d.gravity, d.time_step, d.solver_iterations)
        sim.no_self_collision(self.ROBOT)
        sim.passive(self.ROBOT, self.links)
        # the closure at C: the two links' far ends (pivots in the COM frames, at L/2 along x); link B sits
        # 2 cm above link A, so the pin is a vertical offset of that much
        sim.ball_joint(self.ROBOT, self.links[0], [half, 0.0, 0.0], self.links[1], [half, 0.0, -0.02])
        self._target = np.zeros(3)
        self._path_bodies: list[str] = []
        simulate_in(self, engine)  # MuJoCo's physics where ``engine`` is its settings (None: PyBullet's)
        #: the engine's physics step (s): the dynamics' in PyBullet, the settings' in MuJoCo; a step that must
        #: divide a duration exactly is shortened from it (:meth:`drive`)
        self.base_step = self.sim.time_step

    def hold(self, duration: float) -> None:
        """Keep the three motors' targets (m) where they are for ``duration`` s of simulated time, the motors
        holding the mechanism against gravity under their force limits."""
        self.drive(self._target, duration)

    def motor_limits(self) -> list[tuple[str, int, float]]:
        """The driven joints, (body, joint index, force limit): the table's and the two sliders' motors (N)."""
        return [(self.ROBOT, joint, self.dynamics.motor_force) for joint in self.motors]

    def reset(self, rho: np.ndarray) -> None:
        """Every joint where the analytic model has it at rho (3,) (m), at rest."""
        g = self.geometry
        rho = np.asarray(rho, float)
        cx, cy = og.fixed_point(rho[:1], og.forward(rho[None], g), g)[0]
        ax, by = g.slider2_origin + rho[1], g.slider3_origin + rho[2]
        for joint, value in zip(self.motors, rho, strict=True):
            self.sim.reset_joint(self.ROBOT, joint, float(value))
        self.sim.reset_joint(self.ROBOT, self.links[0], math.atan2(cy, cx - ax))
        self.sim.reset_joint(self.ROBOT, self.links[1], math.atan2(cy - by, cx))
        self._target = rho.copy()

    def drive(self, rho: np.ndarray, duration: float, exact: bool = False) -> None:
        """Move the three motors' targets linearly from the last target to
        ``rho`` (m) over ``duration`` s of simulated time: rounded to whole
        physics steps, or, with ``exact``, exactly (the physics step then
        shortened to divide it, the motors' bandwidth kept)."""
        rho = np.asarray(rho, float)
        self._step_for(duration, exact)  # the physics step and the servos for it
        self.sim.ramp([(self.ROBOT, self.motors)], self._target, rho, duration)
        self._target = rho.copy()

    def _step_for(self, duration: float, exact: bool) -> float:
        """The physics step of a drive over ``duration`` s (:meth:`drive`), set in the engine."""
        step = exact_time_step(duration, self.base_step) if exact else self.base_step
        if step != self.sim.time_step:
            self.sim.set_time_step(step)
        d = self.dynamics  # the servos' bandwidth kept at any step
        self.sim.servos([(self.ROBOT, self.motors)], d.motor_force, d.bandwidth * step, d.velocity_gain)
        return step

    @property
    def rho(self) -> np.ndarray:
        """The three encoders now (m)."""
        return self.sim.joint_positions(self.ROBOT, self.motors)

    def tool(self) -> np.ndarray:
        """The tool point C now, at link AC's far end, in the table frame (m, (2,))."""
        pos, orn = self.sim.link_frame(self.ROBOT, self.links[0])
        c = pos[:2] + self.geometry.link * quat_to_matrix(orn)[:2, 0]
        return c - og.fixed_point(self.rho[0], np.zeros(2), self.geometry)

    def closure_error(self) -> float:
        """The gap (m) between the two links' far ends in the plane."""
        ends = []
        for link in self.links:
            pos, orn = self.sim.link_frame(self.ROBOT, link)
            ends.append(pos[:2] + self.geometry.link * quat_to_matrix(orn)[:2, 0])
        return float(np.linalg.norm(ends[0] - ends[1]))

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image from above (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.05, 0.0), distance=3.0, yaw=0.0, pitch=-89.0)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()


def drive_together(scenes: Sequence[OrthoglideDynamicScene], rho: np.ndarray, durations: np.ndarray, exact: bool,
                   pool: Any = None) -> None:
    """:meth:`OrthoglideDynamicScene.drive` of each of ``scenes`` (in MuJoCo alone, one geometry and dynamics) to
    its row of ``rho`` (M, 3) (m) over its ``durations`` (M,) (s), the robots whose drives take the same physics
    steps stepped in one batch on ``pool``'s threads (:func:`paragym.sim.mujoco_sim.ramp_together`)."""
    rho = np.asarray(rho, float)
    groups: dict[tuple[float, float], list[int]] = {}
    for k, (scene, duration) in enumerate(zip(scenes, durations, strict=True)):
        groups.setdefault((float(duration), scene._step_for(float(duration), exact)), []).append(k)
    first = scenes[0]
    for (duration, _), members in groups.items():
        group = [scenes[k] for k in members]
        ramp_together([scene.sim for scene in group], [(first.ROBOT, first.motors)],
                      np.array([scene._target for scene in group]), rho[members], duration, pool)
    for scene, target in zip(scenes, rho, strict=True):
        scene._target = target.copy()


def state_together(scenes: Sequence[OrthoglideDynamicScene]) -> tuple[np.ndarray, np.ndarray]:
    """The encoders (M, 3) (m) of ``scenes`` (as :func:`drive_together` takes them) and the gap (M,) (m) at the
    pin C as MuJoCo's loop closure has it (:meth:`~paragym.sim.mujoco_sim.MuJoCoSim.loop_residual`)."""
    first = scenes[0]
    rho, _, _, gap = read_together([scene.sim for scene in scenes], [(first.ROBOT, first.motors)], [])
    return rho, gap
