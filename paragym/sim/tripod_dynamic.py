"""The mobile tripod of paper 004 under physics, dynamic fidelity: wheels on the ground, legs in a closed chain.

One multibody on the terrain's heightfield (a plane when it is flat), built in PyBullet and simulated there or,
with ``engine`` MuJoCo's settings, in MuJoCo (:mod:`paragym.sim.mujoco_sim`, the same scene code):

* the plate, free (three passive prismatic joints and a spherical one), with
  the three legs of fixed length r hanging from its vertices on passive
  revolute joints whose encoders read eta (the leg turns about the
  tangential axis, eta measured down from the plate's plane: eqs 1-3);
* at each leg's end, on a passive spherical joint (the paper's), a drive
  unit: a chassis on two driven wheels (servos with a torque limit, encoders
  on both) and two frictionless casters 1 cm clear of the ground that only
  stop it pitching over. The three units close the chain through the ground.

Each unit steers itself by driving its wheels apart: it holds the heading it
believes is commanded (plus, for a misaligned unit, its mounting error) from
its own yaw, at the commanded speed. Nothing moves the units but their wheels,
friction, the legs and gravity, so slip is what the contact makes of it:
the units scrub when a misaligned one pulls against the others, slide on a
slippery floor (the ``slip`` scenarios lower the wheels' friction, each unit
to its own random coefficient redrawn every second, down to
``slip_friction`` where the kinematic model's slip would reach the paper's
1 cm/s), climb and roll off the
terrain's bumps, and the push scenario is an external force on one unit,
toward the robot's centre, for 0.1 s at its time.

What the env reads is what the robot would: odometry integrates each unit's
wheel encoders (the mean of its two wheels' travel) along the heading it
believes; eta comes from the leg encoders (the task adds the encoders'
noise); the true unit positions are the spherical joints' simulated
positions, dropped by the units' height onto the ground.

Masses, the wheels' torque limit, friction and the heading gain are
assumptions (paper 004 gives none), in :class:`TripodDynamics`. The units
are heavy (25 kg) so that their wheels' friction carries the legs' outward
thrust; the push is 14,000 N per metre of the scenario's depth (350 N for
the paper's 2.5 cm), calibrated so that the pushed unit ends 2.6 cm from
where it would have been.

The contract, checked by ``tests/test_dynamic_fidelity.py``: on the paper's
drives the dynamic model agrees with the kinematic one where the
disturbance is physical (the misaligned unit's 0.69 m sideways, the push's
2.6 cm, the bumps), and at the default settings (a 5 ms step, 30 solver
iterations) the initial-heading drive ends within 5 mm of a 2 ms,
100-iteration run. How the model was calibrated and the designs that were
measured and not kept are in the docs (``docs/guides/dynamics.md``, "The
mobile tripod's model").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym.mechanisms import tripod as mt
from paragym.mechanisms.geometry import PartShape, matrix_to_quat, quat_to_matrix
from paragym.sim.client import LinkSpec, PyBulletSim, physics_steps
from paragym.sim.mujoco_sim import simulate_in
from paragym.sim.tripod_drive import Terrain

__all__ = ["TripodDynamicScene", "TripodDynamics"]

def _rot_y(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True)
class TripodDynamics:
    """Physical parameters (SI), assumed, and the simulation's settings."""

    plate_mass: float = 10.0
    leg_mass: float = 1.5
    chassis_mass: float = 25.0  # heavy enough that the wheels' friction carries the legs' outward thrust
    wheel_mass: float = 1.0
    wheel_radius: float = 0.1
    wheel_base: float = 0.6  # m between a unit's two wheels: wide enough not to tip under the legs' thrust
    unit_height: float = 0.1  # m from the ground to a unit's spherical joint: at the axle (the wheels' radius)
    wheel_torque: float = 30.0  # N m per wheel
    friction: float = 0.9  # wheel-ground
    slip_friction: float = 0.25  # the wheels' friction where the scenario's slip reaches the paper's 1 cm/s
    heading_gain: float = 4.0  # 1/s: a unit turns toward its heading at this rate per rad of error
    wheel_bandwidth: float = 20.0  # 1/s: the wheel servos correct an angle error at this rate
    acceleration: float = 1.0  # m/s^2: the units' speed ramps to the command at this rate (no wheelspin at start)
    push_force: float = 14000.0  # N per m of the scenario's push depth, for 0.1 s (module docstring)
    time_step: float = 5e-3  # s (module docstring)
    solver_iterations: int = 30
    gravity: float = 9.81

    @classmethod
    def converged(cls) -> TripodDynamics:
        """The same step with 100 solver iterations: the setting at which friction holds below its limit (a
        loaded unit stands still; at 30 iterations it creeps sideways, ``tests/test_dynamic_fidelity.py``) and
        the leaderboard's. Opt-in: the released ids' default keeps the settings they were released with
        (the convergence study on the conformance page gives both)."""
        return cls(solver_iterations=100)


