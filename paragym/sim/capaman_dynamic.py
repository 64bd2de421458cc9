"""The CaPaMan in PyBullet, dynamic fidelity: the closed chain under motors.

The kinematic tree of :func:`paragym.sim.capaman_scene.capaman_links` gets
masses, a slider on each rail (the prismatic joint s_k, passive), and the
loop closures as PyBullet point-to-point constraints: each parallelogram's
crank b tip to its coupler's far end, and each slider to its ball joint p_k on
the plate (the plate floats on three passive prismatic joints and a passive
spherical one, so it is a free rigid body held only by the three legs).
Crank a of each leg is driven by a position-controlled motor with a torque
limit; every other joint is free; gravity is on. Nothing of the analytic
model is imposed after the initial state: the executed motion lags,
overshoots and sags as the physics makes it.

Masses, torque limit and gains are assumptions (the paper gives none), set
in :class:`CaPaManDynamics`.

Contact, loops and stops. The obstacles are rigid bodies and PyBullet's
contact solver stops every part at every physics step. The loop closures are
constraints that the solver satisfies to its tolerance, so how closed they
stay depends on the settings, most of all when the motors push a part into
an obstacle at their torque limit. The contract, checked by
``tests/test_rules.py`` for the released settings and for every preset:

* free motion: the loops stay closed within 0.1 mm;
* pushed into an obstacle at the torque limit: within 1 mm, and the tool tip
  within 1 mm of where the released settings put it under the same push;
* presets have joint stops (:attr:`CaPaManDynamics.joint_stops`) just
  outside the commanded range 45-135 deg, so that a push on an obstacle
  cannot force a crank round or flip a parallelogram. The released settings
  have none (their episodes end at the first contact, before a crank can be
  forced), so that the released ids keep their motion bit for bit.

Presets (opt-in: the released ids keep the released settings by default):
:meth:`CaPaManDynamics.fast` takes a 5 ms step with 100 solver iterations
and an error reduction of 0.95 (the solver corrects 95 % of a loop's drift
each step); :meth:`CaPaManDynamics.split` the same settings in the split
layout. Their speed against the released settings is measured by
``benchmarks/env_speed.py``; the figures are in CHANGELOG.md.

Two layouts (``CaPaManDynamics.layout``) cut the same mechanism into PyBullet
multibodies: "tree", the released one above, and "split", one multibody per
leg on its fixed base (cranks, coupler, bar, rail and slider, its
parallelogram closed inside it) and the plate with its tool as a free body,
tied to the legs by the three ball joints. The joints, masses and motors are
the same, and so is the motion at equal settings (to solver precision,
tested); the split's physics step is cheaper, since each closure's solver
rows span a leg and the plate instead of the whole tree.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np

from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import PartShape, quat_to_matrix
from paragym.sim.capaman_scene import capaman_links
from paragym.sim.client import LinkSpec, motors_of
from paragym.sim.mujoco_sim import ramp_together, read_together, scene_sim, simulate_in
from paragym.sim.obstacles import Box
from paragym.trajectories import JointTrajectory, RigidMotion

__all__ = ["CONTACT_PUSHES", "CaPaManDynamicScene", "CaPaManDynamics", "ExecutedMotion", "drive_together",
           "push_into", "state_together"]


@dataclass(frozen=True)
class CaPaManDynamics:
    """Physical parameters (SI). Assumed: aluminium-like parts, a 2 kg plate,
    8 N m crank motors; PyBullet's motor gains are its normalised ones."""

    crank_mass: float = 0.15
    coupler_mass: float = 0.15
    bar_mass: float = 0.15
    rail_mass: float = 0.2
    slider_mass: float = 0.05
    plate_mass: float = 2.0
    tool_mass: float = 0.1
    motor_torque: float = 8.0  # N m, per crank
    position_gain: float = 0.3
    velocity_gain: float = 1.0
    #: the settings that are per physics step: PyBullet's motor position gain corrects that share of the error
    #: per step, a bandwidth of position_gain / time_step; the same model at another step scales them with it
    PER_STEP: ClassVar[tuple[str, ...]] = ("position_gain",)
    time_step: float = 1e-3  # s
    solver_iterations: int = 150
    gravity: float = 9.81
    #: the constraint solver's error reduction (share of a loop's drift corrected per step); None: PyBullet's
    erp: float | None = None
    #: hard stops on the cranks, ``stop_margin`` (rad) outside the commanded range 45-135 deg (as a servo's soft
    #: limits sit inside its mechanical ones, so that a crank held at the end of its range never rests on its
    #: stop). The released settings have none: PyBullet's limit rows change the solver's results even where no
    #: stop is reached, so the released ids' default keeps its motion; every preset has them
    joint_stops: bool = False
    stop_margin: float = math.radians(1.0)

    #: how the mechanism is cut into PyBullet multibodies: "tree" (one) or "split" (one per leg, and the
    #: plate with its tool); the same joints and masses (module docstring)
    layout: str = "tree"

    @classmethod
    def fast(cls) -> CaPaManDynamics:
        """A 5 ms step, 100 solver iterations and an error reduction of 0.95, with joint stops (module
        docstring): opt-in, because the released ids' dynamic fidelity keeps the settings it was released with."""
        return cls(time_step=5e-3, solver_iterations=100, erp=0.95, joint_stops=True)

    @classmethod
    def split(cls) -> CaPaManDynamics:
        """:meth:`fast`'s settings in the split layout: the same motion at a lower cost (module docstring)."""
        return replace(cls.fast(), layout="split")


