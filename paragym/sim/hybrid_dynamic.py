"""The hybrid hexapod + tripod of paper 002 in PyBullet, dynamic fidelity.

Paper 002 validated its planned strokes in a CAD model; here PyBullet is
that model. One multibody: platform A floats on the base (three passive
prismatic joints and a spherical one) and E floats on A the same way; each
hexapod leg hangs from the base on a universal joint (two revolute joints)
and extends along a prismatic actuator; each tripod leg turns on A about its
tangential revolute axis and extends likewise. The legs' tips are tied to
their platforms by point-to-point constraints (the ball joints), so the
platforms are held only by the legs. The nine prismatic actuators are
position-controlled with a force limit; gravity is on.

Masses and motor settings are assumptions (:class:`HybridDynamics`).

Two uses share the scene. :meth:`HybridDynamicScene.execute` runs a whole
planned stroke profile for the KF validation, at the fine settings
(``HybridDynamics()``: 1 ms, 150 solver iterations). The env's dynamic
fidelity steps it one control period at a time (:meth:`drive`,
:meth:`measure`) at :meth:`HybridDynamics.fast`: a 5 ms step, 50 solver
iterations and an error reduction of 0.9 (the solver corrects 90 % of a
joint's drift each step).

Two layouts (``HybridDynamics.layout``) cut the same mechanism into PyBullet
multibodies. "tree", the released default, is the one multibody above.
"split" makes eight: each hexapod leg on its own fixed base (its universal
joint and actuator), A a free body carrying the tripod's three legs, and E a
free body; the nine ball joints then tie bodies together. The joints,
masses and motors are the same, and so is the motion at equal settings (to
solver precision, tested); the split's solver rows span a leg and a
platform instead of the 36-dof tree, so its physics step is cheaper.
:meth:`HybridDynamics.split` (opt-in: a released id's default never
changes) runs it at a 5 ms step, 80 iterations, error reduction 0.9 and a
servo gain of 1 (the servo corrects its whole error each step, a bandwidth
of 200/s).

The contract, checked by ``tests/test_dynamic_fidelity.py`` and
``tests/test_rules.py``: at the default and split settings E tracks its
command on the paper's path within 1.5 mm of the fine settings, and the
ball joints stay closed within 4 mm under any in-Box actions (below the
5 mm at which a v2 episode ends as a broken mechanism). Speeds are
measured by ``benchmarks/env_speed.py``; the figures are in CHANGELOG.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np
from scipy.interpolate import PchipInterpolator

from paragym.mechanisms import hybrid
from paragym.mechanisms.geometry import PartShape, matrix_to_quat, quat_to_matrix
from paragym.sim.client import LinkSpec, motors_of
from paragym.sim.mujoco_sim import ramp_together, read_together, scene_sim, simulate_in

__all__ = ["HybridDynamicScene", "HybridDynamics", "HybridRun", "drive_together", "state_together"]

_ID = (0.0, 0.0, 0.0, 1.0)


@dataclass(frozen=True)
class HybridDynamics:
    """Physical parameters (SI), assumed."""

    platform_a_mass: float = 3.0
    platform_e_mass: float = 1.0
    leg_mass: float = 0.2
    motor_force: float = 800.0  # N per actuator
    position_gain: float = 0.3
    velocity_gain: float = 1.0
    #: the settings that are per physics step: PyBullet's motor position gain corrects that share of the error
    #: per step, a bandwidth of position_gain / time_step; the same model at another step scales them with it
    PER_STEP: ClassVar[tuple[str, ...]] = ("position_gain",)
    time_step: float = 1e-3
    solver_iterations: int = 150
    gravity: float = 9.81
    erp: float | None = None  # the constraint solver's error reduction (None: PyBullet's default)
    #: how the mechanism is cut into PyBullet multibodies: "tree" (one) or "split" (one per hexapod leg,
    #: A with the tripod's legs, E); the same joints and masses (module docstring)
    layout: str = "tree"

    @classmethod
    def fast(cls) -> HybridDynamics:
        """The env's default settings: one tree, a 5 ms step, 50 solver iterations, error reduction 0.9
        (module docstring)."""
        return cls(time_step=5e-3, solver_iterations=50, erp=0.9)

    @classmethod
    def split(cls) -> HybridDynamics:
        """The split layout at a 5 ms step, 80 solver iterations, error reduction 0.9 and a servo gain of 1
        (200/s): opt-in (module docstring)."""
        return cls(time_step=5e-3, solver_iterations=80, erp=0.9, position_gain=1.0, layout="split")


@dataclass(frozen=True)
class HybridRun:
    """A dynamic run at the simulation rate: E's and A's recorded poses
    (world, positions (N, 3), rotations (N, 3, 3)), E's velocities and
    accelerations, the measured strokes (N, 9), and the largest ball-joint
    gap of the run (m)."""

    t: np.ndarray
    e_position: np.ndarray
    e_rotation: np.ndarray
    e_velocity: np.ndarray
    e_angular_velocity: np.ndarray
    e_acceleration: np.ndarray
    e_angular_acceleration: np.ndarray
    a_position: np.ndarray
    strokes: np.ndarray
    closure_error: float


def _quat_z_to(d: np.ndarray) -> tuple[float, float, float, float]:
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, d)
    s, c = np.linalg.norm(axis), float(np.dot(z, d))
    half = np.arctan2(s, c) / 2
    x, y, z = axis / max(s, 1e-12) * np.sin(half)
    return x, y, z, np.cos(half)


class HybridDynamicScene:
    """The dynamic hybrid robot (module docstring), built at the home pose in
    the dynamics' ``layout``: every joint is addressed as (body name, link
    index), so that both layouts share the code below. ``engine``: None for
    PyBullet's physics, a :class:`~paragym.sim.mujoco_sim.MuJoCoSettings` for
    MuJoCo's over the PyBullet world as built, or over the scene described as data with ``mirror=False``
    (:mod:`paragym.sim.mujoco_sim`)."""

    ROBOT = "hybrid"
    #: the exported MJCF's servo bandwidth times its step (:func:`paragym.sim.export.servo_gains`), which the
    #: MuJoCo fidelity runs too: a servo's gains are set for its leg, and the loops hang the platforms on it, so
    #: at the default 0.5 the legs rang under the reference's motion (KF FAIL in 5 of 10 reference episodes in
    #: MuJoCo); at 1.0 none rang (10 of 10 KF PASS); at 1.5 all did (0 of 10)
    EXPORT_SERVO_BANDWIDTH = 1.0

    def __init__(self, geometry: hybrid.HybridGeometry = hybrid.DEFAULT_GEOMETRY,
                 dynamics: HybridDynamics | None = None, gui: bool = False, engine: Any = None) -> None:
        self.geometry = g = geometry
        self.dynamics = d = dynamics or HybridDynamics()
        if d.layout not in ("tree", "split"):
            raise ValueError(f'dynamics.layout must be "tree" or "split"; got {d.layout!r}')
        self.sim = sim = scene_sim(gui, engine)
        sim.set_physics(d.gravity, d.time_step, d.solver_iterations, d.erp)
        home = hybrid.solve(np.zeros(6), 0.5, g)
        t_a, t_t = home.t_a[0], home.t_t[0]
        rod = PartShape("rod", "cylinder", radius=0.008, length=0.05)
        a_shape = PartShape("A", "cylinder", radius=g.platform_radius + 0.015, length=0.01)
        e_shape = PartShape("E", "cylinder", radius=g.r_te + 0.015, length=0.01)
        a_rgba, e_rgba = (0.2, 0.45, 0.8, 1), (0.85, 0.7, 0.2, 1)
        self._frames = []  # each leg's fixed joint frame (orientation of its home direction)
        hexapod = []  # each hexapod leg's links, from the base
        a_world = (t_a[:3, :3] @ g.platform_joints.T).T + t_a[:3, 3]
        for i in range(6):
            direction = a_world[i] - g.base_joints[i]
            q0 = _quat_z_to(direction / np.linalg.norm(direction))
            self._frames.append(q0)
            hexapod.append([LinkSpec(f"h{i}_u", None, "revolute", tuple(g.base_joints[i]), q0, (1, 0, 0)),
                            LinkSpec(f"h{i}_v", f"h{i}_u", "revolute", axis=(0, 1, 0)),
                            LinkSpec(f"h{i}_p", f"h{i}_v", "prismatic", axis=(0, 0, 1), shape=rod,
                                     shape_offset=(0, 0, -0.025), mass=d.leg_mass, rgba=(0.3, 0.3, 0.3, 1))])
        tripod = []  # each tripod leg's links, from platform A
        e_in_a = (t_t[:3, :3] @ g.tripod_top.T).T + t_t[:3, 3]
        for j in range(3):
            direction = e_in_a[j] - g.tripod_base[j]
            z = direction / np.linalg.norm(direction)
            x = g.tripod_axes[j]
            frame = np.column_stack([x, np.cross(z, x), z])
            qj = tuple(matrix_to_quat(frame))
            self._frames.append(qj)
            tripod.append([LinkSpec(f"t{j}_r", "A", "revolute", tuple(g.tripod_base[j]), qj, (1, 0, 0)),
                           LinkSpec(f"t{j}_p", f"t{j}_r", "prismatic", axis=(0, 0, 1), shape=rod,
                                    shape_offset=(0, 0, -0.025), mass=d.leg_mass, rgba=(0.6, 0.2, 0.2, 1))])
        if d.layout == "tree":  # one multibody; A and E float on three prismatic joints and a spherical one
            links = [LinkSpec("a_x", None, "prismatic", axis=(1, 0, 0)),
                     LinkSpec("a_y", "a_x", "prismatic", axis=(0, 1, 0)),
                     LinkSpec("a_z", "a_y", "prismatic", axis=(0, 0, 1)),
                     LinkSpec("A", "a_z", "spherical", mass=d.platform_a_mass, shape=a_shape, rgba=a_rgba),
                     LinkSpec("e_x", "A", "prismatic", axis=(1, 0, 0)),
                     LinkSpec("e_y", "e_x", "prismatic", axis=(0, 1, 0)),
                     LinkSpec("e_z", "e_y", "prismatic", axis=(0, 0, 1)),
                     LinkSpec("E", "e_z", "spherical", mass=d.platform_e_mass, shape=e_shape, rgba=e_rgba)]
            sim.add_tree_body(self.ROBOT, links + [link for leg in hexapod + tripod for link in leg])
            at = lambda link: (self.ROBOT, sim.link_index(self.ROBOT, link))  # noqa: E731
            self._a_float, self._e_float = [at(f"a_{c}") for c in "xyz"], [at(f"e_{c}") for c in "xyz"]
            #: the platforms A and E: (body, link); link -1 is a free body's base
            self.a_platform, self.e_platform = at("A"), at("E")
            sim.no_self_collision(self.ROBOT)
        else:  # each hexapod leg its own fixed-base multibody; A a free base carrying the tripod's legs; E free
            for i, leg in enumerate(hexapod):
                sim.add_tree_body(f"leg{i}", leg)
            sim.add_tree_body("A", [replace(link, parent=None) if link.parent == "A" else link
                                    for leg in tripod for link in leg], d.platform_a_mass, a_shape, a_rgba)
            sim.add_tree_body("E", [], d.platform_e_mass, e_shape, e_rgba)
            at = sim.locate
            self._a_float, self._e_float = [], []
            self.a_platform, self.e_platform = ("A", -1), ("E", -1)
            for body in sim.body_names:
                sim.no_collision(body)
        self.hex_u = [at(f"h{i}_u") for i in range(6)]
        self.hex_v = [at(f"h{i}_v") for i in range(6)]
        self.tri_r = [at(f"t{j}_r") for j in range(3)]
        self.actuators = [at(f"h{i}_p") for i in range(6)] + [at(f"t{j}_p") for j in range(3)]
        #: the nine actuators as motors (body, joints), in the order of the strokes
        self.motors = motors_of(self.actuators)
        sim.servos(self.motors, d.motor_force, d.position_gain, d.velocity_gain)
        for body, link in self._a_float + self._e_float + self.hex_u + self.hex_v + self.tri_r:
            sim.passive(body, [link])
        for body, link in (self.a_platform, self.e_platform):
            if link >= 0:
                sim.passive(body, [], [link])
        for k, (body, link) in enumerate(self.actuators):  # ball joints: leg tip (COM offset -0.025) to its joint
            platform, joint = ((self.a_platform, g.platform_joints[k]) if k < 6 else
                               (self.e_platform, g.tripod_top[k - 6]))
            sim.ball_joint(body, link, [0, 0, 0.025], platform[1], list(joint), other=platform[0])
        self.reset(np.zeros(6), 0.5)
        simulate_in(self, engine)

    def hold(self, duration: float) -> None:
        """Keep the nine strokes' targets (m) where they are for ``duration`` s of simulated time, the motors
        holding the mechanism against gravity under their force limits."""
        self.drive(self._target, duration)

    def motor_limits(self) -> list[tuple[str, int, float]]:
        """The driven joints, (body, joint index, force limit): the nine prismatic actuators, in the order of
        the strokes (N)."""
        return [(body, joint, self.dynamics.motor_force) for body, joint in self.actuators]

    def _set(self, joint: tuple[str, int], value: float | np.ndarray) -> None:
        self.sim.reset_joint(joint[0], joint[1], value if isinstance(value, np.ndarray) else float(value))

    def _place(self, platform: tuple[str, int], floats: list[tuple[str, int]], t: np.ndarray) -> None:
        self.sim.place_free(platform, floats, t[:3, 3], matrix_to_quat(t[:3, :3]))

    def reset(self, p: np.ndarray, delta: float) -> None:
        """Every joint where the kinematics has it for E displacement ``p`` at split ``delta``, at rest."""
        g = self.geometry
        st = hybrid.solve(p, delta, g)
        t_a, t_t = st.t_a[0], st.t_t[0]
        self._place(self.a_platform, self._a_float, t_a)
        # E's pose: in A's frame along the tree's chain, in the world as a free body
        self._place(self.e_platform, self._e_float, t_t if self.e_platform[1] >= 0 else t_a @ t_t)
        a_world = (t_a[:3, :3] @ g.platform_joints.T).T + t_a[:3, 3]
        for i in range(6):
            d = a_world[i] - g.base_joints[i]
            local = quat_to_matrix(np.array(self._frames[i])).T @ (d / np.linalg.norm(d))
            self._set(self.hex_v[i], np.arcsin(np.clip(local[0], -1, 1)))
            self._set(self.hex_u[i], np.arctan2(-local[1], local[2]))
            self._set(self.actuators[i], st.lengths[0, i])
        e_in_a = (t_t[:3, :3] @ g.tripod_top.T).T + t_t[:3, 3]
        for j in range(3):
            d = e_in_a[j] - g.tripod_base[j]
            local = quat_to_matrix(np.array(self._frames[6 + j])).T @ (d / np.linalg.norm(d))
            self._set(self.tri_r[j], np.arctan2(-local[1], local[2]))
            self._set(self.actuators[6 + j], st.lengths[0, 6 + j])
        self._target = st.lengths[0].copy()

    def drive(self, strokes: np.ndarray, duration: float) -> None:
        """Move the nine actuators' targets linearly from the last target to
        ``strokes`` (9,) (m) over ``duration`` s of simulated time, the motors
        chasing them under their force limit."""
        strokes = np.asarray(strokes, float)
        self.sim.ramp(self.motors, self._target, strokes, duration)
        self._target = strokes.copy()

    def measure(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The simulated state now: T_A and T_E (4, 4, base frame) from the
        platforms' poses, and the nine strokes (m) from the actuators' joints."""
        out = []
        for body, link in (self.a_platform, self.e_platform):
            pos, orn = self.sim.link_frame(body, link)
            t = np.eye(4)
            t[:3, :3], t[:3, 3] = quat_to_matrix(orn), pos
            out.append(t)
        return out[0], out[1], self.sim.motor_positions(self.motors)

    def render(self, width: int = 480, height: int = 360) -> np.ndarray:
        """RGB image of the simulated robot (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.0, 0.25), distance=1.1, yaw=35.0, pitch=-20.0)

    def closure_error(self) -> float:
        """Largest ball-joint gap (m) now."""
        g = self.geometry
        frame = lambda joint: self.sim.link_frame(*joint)  # noqa: E731
        worst = 0.0
        for platform, joints, legs in ((self.a_platform, g.platform_joints, self.actuators[:6]),
                                       (self.e_platform, g.tripod_top, self.actuators[6:])):
            pos, orn = frame(platform)
            rot = quat_to_matrix(orn)
            for leg, joint in zip(legs, joints, strict=True):
                worst = max(worst, float(np.linalg.norm(frame(leg)[0] - (pos + rot @ joint))))
        return worst

    def execute(self, u: np.ndarray, strokes: np.ndarray, p0: np.ndarray, delta0: float, duration: float,
                settle: float = 0.5) -> HybridRun:
        """Drive the nine actuators through ``strokes`` (K, 9) given at path
        parameters ``u`` (K,), with u = t / duration, then hold ``settle`` s;
        record E's motion at every step."""
        d, sim = self.dynamics, self.sim
        self.reset(p0, delta0)
        spline = PchipInterpolator(u * duration, strokes)
        rate = spline.derivative()
        n = int(round((duration + settle) / d.time_step)) + 1
        t = np.arange(n) * d.time_step
        target, target_rate = spline(np.clip(t, 0, duration)), np.where((t <= duration)[:, None],
                                                                         rate(np.clip(t, 0, duration)), 0.0)
        pos, orn, vel, omega = (np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3)))
        a_pos, measured = np.empty((n, 3)), np.empty((n, 9))
        closure = 0.0
        for i in range(n):  # the physics is sequential
            if i:
                sim.drive(self.motors, target[i], target_rate[i])
                sim.step()
            pos[i], orn[i], vel[i], omega[i] = sim.link_motion(*self.e_platform, velocity=True)
            a_pos[i] = sim.link_frame(*self.a_platform)[0]
            measured[i] = sim.motor_positions(self.motors)
            if i % 200 == 0:
                closure = max(closure, self.closure_error())
        acc = np.asarray(np.gradient(vel, d.time_step, axis=0))  # (stubs read a 2-D input's gradient as a tuple)
        ang_acc = np.asarray(np.gradient(omega, d.time_step, axis=0))
        return HybridRun(t, pos, quat_to_matrix(orn), vel, omega, acc, ang_acc, a_pos, measured, closure)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()


