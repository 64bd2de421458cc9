"""KF validation of any policy's executed episode, for every task (paper 000, section 5, eqs 11-21, adapted).

Paper 000 checks a plan by executing it and comparing what four 3-axis
accelerometers on the moving plate read, through the Kalman filter of eqs
18-20, with what the plan says they should read. :func:`validate_episode`
does that for whatever a policy did: it runs the policy's episode in the
env's dynamic fidelity, records the moving body's simulated motion at every
physics step (the executed trajectory), takes the pose the policy commanded
at every control step (the commanded trajectory: cubic splines through
those poses, :func:`paragym.validation.motion.pose_path_motion`), and judges
the one against the other with the same sensors, filter and verdict as a
plan (:func:`paragym.validation.report.validate`).

The adaptation, task by task (where the array sits and what "commanded" is):

* **CaPaMan**: the movable plate about H, as in the paper; commanded: the
  plate's pose by the closed-form direct kinematics of the motors' targets.
* **Hybrid**: platform E; commanded: the step's pose of E (the nominal path
  plus the action's offset); the array is the paper's scaled to E (r = 0.06 m).
* **2PRR + table**: the tool holder at C on link AC (a body turning in the
  plane; the array with r = 0.05 m, in the table's plane and 3 cm below it);
  commanded: C and link AC's direction from the commanded joints (eqs 1-6).
* **Mobile tripod**: the upper plate (r = 0.3 m, sampled at 100 Hz: the
  drive is slow, and a 30 s drive at 500 Hz made the filter the run's
  largest cost). The robot drives the
  commanded path whatever the policy does: the policy is the estimator, so
  the trajectory it "commands" is the one it claims, the plate fitted to its
  estimated units. Accelerometers see accelerations and turn rates, not
  position: a slowly drifting estimate passes, an estimate that jumps or
  shakes fails.

Eq 12's gravity term is removed at the commanded attitude, so an execution
whose attitude departs from the command leaves gravity in the readings, and
the verdict sees it. A policy whose execution diverges from its command (a
sagging platform, a lagging axis, an estimate that is not the robot) fails.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym.mechanisms import capaman, hybrid
from paragym.mechanisms import mobile_tripod as mt
from paragym.mechanisms import orthoglide as og
from paragym.rollout import Episode
from paragym.sim.client import physics_steps
from paragym.trajectories import RigidMotion
from paragym.validation.motion import pose_path_motion
from paragym.validation.report import Tolerances, ValidationReport, validate
from paragym.validation.sensors import AccelerometerArray

__all__ = ["EpisodeValidation", "MotionRecorder", "validate_episode"]


class MotionRecorder:
    """Records a point of a simulated link after every physics step: the
    point at ``offset`` (link frame, m), the link's rotation, and their
    velocities; :meth:`motion` gives them as a :class:`RigidMotion`, the
    accelerations by central differences at the simulation rate."""

    def __init__(self, sim: Any, robot: str, link: int, time_step: float, offset: np.ndarray | None = None) -> None:
        self.sim, self.robot, self.link, self.time_step = sim, robot, link, time_step
        self.offset = np.zeros(3) if offset is None else np.asarray(offset, float)
        self._rows: list[tuple[np.ndarray, ...]] = []
        self.sample()
        sim.after_step.append(self.sample)

    def sample(self) -> None:
        self._rows.append(self.sim.link_motion(self.robot, self.link, velocity=True))  # converted in motion()

    def stop(self) -> None:
        """Stop recording."""
        if self.sample in self.sim.after_step:
            self.sim.after_step.remove(self.sample)

    def motion(self) -> RigidMotion:
        pos, orn, vel, omega = (np.array(a) for a in zip(*self._rows, strict=True))
        rot = capaman.quat_to_matrix(orn)
        arm = rot @ self.offset
        pos, vel = pos + arm, vel + np.cross(omega, arm)
        t = np.arange(len(pos)) * self.time_step
        return RigidMotion(t, pos, rot, vel, omega, np.gradient(vel, self.time_step, axis=0),
                           np.gradient(omega, self.time_step, axis=0))


@dataclass(frozen=True)
class EpisodeValidation:
    """The verdict on one executed episode: the report, the largest distance
    (m) between the executed and the commanded body, the episode itself
    (observations, actions, rewards, infos), and both motions."""

    report: ValidationReport
    position_error: float
    episode: Episode
    commanded: RigidMotion
    executed: RigidMotion

    @property
    def passed(self) -> bool:
        return self.report.passed

    @property
    def success(self) -> bool:
        return self.episode.success

    @property
    def episode_return(self) -> float:
        return self.episode.episode_return

    @property
    def steps(self) -> int:
        return len(self.episode.actions)


def _pose(position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    return np.concatenate([position, hybrid.matrix_euler(rotation[None])[0]])


class _Task:
    """Where a task's array sits, what it reads as the command, and when."""

    sensors: AccelerometerArray

    def __init__(self, env: Any) -> None:
        self.env = env

    def recorder(self) -> MotionRecorder:
        raise NotImplementedError

    def commanded(self) -> np.ndarray:
        """The commanded pose of the body now (6,): x, y, z (m), roll, pitch, yaw (rad)."""
        raise NotImplementedError

    def period(self) -> float:
        """Simulated seconds of the step just taken."""
        raise NotImplementedError


class _CaPaMan(_Task):
    sensors = AccelerometerArray.paper_layout()

    def recorder(self) -> MotionRecorder:
        scene = self.env.scene
        return MotionRecorder(scene.sim, *scene.plate, scene.dynamics.time_step)

    def commanded(self) -> np.ndarray:
        e = self.env
        pose = capaman.forward(e.state.command[:1], e.geometry, validate=False)
        return _pose(pose.position[0], pose.rotation[0])

    def period(self) -> float:
        d = self.env.world.scene.dynamics
        return d.time_step * physics_steps(self.env.control_period, d.time_step)