@dataclass(frozen=True)
class ExecutedMotion(RigidMotion):
    """What the dynamic run did, at the simulation rate (world frame, SI): the
    plate centre H's motion (PyBullet's pose and velocities; accelerations by
    central differences), the measured crank angles ``alpha``, and the
    largest loop-closure error of the run."""

    alpha: np.ndarray
    closure_error: float


def _dynamic_links(g: capaman.CaPaManGeometry, d: CaPaManDynamics) -> list[LinkSpec]:
    masses = {"crank_a": d.crank_mass, "crank_b": d.crank_mass, "coupler": d.coupler_mass, "bar": d.bar_mass,
              "rail": d.rail_mass, "plate": d.plate_mass, "tool": d.tool_mass}
    links = []
    for link in capaman_links(g):
        kind = "plate" if link.name == "plate" else link.name.split("_", 1)[-1]
        links.append(replace(link, mass=masses.get(kind, 1e-3)))
        if kind == "rail":  # the slider runs along the rail (its local z, w_k)
            leg = link.name.split("_")[0]
            slider = PartShape(f"{leg}_slider", "box", (0.012, 0.012, 0.012))
            links.append(LinkSpec(f"{leg}_slider", link.name, "prismatic", axis=(0.0, 0.0, 1.0), shape=slider,
                                  rgba=(0.8, 0.8, 0.8, 1.0), mass=d.slider_mass))
    return links


