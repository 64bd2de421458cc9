"""The CaPaMan in PyBullet, dynamic fidelity: the closed chain under motors.

The kinematic tree of :func:`paragym.sim.capaman_model.capaman_links` gets
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
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pybullet as pb

from paragym.mechanisms import capaman
from paragym.sim.capaman_model import capaman_links
from paragym.sim.client import LinkSpec, PyBulletSim
from paragym.trajectories import JointTrajectory, RigidMotion

__all__ = ["CaPaManDynamics", "CaPaManDynamicScene", "ExecutedMotion"]


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
    time_step: float = 1e-3  # s
    solver_iterations: int = 150
    gravity: float = 9.81


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
            slider = capaman.PartShape(f"{leg}_slider", "box", (0.012, 0.012, 0.012))
            links.append(LinkSpec(f"{leg}_slider", link.name, "prismatic", axis=(0.0, 0.0, 1.0), shape=slider,
                                  rgba=(0.8, 0.8, 0.8, 1.0), mass=d.slider_mass))
    return links


class CaPaManDynamicScene:
    """A PyBullet world with one dynamic CaPaMan.

    Args:
        geometry: the mechanism's dimensions.
        dynamics: masses, motors and integration settings.
    """

    ROBOT = "capaman"

    def __init__(self, geometry: capaman.CaPaManGeometry = capaman.DEFAULT_GEOMETRY,
                 dynamics: CaPaManDynamics | None = None, gui: bool = False, clearance_cap: float = 0.05) -> None:
        self.geometry = g = geometry
        self.clearance_cap = clearance_cap
        self.obstacles: tuple = ()
        self.dynamics = d = dynamics or CaPaManDynamics()
        self.sim = PyBulletSim(gui=gui)
        self.sim.add_tree_body(self.ROBOT, _dynamic_links(g, d))
        idx = lambda link: self.sim.link_index(self.ROBOT, link)  # noqa: E731
        legs = (1, 2, 3)
        self.motors = [idx(f"leg{k}_crank_a") for k in legs]
        self.cranks_b = [idx(f"leg{k}_crank_b") for k in legs]
        self.couplers = [idx(f"leg{k}_coupler") for k in legs]
        self.sliders = [idx(f"leg{k}_slider") for k in legs]
        self.plate = idx("plate")
        self.float_joints = [idx("plate_x"), idx("plate_y"), idx("plate_z")]
        self.sim.on_rebuild(self._set_up_physics)
        self.set_configuration(g.alpha_home)

    @property
    def body(self) -> int:
        """The mechanism's PyBullet body id now (it changes when the world is rebuilt)."""
        return self.sim.body(self.ROBOT)

    def _set_up_physics(self) -> None:
        """Gravity, the engine's parameters, the passive joints, no self-collision and the six loop
        closures (run again whenever the world is rebuilt)."""
        g, d, c = self.geometry, self.dynamics, self.sim.client
        pb.setGravity(0, 0, -d.gravity, physicsClientId=c)
        pb.setPhysicsEngineParameter(fixedTimeStep=d.time_step, numSolverIterations=d.solver_iterations,
                                     physicsClientId=c)
        no_collision = pb.getNumJoints(self.body, physicsClientId=c)
        for i in range(-1, no_collision):  # the parts of one mechanism do not collide with each other
            for j in range(i + 1, no_collision):
                pb.setCollisionFilterPair(self.body, self.body, i, j, 0, physicsClientId=c)
        passive = self.cranks_b + self.couplers + self.sliders + self.float_joints
        pb.setJointMotorControlArray(self.body, passive, pb.VELOCITY_CONTROL, forces=[0.0] * len(passive),
                                     physicsClientId=c)
        pb.setJointMotorControlMultiDof(self.body, self.plate, pb.POSITION_CONTROL, targetPosition=[0, 0, 0, 1],
                                        force=[0.0, 0.0, 0.0], physicsClientId=c)
        for k in range(3):  # loop closures: parallelogram, then ball joint (frames at the links' COMs)
            pb.createConstraint(self.body, self.cranks_b[k], self.body, self.couplers[k], pb.JOINT_POINT2POINT,
                                [0, 0, 0], [0, 0, g.a / 2], [0, 0, g.c / 2], physicsClientId=c)
            pb.createConstraint(self.body, self.sliders[k], self.body, self.plate, pb.JOINT_POINT2POINT,
                                [0, 0, 0], [0, 0, 0], list(g.plate_points[k]), physicsClientId=c)

    def reset(self, alpha: np.ndarray) -> None:
        """Put every joint where the analytic model has it at ``alpha`` (rad), at rest."""
        g, c = self.geometry, self.sim.client
        al = capaman.check_joint_angles(alpha, g)
        pose = capaman.forward(al, g)
        for k in range(3):
            a = float(al[0, k])
            for joint, value in ((self.motors[k], -a), (self.cranks_b[k], -a), (self.couplers[k], a),
                                 (self.sliders[k], float(pose.sliders[0, k]))):
                pb.resetJointState(self.body, joint, value, 0.0, physicsClientId=c)
        for joint, value in zip(self.float_joints, pose.position[0], strict=True):
            pb.resetJointState(self.body, joint, float(value), 0.0, physicsClientId=c)
        pb.resetJointStateMultiDof(self.body, self.plate, list(pose.quaternion[0]), [0.0, 0.0, 0.0],
                                   physicsClientId=c)

    def closure_error(self) -> float:
        """Largest gap (m) of the six loop closures now."""
        g, c = self.geometry, self.sim.client
        frame = lambda link: pb.getLinkState(self.body, link, computeForwardKinematics=True,  # noqa: E731
                                             physicsClientId=c)
        p_pos, p_orn = frame(self.plate)[4:6]
        rot = np.array(pb.getMatrixFromQuaternion(p_orn)).reshape(3, 3)
        worst = 0.0
        for k in range(3):
            ball = np.array(p_pos) + rot @ g.plate_points[k]
            worst = max(worst, float(np.linalg.norm(np.array(frame(self.sliders[k])[4]) - ball)))
            b_pos, b_orn = frame(self.cranks_b[k])[4:6]
            c_pos, c_orn = frame(self.couplers[k])[4:6]
            tip_b = np.array(b_pos) + np.array(pb.getMatrixFromQuaternion(b_orn)).reshape(3, 3)[:, 2] * g.a
            end_c = np.array(c_pos) + np.array(pb.getMatrixFromQuaternion(c_orn)).reshape(3, 3)[:, 2] * g.c
            worst = max(worst, float(np.linalg.norm(tip_b - end_c)))
        return worst

    def execute(self, trajectory: JointTrajectory, settle: float = 0.5) -> ExecutedMotion:
        """Drive the cranks along ``trajectory`` (targets alpha(t), alpha_dot(t)
        every step), then hold the last targets for ``settle`` s; record the
        plate's motion at every step."""
        d, c = self.dynamics, self.sim.client
        self.reset(trajectory.position(np.array([0.0]))[0])
        n = int(round((trajectory.duration + settle) / d.time_step)) + 1
        t = np.arange(n) * d.time_step
        target, target_rate = trajectory.position(t), trajectory.velocity(t)
        pos, orn = np.empty((n, 3)), np.empty((n, 4))
        vel, omega, alpha = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        closure = 0.0
        forces = [d.motor_torque] * 3
        kp, kd = [d.position_gain] * 3, [d.velocity_gain] * 3
        for i in range(n):  # the physics is sequential: one step after the other
            if i:
                pb.setJointMotorControlArray(self.body, self.motors, pb.POSITION_CONTROL,
                                             targetPositions=list(-target[i]), targetVelocities=list(-target_rate[i]),
                                             forces=forces, positionGains=kp, velocityGains=kd, physicsClientId=c)
                pb.stepSimulation(physicsClientId=c)
            state = pb.getLinkState(self.body, self.plate, computeLinkVelocity=True, computeForwardKinematics=True,
                                    physicsClientId=c)
            pos[i], orn[i], vel[i], omega[i] = state[4], state[5], state[6], state[7]
            alpha[i] = [-s[0] for s in pb.getJointStates(self.body, self.motors, physicsClientId=c)]
            if i % 100 == 0:
                closure = max(closure, self.closure_error())
        acc = np.gradient(vel, d.time_step, axis=0)
        ang_acc = np.gradient(omega, d.time_step, axis=0)
        return ExecutedMotion(t, pos, capaman.quat_to_matrix(orn), vel, omega, acc, ang_acc, alpha, closure)

    # --- the interface of CaPaManScene, for an environment in dynamic fidelity ------------
    def set_obstacles(self, obstacles: tuple) -> None:
        """Replace the obstacles (static bodies the mechanism can hit)."""
        obstacles = tuple(obstacles)
        if obstacles == self.obstacles:
            return
        if "obstacles" in self.sim.body_names:
            self.sim.remove("obstacles")  # rebuilds the world: pose the mechanism again
            self.set_configuration(self._target if hasattr(self, "_target") else self.geometry.alpha_home)
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
        d, c = self.dynamics, self.sim.client
        steps = max(1, int(round(duration / d.time_step)))
        start = self._target
        rate = (np.asarray(target, float) - start) / (steps * d.time_step)
        for i in range(1, steps + 1):
            goal = start + (target - start) * (i / steps)
            pb.setJointMotorControlArray(self.body, self.motors, pb.POSITION_CONTROL, targetPositions=list(-goal),
                                         targetVelocities=list(-rate), forces=[d.motor_torque] * 3,
                                         positionGains=[d.position_gain] * 3, velocityGains=[d.velocity_gain] * 3,
                                         physicsClientId=c)
            pb.stepSimulation(physicsClientId=c)
        self._target = np.asarray(target, float).copy()
        return self.tip

    @property
    def alpha(self) -> np.ndarray:
        """The crank angles now (rad), as the motors' encoders read them."""
        return np.array([-s[0] for s in pb.getJointStates(self.body, self.motors, physicsClientId=self.sim.client)])

    @property
    def tip(self) -> np.ndarray:
        """The tool tip now (m), from the plate's simulated pose."""
        pos, orn = pb.getLinkState(self.body, self.plate, computeForwardKinematics=True,
                                   physicsClientId=self.sim.client)[4:6]
        rot = np.array(pb.getMatrixFromQuaternion(orn)).reshape(3, 3)
        return np.array(pos) - self.geometry.tool_length * rot[:, 2]

    def clearance(self) -> tuple[float, str | None]:
        """Signed distance (m) from the whole mechanism to the nearest obstacle, capped."""
        if not self.obstacles:
            return self.clearance_cap, None
        return self.sim.clearance(self.ROBOT, ["obstacles"], self.clearance_cap)

    def render(self, width: int = 480, height: int = 360, yaw: float = 45.0, pitch: float = -25.0,
               distance: float = 0.9) -> np.ndarray:
        """RGB image of the scene (uint8, (height, width, 3))."""
        return self.sim.render(width, height, target=(0.0, 0.0, 0.1), distance=distance, yaw=yaw, pitch=pitch)

    def close(self) -> None:
        """Disconnect PyBullet."""
        self.sim.close()