class _Hybrid(_Task):
    sensors = AccelerometerArray.paper_layout(r=0.06, depth=0.03)

    def recorder(self) -> MotionRecorder:
        scene = self.env.world.scene
        return MotionRecorder(scene.sim, *scene.e_platform, scene.dynamics.time_step)

    def commanded(self) -> np.ndarray:
        t_e = hybrid.pose_matrix(hybrid.home_pose(self.env.geometry) + self.env.world.command)[0]
        return _pose(t_e[:3, 3], t_e[:3, :3])

    def period(self) -> float:
        d = self.env.world.scene.dynamics
        return d.time_step * physics_steps(self.env.world.control_period, d.time_step)


class _Orthoglide(_Task):
    sensors = AccelerometerArray.paper_layout(r=0.05, depth=0.03)

    def recorder(self) -> MotionRecorder:
        scene = self.env.world.scene
        return MotionRecorder(scene.sim, scene.ROBOT, scene.links[0], scene.dynamics.time_step,
                              np.array([self.env.geometry.link, 0.0, 0.0]))

    def commanded(self) -> np.ndarray:
        g = self.env.geometry
        rho = self.env.world.command
        c = og.fixed_point(rho[:1], og.forward(rho[None], g), g)[0]
        a = g.slider2_origin + rho[1]
        yaw = np.arctan2(c[1], c[0] - a)
        z = self.env.world.scene.sim.link_frame(self.env.world.scene.ROBOT, self.env.world.scene.links[0])[0][2]
        return np.array([c[0], c[1], z, 0.0, 0.0, yaw])

    def period(self) -> float:
        s, d = self.env.state, self.env.world.scene.dynamics
        k = int(s.k[0])
        h = float(s.dt[0, k - 1]) if k > 0 else 0.0
        return d.time_step * physics_steps(h, d.time_step)


class _Tripod(_Task):
    sensors = AccelerometerArray.paper_layout(r=0.3, depth=0.1, rate=100.0)  # a slow vehicle: 100 Hz is plenty

    def __init__(self, env: Any) -> None:
        super().__init__(env)
        self._eta = env.state.drive.eta[0].copy()

    def recorder(self) -> MotionRecorder:
        scene = self.env.world.scene
        return MotionRecorder(scene.sim, scene.ROBOT, scene.plate_link, scene.dynamics.time_step)

    def commanded(self) -> np.ndarray:
        s, e = self.env.state, self.env
        units = s.estimate[0] + [0.0, 0.0, e.world.dynamics.unit_height]
        # the legs' angles the estimate implies (eqs 4-5; least squares where no legs reach), then the plate on it
        self._eta = mt.eta(units[None], self._eta[None], e.geometry)[0][0]
        rotation, centre = mt.plate_fit(units, self._eta, e.geometry)
        return _pose(centre[0], rotation[0])

    def period(self) -> float:
        d = self.env.world.dynamics
        return d.time_step * physics_steps(self.env.state.drive.dt, d.time_step)


def _task(env: Any) -> _Task:
    name = type(env).__name__
    for key, cls in (("CaPaMan", _CaPaMan), ("Hybrid", _Hybrid), ("Orthoglide", _Orthoglide),
                     ("MobileTripod", _Tripod)):
        if name.startswith(key):
            return cls(env)
    raise ValueError(f"no episode validation for {name}")


def validate_episode(env: Any, policy: Any, seed: int = 0, tolerances: Tolerances | None = None,
                     sensor_seed: int = 0) -> EpisodeValidation:
    """Run ``policy`` (``reset(obs, info)``, ``act(obs, info)``) for one
    episode of ``env`` (made with ``fidelity="dynamic"``) from ``seed``, and
    validate the executed motion against the commanded one (module
    docstring). ``sensor_seed`` draws the accelerometers' noise."""
    base = env.unwrapped
    if getattr(base, "fidelity", None) != "dynamic":
        raise ValueError("validate_episode needs an env made with fidelity='dynamic'")
    obs, info = env.reset(seed=seed)
    task = _task(base)
    policy.reset(obs, info)
    episode = Episode(observations=[obs], infos=[info])
    recorder = task.recorder()
    times, poses = [0.0], [task.commanded()]
    try:
        while True:
            action = policy.act(obs, info)
            obs, reward, terminated, truncated, info = env.step(action)
            episode.actions.append(np.asarray(action))
            episode.observations.append(obs)
            episode.rewards.append(float(reward))
            episode.infos.append(info)
            times.append(times[-1] + task.period())
            poses.append(task.commanded())
            if terminated or truncated:
                episode.terminated, episode.truncated = bool(terminated), bool(truncated)
                break
    finally:
        recorder.stop()
    executed = recorder.motion()
    poses_arr = np.array(poses)
    poses_arr[:, 3:] = np.unwrap(poses_arr[:, 3:], axis=0)
    times_arr = np.array(times)
    keep = np.concatenate([[True], np.diff(times_arr) > 0])  # a step that moved no time (after the end) adds no knot
    sensors = task.sensors
    commanded = pose_path_motion(times_arr[keep], poses_arr[keep], sensors.rate, moving_at_end=True)
    end = min(commanded.t[-1], executed.t[-1])
    on_grid = commanded.at(executed.t[executed.t <= end])
    error = float(np.linalg.norm(executed.position[:len(on_grid.t)] - on_grid.position, axis=1).max())
    report = validate(commanded, executed, sensors, tolerances=tolerances, seed=sensor_seed)
    return EpisodeValidation(report, error, episode, commanded, executed)