class CaPaManDynamicScene:
    """A PyBullet world with one dynamic CaPaMan.

    Args:
        geometry: the mechanism's dimensions.
        dynamics: masses, motors and integration settings.
        engine: None: PyBullet's physics; a :class:`~paragym.sim.mujoco_sim.MuJoCoSettings`: MuJoCo's, over
            the PyBullet world as built, or with ``mirror=False`` over the scene described as data (MuJoCo
            alone; PyBullet built only if a distance or a picture is asked for) (:mod:`paragym.sim.mujoco_sim`).
    """

    ROBOT = "capaman"
    #: the exported MJCF's servo bandwidth times its step (:func:`paragym.sim.export.servo_gains`): at the
    #: default 0.5 the crank servos, held against the loops that carry the plate, chattered by +-7 N m about
    #: their mean holding torque in MuJoCo; at 0.25 they hold it still, sagging as little (0.1 mm)
    EXPORT_SERVO_BANDWIDTH = 0.25

    def __init__(self, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                 dynamics: CaPaManDynamics | None = None, gui: bool = False, clearance_cap: float = 0.05,
                 engine: Any = None) -> None:
        self.geometry = g = geometry
        self.clearance_cap = clearance_cap
        self.obstacles: tuple = ()
        self.dynamics = d = dynamics or CaPaManDynamics()
        if d.layout not in ("tree", "split"):
            raise ValueError(f'dynamics.layout must be "tree" or "split"; got {d.layout!r}')
        self.sim = sim = scene_sim(gui, engine)
        links = _dynamic_links(g, d)
        if d.layout == "tree":  # one multibody; the plate floats on three prismatic joints and a spherical one
            sim.add_tree_body(self.ROBOT, links)
            #: the mechanism's bodies
            self.bodies: tuple[str, ...] = (self.ROBOT,)
        else:  # each leg its own fixed-base multibody; the plate (with its tool) a free body
            by_name = {link.name: link for link in links}
            for k in (1, 2, 3):
                sim.add_tree_body(f"leg{k}", [link for link in links if link.name.startswith(f"leg{k}_")])
            plate = by_name["plate"]
            sim.add_tree_body("plate", [replace(by_name["tool"], parent=None)], plate.mass, plate.shape, plate.rgba)
            self.bodies = ("leg1", "leg2", "leg3", "plate")
        at = sim.locate
        legs = (1, 2, 3)
        #: the crank motors (body, joint), legs 1-3
        self.motors = [at(f"leg{k}_crank_a") for k in legs]
        self.cranks_b = [at(f"leg{k}_crank_b") for k in legs]
        self.couplers = [at(f"leg{k}_coupler") for k in legs]
        self.sliders = [at(f"leg{k}_slider") for k in legs]
        #: the plate (body, link); link -1 is a free body's base
        self.plate = at("plate") if d.layout == "tree" else ("plate", -1)
        self.float_joints = [at(f"plate_{c}") for c in "xyz"] if d.layout == "tree" else []
        self._motors = motors_of(self.motors)
        self.sim.on_rebuild(self._set_up_physics)
        self.reset(g.alpha_home)  # the pose the export writes the servos' gains at
        self._target = np.asarray(g.alpha_home, float).copy()
        simulate_in(self, engine)

    def _set_up_physics(self) -> None:
        """Gravity, the engine's parameters, the passive joints, no self-collision and the six loop
        closures (run again whenever the world is rebuilt)."""
        g, d, sim = self.geometry, self.dynamics, self.sim
        sim.set_physics(d.gravity, d.time_step, d.solver_iterations, d.erp)
        sim.servos(self._motors, d.motor_torque, d.position_gain, d.velocity_gain)
        sim.no_self_collision(*self.bodies)  # the parts of one mechanism do not collide with each other
        for body, joint in self.motors + self.cranks_b if d.joint_stops else ():  # these joints turn by -alpha
            sim.joint_stops(body, [joint], -g.alpha_max - d.stop_margin, -g.alpha_min + d.stop_margin)
        for body, joint in self.cranks_b + self.couplers + self.sliders + self.float_joints:
            sim.passive(body, [joint])
        if self.plate[1] >= 0:
            sim.passive(self.plate[0], [], [self.plate[1]])
        for k in range(3):  # loop closures: parallelogram, then ball joint (frames at the links' COMs)
            (leg, crank_b), (_, coupler), (_, slider) = self.cranks_b[k], self.couplers[k], self.sliders[k]
            sim.ball_joint(leg, crank_b, [0, 0, g.a / 2], coupler, [0, 0, g.c / 2])
            sim.ball_joint(leg, slider, [0, 0, 0], self.plate[1], list(g.plate_points[k]), other=self.plate[0])

    def hold(self, duration: float) -> None:
        """Keep the cranks' targets (rad) where they are for ``duration`` s of simulated time, the motors
        holding the mechanism against gravity under their force limits."""
        self.drive(self._target, duration)

    def motor_limits(self) -> list[tuple[str, int, float]]:
        """The driven joints, (body, joint index, force limit): the three crank motors (N m)."""
        return [(body, joint, self.dynamics.motor_torque) for body, joint in self.motors]

    def reset(self, alpha: np.ndarray) -> None:
        """Put every joint where the analytic model has it at ``alpha`` (rad), at rest."""
        g, sim = self.geometry, self.sim
        al = capaman.check_joint_angles(alpha, g)
        pose = capaman.forward(al, g)
        for k in range(3):
            a = float(al[0, k])
            for joint, value in ((self.motors[k], -a), (self.cranks_b[k], -a), (self.couplers[k], a),
                                 (self.sliders[k], float(pose.sliders[0, k]))):
                sim.reset_joint(*joint, value)
        sim.place_free(self.plate, self.float_joints, pose.position[0], pose.quaternion[0])

    def closure_error(self) -> float:
        """Largest gap (m) of the six loop closures now."""
        g = self.geometry
        frame = lambda joint: self.sim.link_frame(*joint)  # noqa: E731
        p_pos, p_orn = frame(self.plate)
        rot = quat_to_matrix(p_orn)
        worst = 0.0
        for k in range(3):
            ball = p_pos + rot @ g.plate_points[k]
            worst = max(worst, float(np.linalg.norm(frame(self.sliders[k])[0] - ball)))
            b_pos, b_orn = frame(self.cranks_b[k])
            c_pos, c_orn = frame(self.couplers[k])
            tip_b = b_pos + quat_to_matrix(b_orn)[:, 2] * g.a
            end_c = c_pos + quat_to_matrix(c_orn)[:, 2] * g.c
            worst = max(worst, float(np.linalg.norm(tip_b - end_c)))
        return worst

    def execute(self, trajectory: JointTrajectory, settle: float = 0.5) -> ExecutedMotion:
        """Drive the cranks along ``trajectory`` (targets alpha(t), alpha_dot(t)
        every step), then hold the last targets for ``settle`` s; record the
        plate's motion at every step."""
        d, sim = self.dynamics, self.sim
        self.reset(trajectory.position(np.array([0.0]))[0])
        n = int(round((trajectory.duration + settle) / d.time_step)) + 1
        t = np.arange(n) * d.time_step
        target, target_rate = trajectory.position(t), trajectory.velocity(t)
        pos, orn = np.empty((n, 3)), np.empty((n, 4))
        vel, omega, alpha = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        closure = 0.0
        for i in range(n):  # the physics is sequential: one step after the other
            if i:
                sim.drive(self._motors, -target[i], -target_rate[i])
                sim.step()
            pos[i], orn[i], vel[i], omega[i] = sim.link_motion(*self.plate, velocity=True)
            alpha[i] = self.alpha
            if i % 100 == 0:
                closure = max(closure, self.closure_error())
        acc = np.asarray(np.gradient(vel, d.time_step, axis=0))  # (stubs read a 2-D input's gradient as a tuple)
        ang_acc = np.asarray(np.gradient(omega, d.time_step, axis=0))
        return ExecutedMotion(t, pos, quat_to_matrix(orn), vel, omega, acc, ang_acc, alpha, closure)

    # --- the interface of CaPaManScene, for an environment in dynamic fidelity ------------
    def set_obstacles(self, obstacles: tuple) -> None:
        """Replace the obstacles (static bodies the mechanism can hit)."""
        obstacles = tuple(obstacles)
        if obstacles == self.obstacles:
            return
        if "obstacles" in self.sim.body_names:
            self.sim.remove("obstacles")  # rebuilds the world: pose the mechanism again
            self.reset(self._target)
        self.obstacles = obstacles
        if obstacles:
            self.sim.add_static_group("obstacles", obstacles)

    def set_configuration(self, alpha: np.ndarray) -> np.ndarray:
        """Reset the mechanism at rest at ``alpha`` with the motors holding it; returns the tool tip."""
        self.reset(alpha)
        self._target = np.asarray(alpha, float).copy()
        return self.tip

    def drive(self, target: np.ndarray, duration: float) -> np.ndarray:
        """Move the motors' targets linearly from the last target to ``target``
        (rad) over ``duration`` s of simulated time; returns the tool tip."""
        target = np.asarray(target, float)
        # the motors' joints turn by -alpha (capaman_links): the ramp of -alpha is the negated ramp of alpha, bit
        # for bit
        self.sim.ramp(self._motors, -self._target, -target, duration)
        self._target = target.copy()
        return self.tip

    @property
    def alpha(self) -> np.ndarray:
        """The crank angles now (rad), as the motors' encoders read them."""
        return -self.sim.motor_positions(self._motors)

    @property
    def tip(self) -> np.ndarray:
        """The tool tip now (m), from the plate's simulated pose."""
        pos, orn = self.sim.link_frame(*self.plate)
        return pos - self.geometry.tool_length * quat_to_matrix(orn)[:, 2]

    def clearance(self) -> tuple[float, str | None]:
        """Signed distance (m) from the whole mechanism to the nearest obstacle, capped."""
        if not self.obstacles:
            return self.clearance_cap, None
        return min((self.sim.clearance(body, ["obstacles"], self.clearance_cap) for body in self.bodies),
                   key=lambda found: found[0])

    def render(self, width: int = 480, height: int = 360, yaw: float = 45.0, pitch: float = -25.0,
               distance: float = 0.9) -> np.ndarray:
        """RGB image of the scene (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.0, 0.1), distance=distance, yaw=yaw, pitch=pitch)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()


def drive_together(scenes: Sequence[CaPaManDynamicScene], targets: np.ndarray, duration: float, pool: Any = None
                   ) -> None:
    """:meth:`CaPaManDynamicScene.drive` of each of ``scenes`` (simulated in MuJoCo, one geometry and dynamics)
    toward its row of ``targets`` (M, 3) (rad) over ``duration`` s, their physics stepped in one batch on
    ``pool``'s threads (:func:`paragym.sim.mujoco_sim.ramp_together`)."""
    targets = np.asarray(targets, float)
    starts = np.array([scene._target for scene in scenes])
    # the motors' joints turn by -alpha (capaman_links), as in drive()
    ramp_together([scene.sim for scene in scenes], scenes[0]._motors, -starts, -targets, duration, pool)
    for scene, target in zip(scenes, targets, strict=True):
        scene._target = target.copy()