class TripodDynamicScene:
    """The dynamic mobile tripod on ``terrain`` (module docstring)."""

    ROBOT = "tripod"

    def __init__(self, terrain: Terrain, geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY,
                 dynamics: TripodDynamics | None = None, gui: bool = False,
                 region: tuple[float, float, float, float] = (-3.0, 25.0, -5.0, 5.0), engine: Any = None) -> None:
        self.geometry, self.terrain = g, _ = geometry, terrain
        self.dynamics = d = dynamics or TripodDynamics()
        self.sim = sim = PyBulletSim(gui=gui)
        if terrain.bumps:  # a heightfield of 0.1 m cells over ``region`` (x0, x1, y0, y1): the drive's ground
            cell = 0.1
            x0, x1, y0, y1 = region
            nx, ny = int(round((x1 - x0) / cell)) + 1, int(round((y1 - y0) / cell)) + 1
            x, y = np.meshgrid(np.arange(nx) * cell + x0, np.arange(ny) * cell + y0)
            heights = terrain.height(np.stack([x, y], -1))
            mid = (heights.max() + heights.min()) / 2  # PyBullet centres a heightfield on its height range
            sim.add_heightfield("ground", heights, cell, (x0 + (nx - 1) * cell / 2, y0 + (ny - 1) * cell / 2, mid),
                                (0.55, 0.6, 0.45, 1))
        else:  # flat: a plane, the same ground at a third of the cost
            sim.add_plane("ground", (0.55, 0.6, 0.45, 1))
        radius = g.p / math.sqrt(3)
        links = [LinkSpec("x", None, "prismatic", axis=(1, 0, 0)), LinkSpec("y", "x", "prismatic", axis=(0, 1, 0)),
                 LinkSpec("z", "y", "prismatic", axis=(0, 0, 1)),
                 LinkSpec("plate", "z", "spherical", shape=PartShape("plate", "cylinder", radius=radius * 0.6,
                                                                     length=0.04),
                          rgba=(0.85, 0.7, 0.2, 1), mass=d.plate_mass)]
        wheel = PartShape("wheel", "sphere", radius=d.wheel_radius)  # a sphere: robust contact with a heightfield
        caster = PartShape("caster", "sphere", radius=0.04)
        axle = tuple(matrix_to_quat(np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])))  # sphere's z -> chassis y
        self._leg_frames = []
        for i, a in enumerate(g.alphas):  # leg i at vertex i: local x radial, y tangential (the axis), z up
            frame = np.column_stack([[math.cos(a), math.sin(a), 0.0], [-math.sin(a), math.cos(a), 0.0], [0, 0, 1]])
            self._leg_frames.append(tuple(matrix_to_quat(frame)))
            links += [
                LinkSpec(f"leg{i}", "plate", "revolute", (radius * math.cos(a), radius * math.sin(a), 0.0),
                         tuple(matrix_to_quat(frame)), (0.0, 1.0, 0.0), PartShape("leg", "box", (g.r / 2, 0.02, 0.02)),
                         (g.r / 2, 0.0, 0.0), (0.3, 0.3, 0.3, 1), d.leg_mass),
                # the unit hangs from the leg's end on its spherical joint, at its axle's middle
                LinkSpec(f"unit{i}", f"leg{i}", "spherical", (g.r, 0.0, 0.0),
                         shape=PartShape("chassis", "box", (0.2, 0.22, 0.04)), rgba=(0.2, 0.45, 0.8, 1),
                         mass=d.chassis_mass),
                LinkSpec(f"left{i}", f"unit{i}", "revolute", (0.0, d.wheel_base / 2, 0.0), axle, (0, 0, 1), wheel,
                         rgba=(0.1, 0.1, 0.1, 1), mass=d.wheel_mass),
                LinkSpec(f"right{i}", f"unit{i}", "revolute", (0.0, -d.wheel_base / 2, 0.0), axle, (0, 0, 1), wheel,
                         rgba=(0.1, 0.1, 0.1, 1), mass=d.wheel_mass),
                LinkSpec(f"front{i}", f"unit{i}", "fixed", (0.25, 0.0, 0.05 - d.wheel_radius), shape=caster,
                         rgba=(0.6, 0.6, 0.6, 1), mass=0.1),
                LinkSpec(f"back{i}", f"unit{i}", "fixed", (-0.25, 0.0, 0.05 - d.wheel_radius), shape=caster,
                         rgba=(0.6, 0.6, 0.6, 1), mass=0.1)]
        sim.add_tree_body(self.ROBOT, links)
        idx = lambda link: sim.link_index(self.ROBOT, link)  # noqa: E731
        self.plate_float = [idx(n) for n in ("x", "y", "z")]
        self.plate_link = idx("plate")
        self.legs = [idx(f"leg{i}") for i in range(3)]
        self.chassis = [idx(f"unit{i}") for i in range(3)]
        self.wheels = [[idx(f"left{i}"), idx(f"right{i}")] for i in range(3)]
        self.casters = [[idx(f"front{i}"), idx(f"back{i}")] for i in range(3)]
        sim.on_rebuild(self._set_up_physics)
        self._wheel_angle = np.zeros((3, 2))
        self._wheel_target = np.zeros((3, 2))
        self._speed = 0.0
        self._heading = np.zeros(3)
        simulate_in(self, engine)  # MuJoCo's physics where ``engine`` is its settings (None: PyBullet's)
        #: the engine's physics step (s): the dynamics' in PyBullet, the settings' in MuJoCo
        self.base_step = self.sim.time_step
        # the wheels' servos follow their angle references (a velocity motor alone creeps)
        self.sim.servos([(self.ROBOT, [w for pair in self.wheels for w in pair])], d.wheel_torque,
                        d.wheel_bandwidth * self.base_step, 1.0)

    def _set_up_physics(self) -> None:
        """Gravity, the engine's settings, friction, the passive joints (run again when the world is rebuilt)."""
        d, sim = self.dynamics, self.sim
        sim.set_physics(d.gravity, d.time_step, d.solver_iterations)
        sim.friction("ground", [-1], 1.0)  # PyBullet multiplies the two coefficients: the wheels' is the contact's
        sim.no_self_collision(self.ROBOT)
        sim.passive(self.ROBOT, self.plate_float + self.legs, [self.plate_link, *self.chassis])
        sim.friction(self.ROBOT, [w for pair in self.wheels for w in pair], d.friction)
        sim.friction(self.ROBOT, [c for pair in self.casters for c in pair], 0.0)

    def motor_limits(self) -> list[tuple[str, int, float]]:
        """The driven joints, (body, joint index, force limit): the six wheels' servos (N m)."""
        return [(self.ROBOT, wheel, self.dynamics.wheel_torque) for pair in self.wheels for wheel in pair]

    # --- state ----------------------------------------------------------------------------------------------
    def reset(self, units: np.ndarray, eta: np.ndarray, heading: float, heading_error: np.ndarray,
              on_wheels: bool = False) -> None:
        """Put the robot at rest with its units' ground points at ``units``
        (3, 3) and its legs at ``eta`` (3,) (a consistent pair: the drive's
        start), every unit facing its true heading. The world is rebuilt
        first: PyBullet keeps its contacts' cached impulses across joint
        resets, and an episode must not depend on the one before it (a seed
        gives the same drive whatever ran earlier).

        A unit's level chassis stands ``unit_height`` above the ground under its joint, so on a slope the wheel on
        the uphill side starts inside the terrain (13.6 mm on one random drive): PyBullet pushes it out over a few
        steps, MuJoCo's stiff contact launches the unit. With ``on_wheels`` each unit is raised until none of its
        wheels and casters starts inside the terrain (:meth:`_wheel_lift`), and the legs and plate take the pose
        the raised joints give."""
        g, d, sim = self.geometry, self.dynamics, self.sim
        sim.rebuild()
        joints = np.asarray(units, float) + [0.0, 0.0, d.unit_height]
        if on_wheels:
            joints[:, 2] += self._wheel_lift(joints, heading + np.asarray(heading_error, float))
        eta_posed, rotation, centre = mt.forward(joints[None], eta0=np.asarray(eta, float), geometry=g)
        if on_wheels:
            eta = eta_posed[0]
        rotation, centre = rotation[0], centre[0]
        for joint, value in zip(self.plate_float, centre, strict=True):
            sim.reset_joint(self.ROBOT, joint, float(value))
        sim.reset_joint(self.ROBOT, self.plate_link, matrix_to_quat(rotation))
        for i in range(3):
            sim.reset_joint(self.ROBOT, self.legs[i], float(eta[i]))
            # the chassis level and facing its true heading, in the leg's frame
            # numpy's own loops, not BLAS, whose per-CPU kernels round a 3x3 product differently
            leg = np.einsum("ij,jk,kl->il", rotation, quat_to_matrix(np.array(self._leg_frames[i])),
                            _rot_y(float(eta[i])))
            yaw = heading + float(heading_error[i])
            chassis = np.array([[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0, 0, 1]])
            sim.reset_joint(self.ROBOT, self.chassis[i], matrix_to_quat(np.einsum("ji,jk->ik", leg, chassis)))
            for w in self.wheels[i]:
                sim.reset_joint(self.ROBOT, w, 0.0)
        self._wheel_angle[:] = 0.0
        self._wheel_target = np.zeros((3, 2))
        self._speed = 0.0
        self._heading = heading + np.asarray(heading_error, float)

    def _wheel_lift(self, joints: np.ndarray, yaws: np.ndarray) -> np.ndarray:
        """How far (m, (3,)) each unit's joint at ``joints`` (3, 3), its level chassis at yaw ``yaws`` (3,), must
        rise so that none of its spheres (the two wheels about the axle's ends, the two casters) starts inside the
        terrain: a sphere of radius r clears the tangent plane of slope s under its centre from r sqrt(1 + s^2)
        above it."""
        d = self.dynamics
        # the spheres in the chassis frame (x forward, y along the axle): (x, y, z, radius), as built in __init__
        spheres = np.array([[0.0, d.wheel_base / 2, 0.0, d.wheel_radius], [0.0, -d.wheel_base / 2, 0.0, d.wheel_radius],
                            [0.25, 0.0, 0.05 - d.wheel_radius, 0.04], [-0.25, 0.0, 0.05 - d.wheel_radius, 0.04]])
        c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
        xy = joints[:, None, :2] + np.stack([c * spheres[:, 0] - s * spheres[:, 1],
                                             s * spheres[:, 0] + c * spheres[:, 1]], -1)
        height, slope = self.terrain.height_and_gradient(xy)
        lowest = height + spheres[:, 3] * np.sqrt(1.0 + np.sum(slope**2, -1)) - spheres[:, 2]  # the joint's z, (3, 4)
        return np.maximum(lowest.max(axis=1) - joints[:, 2], 0.0)

    def set_friction(self, coefficients: np.ndarray) -> None:
        """Each unit's wheel-ground friction coefficient (3,)."""
        for i in range(3):
            self.sim.friction(self.ROBOT, self.wheels[i], float(coefficients[i]))

    def drive(self, speed: float, duration: float, push: tuple[int, np.ndarray] | None = None,
              push_steps: int = 0) -> np.ndarray:
        """Drive ``duration`` s at ``speed`` (m/s; reached at ``acceleration``), each unit steering to its
        own heading; ``push`` = (unit, force (3,) N) for the first
        ``push_steps`` physics steps (of :attr:`base_step`). Returns each unit's wheel travel (3,) (m,
        the mean of its two encoders' increments times the wheel radius)."""
        d, sim = self.dynamics, self.sim
        turn = np.empty(3)
        for i in range(3):  # the heading loop, at the control rate
            yaw = self._yaw(i)
            error = math.atan2(math.sin(self._heading[i] - yaw), math.cos(self._heading[i] - yaw))
            turn[i] = d.heading_gain * error * d.wheel_base / 2
        sides = np.repeat(turn, 2) * np.tile([-1.0, 1.0], 3)  # left wheels slower, right faster to turn left
        h = self.base_step
        steps = physics_steps(duration, h)
        wheels = [w for pair in self.wheels for w in pair]
        motors = [(self.ROBOT, wheels)]
        target = self._wheel_target.ravel()
        for s in range(steps):  # the wheel servos follow their angle references (a velocity motor alone creeps)
            step_speed = d.acceleration * h
            self._speed = min(speed, self._speed + step_speed) if speed >= self._speed else \
                max(speed, self._speed - step_speed)
            rates = (self._speed + sides) / d.wheel_radius
            target += rates * h
            sim.drive(motors, target, rates)
            if push is not None and s < push_steps:
                sim.push(self.ROBOT, self.chassis[push[0]], push[1])
            sim.step()
        self._wheel_target = target.reshape(3, 2)
        angles = sim.joint_positions(self.ROBOT, wheels).reshape(3, 2)
        travel = (angles - self._wheel_angle).mean(axis=1) * d.wheel_radius
        self._wheel_angle = angles
        return travel

    def _yaw(self, i: int) -> float:
        r = quat_to_matrix(self.sim.link_frame(self.ROBOT, self.chassis[i])[1])
        return math.atan2(r[1, 0], r[0, 0])

    @property
    def eta(self) -> np.ndarray:
        """The leg encoders now (3,), rad."""
        return self.sim.joint_positions(self.ROBOT, self.legs)

    @property
    def units_true(self) -> np.ndarray:
        """The units' ground points now (3, 3): the spherical joints'
        simulated positions, dropped by the units' height."""
        out = np.empty((3, 3))
        for i, chassis in enumerate(self.chassis):
            out[i] = self.sim.link_frame(self.ROBOT, chassis)[0]
        return out - [0.0, 0.0, self.dynamics.unit_height]

    def centre(self) -> np.ndarray:
        """The plate's centre now (3,)."""
        return self.sim.link_frame(self.ROBOT, self.plate_link)[0]

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image around the robot (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=tuple(self.centre()), distance=6.0, yaw=30.0, pitch=-30.0)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