def drive_together(scenes: Sequence[HybridDynamicScene], strokes: np.ndarray, duration: float, pool: Any = None
                   ) -> None:
    """:meth:`HybridDynamicScene.drive` of each of ``scenes`` (in MuJoCo alone, one geometry and dynamics) to its
    row of ``strokes`` (M, 9) (m) over ``duration`` s, their physics stepped in one batch on ``pool``'s threads
    (:func:`paragym.sim.mujoco_sim.ramp_together`)."""
    strokes = np.asarray(strokes, float)
    first = scenes[0]
    ramp_together([scene.sim for scene in scenes], first.motors, np.array([scene._target for scene in scenes]),
                  strokes, duration, pool)
    for scene, target in zip(scenes, strokes, strict=True):
        scene._target = target.copy()


def state_together(scenes: Sequence[HybridDynamicScene]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`HybridDynamicScene.measure` of each of ``scenes`` (as :func:`drive_together` takes them), T_A and
    T_E (M, 4, 4) and the strokes (M, 9), and the largest ball-joint gap (M,) (m) as MuJoCo's loop closures
    have it (:meth:`~paragym.sim.mujoco_sim.MuJoCoSim.loop_residual`), in one array each."""
    first = scenes[0]
    strokes, position, quaternion, gap = read_together([scene.sim for scene in scenes], first.motors,
                                                       [first.a_platform, first.e_platform])
    t = np.zeros((len(scenes), 2, 4, 4))
    t[..., :3, :3], t[..., :3, 3], t[..., 3, 3] = quat_to_matrix(quaternion), position, 1.0
    return t[:, 0], t[:, 1], strokes, gap