def state_together(scenes: Sequence[CaPaManDynamicScene]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The crank angles (M, 3) (rad), tool tips (M, 3) (m) and largest loop gaps (M,) (m) of ``scenes`` (as
    :func:`drive_together` takes them): :attr:`CaPaManDynamicScene.alpha`, :attr:`~CaPaManDynamicScene.tip` and
    the loops' gap as MuJoCo measures it (:meth:`~paragym.sim.mujoco_sim.MuJoCoSim.loop_residual`), in one array
    each."""
    first = scenes[0]
    motors, position, quaternion, gap = read_together([scene.sim for scene in scenes], first._motors, [first.plate])
    tip = position[:, 0] - first.geometry.tool_length * quat_to_matrix(quaternion[:, 0])[..., :, 2]
    return -motors, tip, gap


#: the contact contract's pushes (``tests/test_rules.py``, ``benchmarks/conformance.py``): boxes the motors drive
#: the mechanism into from home, and the crank angles (rad) they are driven toward: the tool from above, and the
#: tool's rod from the side
CONTACT_PUSHES = {"down": (Box((0.0, 0.0, 0.03), (0.03, 0.03, 0.02)), np.radians([45.0, 45, 45])),
                  "sideways": (Box((-0.025, -0.043, 0.08), (0.008, 0.008, 0.015)), np.radians([135.0, 45, 90]))}


def push_into(scene: CaPaManDynamicScene, push: str, box: bool = True) -> tuple[np.ndarray, float]:
    """Drive ``scene`` from home toward the angles of ``CONTACT_PUSHES[push]``, its box in place (or not, without
    ``box``): a 1 s ramp of the commands, then 1 s on at the goal (the motors at their torque limit once the box
    blocks them). Returns the tool tip at every control period of 0.02 s (100, 3) (m) and the largest loop gap
    over them (m). The scene is left where the push ended."""
    obstacle, goal = CONTACT_PUSHES[push]
    home = np.asarray(scene.geometry.alpha_home, float).ravel()
    scene.set_obstacles((obstacle,) if box else ())
    scene.set_configuration(home)
    tips, gap = [], 0.0
    for i in range(100):
        tips.append(scene.drive(home + (goal - home) * min(1.0, (i + 1) / 50), 0.02))
        gap = max(gap, scene.closure_error())
    return np.array(tips), gap
