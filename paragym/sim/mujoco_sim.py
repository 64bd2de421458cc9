"""A dynamic scene's physics in MuJoCo: the MuJoCo dynamic fidelity (``engine="mujoco"``).

:class:`MuJoCoSim` stands where a dynamic scene's :class:`~paragym.sim.client.PyBulletSim` stands and answers
the same calls, so that the scene (:mod:`paragym.sim.capaman_dynamic`, :mod:`paragym.sim.hybrid_dynamic`,
:mod:`paragym.sim.orthoglide_dynamic`, :mod:`paragym.sim.tripod_dynamic`), its world, the task's transition and
KF validation run unchanged on either engine. The scene is built in PyBullet
as always; its mechanism is then written as MJCF by :func:`paragym.sim.export.mjcf` (the same links, masses,
loop closures as ``connect`` constraints, motors as force-limited position servos) and simulated by MuJoCo:

* **physics** (every step, every motor, every loop closure, contact with the fixed parts and the ground, a
  push's force, a contact's friction as the scene sets it) is MuJoCo's;
* **geometry** stays PyBullet's: the scene's PyBullet world is kept as a mirror, posed at MuJoCo's joint values
  whenever it is read, and answers the clearance queries (the task's collision rule, one code for both
  engines), renders, and keeps the bodies' bookkeeping (names, link indices, obstacles);
* a reset poses the mirror (the scene's own reset code), which answers the reads until MuJoCo next runs; MuJoCo
  then starts from there, at rest, with nothing of a former episode (warm starts, time); new fixed parts (a
  scenario's obstacles) recompile the model with the robot as it was first written, so that the servos' gains
  do not depend on the pose at a reset.

**MuJoCo alone** (``MuJoCoSettings(mirror=False)``): the scene is built on a
:class:`~paragym.sim.description.SceneDescription` instead of PyBullet, which the export writes and a reset
poses; reads after a reset load it into MuJoCo first, and PyBullet is built from the description only for a
picture or a distance. Such robots step in batches: :func:`ramp_together` runs one control period of many
robots, each in a model of its own, in one call of MuJoCo's ``rollout`` on a :class:`RolloutPool`'s threads
with no lock held, and :func:`read_together` reads what the task reads of them in one array each. ``rollout``
starts each call from a zero warm start, so a robot here starts every control period so too
(:attr:`MuJoCoSim.cold_periods`), alone or in a batch: the same bits either way.

The motors: MuJoCo's position servo pushes kp (u - q) - kv q_dot within its force range; :meth:`MuJoCoSim.drive`
sets u = target + (kv / kp) * rate, which makes that kp (target - q) + kv (rate - q_dot), the PD law of
PyBullet's motors with its target rate. The gains are the export's (critically damped at
``servo_bandwidth`` / h for what each servo moves, :func:`paragym.sim.export.servo_gains`), not PyBullet's
normalised ones; the force limit is the scene's (:meth:`MuJoCoSim.servos`).

The settings (:class:`MuJoCoSettings`) are the engine's own: its physics step (1 ms by default: MuJoCo's
servos are springs integrated step by step, and at the PyBullet scenes' 5 ms they cannot hold the hybrid's
platforms, :func:`paragym.sim.export.mujoco_time_step`), the servos' bandwidth and the solver's iterations.
A scene's ``time_step`` passed to :meth:`MuJoCoSim.ramp` is ignored: a ramp lasts its duration in MuJoCo's
steps. Lengths in m, angles in rad, forces in N or N m.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from paragym.kernels import thread_count
from paragym.sim import export
from paragym.sim.client import depth_first, physics_steps
from paragym.sim.description import SceneDescription
from paragym.sim.recipes import Recipe, Vector

__all__ = ["ENGINES", "MAX_STEP", "MuJoCoSettings", "MuJoCoSim", "RolloutPool", "check_engine", "ramp_together",
           "read_together", "rollout_pool", "scene_sim", "simulate_in", "vector_engine"]

#: the engines of the dynamic fidelity, by the name the ``engine`` argument takes
ENGINES = ("pybullet", "mujoco")
#: the longest MuJoCo step (s) the fidelity takes: the reference's verdicts there are those of the default step
#: (:data:`paragym.sim.export.MUJOCO_STEP`; the conformance page)
MAX_STEP = 2e-3


@dataclass(frozen=True)
class MuJoCoSettings:
    """The MuJoCo dynamic fidelity's own settings (SI).

    Presets: the default (a 1 ms step, :data:`paragym.sim.export.MUJOCO_STEP`) and :meth:`fast` (2 ms: the
    longest step, :data:`MAX_STEP`, at which the reference's verdicts stay those of 1 ms).

    Attributes:
        time_step: MuJoCo's physics step (s), at most :data:`MAX_STEP`.
        servo_bandwidth: the servos' bandwidth times the step (:func:`paragym.sim.export.servo_gains`); None:
            the scene's ``EXPORT_SERVO_BANDWIDTH`` or :data:`paragym.sim.export.SERVO_BANDWIDTH`.
        iterations: the constraint solver's iterations; None: the scene's dynamics' ``solver_iterations``.
        mirror: the scene is built in PyBullet, which answers clearance and draws (module docstring); False:
            MuJoCo alone, the scene described as data (:mod:`paragym.sim.description`) and PyBullet built only
            for a picture; its robots step in batches (:func:`ramp_together`), so each control period starts the
            solver from a zero warm start (:attr:`MuJoCoSim.cold_periods`). What the native dynamic vector envs
            run, N robots at once; tasks that have such a world take it.
    """

    time_step: float = export.MUJOCO_STEP
    servo_bandwidth: float | None = None
    iterations: int | None = None
    mirror: bool = True

    def __repr__(self) -> str:
        """The fields, ``mirror`` only where False: settings made before it existed print as they did (a result
        row records its engine so)."""
        shown = (f"time_step={self.time_step!r}, servo_bandwidth={self.servo_bandwidth!r}, "
                 f"iterations={self.iterations!r}")
        return f"MuJoCoSettings({shown}{'' if self.mirror else ', mirror=False'})"

    @classmethod
    def fast(cls) -> MuJoCoSettings:
        """A 2 ms step (class docstring): half the physics steps of the default."""
        return cls(time_step=MAX_STEP)

    def refined(self, step: float, iterations: int, bandwidth: float, solver_iterations: int) -> MuJoCoSettings:
        """The same model integrated at ``step`` times this physics step with ``iterations`` times the solver's
        iterations (these settings', else ``solver_iterations``, the scene's): the servos' bandwidth, a share
        per step (these settings', else ``bandwidth``, the scene's), scaled with the step, so that they stay as
        fast in rad/s. What a convergence study sweeps (``benchmarks/convergence.py``)."""
        return replace(self, time_step=self.time_step * step,
                       servo_bandwidth=(self.servo_bandwidth or bandwidth) * step,
                       iterations=int((self.iterations or solver_iterations) * iterations))

    def __post_init__(self) -> None:
        if not (isinstance(self.time_step, int | float) and 0 < self.time_step <= MAX_STEP):
            raise ValueError(f"MuJoCoSettings.time_step must be in (0, {MAX_STEP:g}] s; got {self.time_step!r}")
        if self.servo_bandwidth is not None and not 0 < self.servo_bandwidth < 2:
            raise ValueError(f"MuJoCoSettings.servo_bandwidth must be in (0, 2) (semi-implicit Euler is unstable "
                             f"from 2 on); got {self.servo_bandwidth!r}")
        if self.iterations is not None and not (isinstance(self.iterations, int) and self.iterations > 0):
            raise ValueError(f"MuJoCoSettings.iterations must be a positive int; got {self.iterations!r}")
        if not isinstance(self.mirror, bool):
            raise ValueError(f"MuJoCoSettings.mirror must be True or False; got {self.mirror!r}")


def check_engine(engine: Any, engines: tuple[str, ...], fidelity: str, alone: bool = False
                 ) -> MuJoCoSettings | None:
    """The ``engine`` argument of an env whose task runs the dynamic fidelity in ``engines``: "pybullet"
    (None), "mujoco" or a :class:`MuJoCoSettings` (the MuJoCo settings). A ValueError naming it for an engine the
    task does not run, for MuJoCo outside the dynamic fidelity, or for MuJoCo alone (``mirror=False``) where the
    task has no such world (``alone``); an ImportError saying how to install MuJoCo where it is missing."""
    if isinstance(engine, MuJoCoSettings):
        settings: MuJoCoSettings | None = engine
    elif isinstance(engine, str) and engine in ENGINES:
        settings = MuJoCoSettings() if engine == "mujoco" else None
    else:
        raise ValueError(f"engine must be 'pybullet', 'mujoco' or a MuJoCoSettings; got {engine!r:.80}")
    if settings is None:
        return None
    if "mujoco" not in engines:
        raise ValueError(f"engine='mujoco': this task's dynamic fidelity runs in {' and '.join(engines)} only")
    if fidelity != "dynamic":
        raise ValueError(f"engine='mujoco' is a dynamic fidelity: make the env with fidelity='dynamic' (got "
                         f"fidelity={fidelity!r})")
    if not settings.mirror and not alone:
        raise ValueError("engine=MuJoCoSettings(mirror=False): this task's MuJoCo fidelity runs over its PyBullet "
                         "scene only (mirror=True)")
    _import_mujoco()
    return settings


def vector_engine(engine: Any) -> Any:
    """The ``engine`` argument of a native vector env in the dynamic fidelity: MuJoCo alone (``"mujoco"`` or a
    :class:`MuJoCoSettings`, made ``mirror=False``). A ValueError for PyBullet's, which steps one robot at a
    time; anything else is left for the task's check to refuse."""
    if isinstance(engine, str) and engine == "pybullet":
        raise ValueError("a native vector env runs the dynamic fidelity in MuJoCo alone: engine='mujoco' (use "
                         "gymnasium's sync/async modes for PyBullet's dynamics)")
    if isinstance(engine, str) and engine == "mujoco":
        engine = MuJoCoSettings()
    return replace(engine, mirror=False) if isinstance(engine, MuJoCoSettings) else engine


def scene_sim(gui: bool, settings: MuJoCoSettings | None) -> Any:
    """What a dynamic scene builds in: a PyBullet world, or for MuJoCo alone (``settings.mirror`` False) a
    :class:`~paragym.sim.description.SceneDescription`."""
    if settings is not None and not settings.mirror:
        return SceneDescription(gui=gui)
    from paragym.sim.client import PyBulletSim

    return PyBulletSim(gui=gui)


def simulate_in(scene: Any, settings: MuJoCoSettings | None) -> None:
    """Give the built dynamic ``scene`` its engine: PyBullet's as built (``settings`` None), else MuJoCo's with
    ``settings`` (``scene.sim`` becomes a :class:`MuJoCoSim` over what it was built in, :func:`scene_sim`)."""
    if settings is not None:
        scene.sim = MuJoCoSim(scene, settings)


def _import_mujoco() -> Any:
    try:
        import mujoco
    except ImportError as error:
        raise ImportError('engine="mujoco" needs MuJoCo: pip install "paragym[mujoco]"') from error
    return mujoco


class MuJoCoSim:
    """The physics of ``scene`` (a dynamic scene built in PyBullet) in MuJoCo, with its PyBullet world as the
    geometry's mirror (module docstring). Joints, links and motors are addressed as in PyBullet: (body name,
    joint or link index), -1 a base."""

    def __init__(self, scene: Any, settings: MuJoCoSettings | None = None) -> None:
        self._mj = _import_mujoco()
        self.settings = s = settings or MuJoCoSettings()
        #: what the scene was built in, which holds the pose a reset puts: its PyBullet world (the mirror, posed
        #: at MuJoCo's state when read), or its description as data (:mod:`paragym.sim.description`)
        self.source = source = scene.sim
        self._described = isinstance(source, SceneDescription)
        self._picture: Any = None  # a described scene's PyBullet world, built when a picture or distance is asked
        #: MuJoCo's physics step (s) and the simulated time (s) so far
        self.time_step = float(s.time_step)
        self.elapsed = 0.0
        #: functions called after every physics step (:meth:`step`), e.g. to record a body's motion
        self.after_step: list[Any] = []
        #: the robot as MJCF, written once from the scene as built (its fixed parts are replaced at a recompile)
        self.robot_mjcf = export.mjcf(scene, getattr(scene, "ROBOT", "paragym"), time_step=s.time_step,
                                      bandwidth=s.servo_bandwidth, iterations=s.iterations)
        self._trees = [(name, depth_first(links), base_mass) for name, links, base_mass, _ in
                       export.bodies_of(source)[0]]
        self._fixed: Any = None
        self.model: Any = None
        self.data: Any = None
        self._actuators: dict[Any, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._need_load = True  # the source holds the state (a reset): load it before MuJoCo runs
        self._pushed = False  # a force acts in the next step (:meth:`push`)
        #: contact friction set since the model was written, (body, link) -> coefficient (:meth:`friction`)
        self._friction: dict[tuple[str, int], float] = {}
        self._mirror_stale = False  # MuJoCo has moved since the source was posed
        #: each :meth:`ramp` (a control period) starts MuJoCo's solver from a zero warm start, as
        #: :func:`ramp_together` steps a batch of robots (MuJoCo alone, :attr:`MuJoCoSettings.mirror` False);
        #: else the warm start carries on from the last step
        self.cold_periods = not s.mirror
        if self._described and source.gui:
            self._geometry()  # the GUI's window opens with the scene
        self._ready()

    @property
    def mirror(self) -> Any:
        """The PyBullet world at MuJoCo's state: the scene's own, or for a described scene one built from its
        description (on first use; again when its bodies change)."""
        return self._geometry()

    def _geometry(self) -> Any:
        """The PyBullet world posed at MuJoCo's state, which answers distances and draws."""
        self._pose_mirror()
        if not self._described:
            return self.source
        from paragym.sim.client import PyBulletSim

        picture, description = self._picture, self.source
        if picture is None or picture.recipes.keys() != description.recipes.keys() or not _same_parts(
                export.fixed_parts(picture), export.fixed_parts(description)):
            if picture is not None:
                picture.close()
            self._picture = picture = PyBulletSim(gui=description.gui)
            description.build_in(picture)
        else:
            description.pose(picture)
        return picture

    # --- the model and the two states --------------------------------------------------------------
    def _compile(self, fixed: list[tuple[str, Any]]) -> None:
        mj = self._mj
        self.model = model = mj.MjModel.from_xml_string(export.with_fixed_parts(self.robot_mjcf, fixed))
        self.data = mj.MjData(model)
        self._fixed = fixed
        self._actuators.clear()
        n = len(self._trees)
        #: (body, joint or link index) -> (MuJoCo body id, joint type, qpos address); -1: the base
        self._joints: dict[tuple[str, int], tuple[int, int, int]] = {}
        for name, links, base_mass in self._trees:
            base = model.body(name).id
            self._joints[name, -1] = (base, -1, int(model.jnt_qposadr[model.body_jntadr[base]]) if base_mass > 0
                                      else -1)
            for i, link in enumerate(links):
                b = model.body(export.model_name(name, link.name, n)).id
                if model.body_jntnum[b]:
                    j = int(model.body_jntadr[b])
                    self._joints[name, i] = (b, int(model.jnt_type[j]), int(model.jnt_qposadr[j]))
                else:
                    self._joints[name, i] = (b, -1, -1)
        for (name, index), lateral in self._friction.items():
            self._set_friction(name, index, lateral)

    def _ready(self) -> None:
        """Load the source's state into MuJoCo if a reset put it there (recompiling for new fixed parts): before
        MuJoCo runs."""
        if not self._need_load:
            return
        mj, mirror = self._mj, self.source
        fixed = export.fixed_parts(mirror)
        if self.model is None or not _same_parts(fixed, self._fixed):
            self._compile(fixed)
        model, data = self.model, self.data
        mj.mj_resetData(model, data)  # nothing of a former episode (warm starts, time) carries over
        ball = mj.mjtJoint.mjJNT_BALL
        for name, links, base_mass in self._trees:
            values = mirror.joint_values(name)
            for index in range(len(links)):
                _, kind, adr = self._joints[name, index]
                if adr < 0:
                    continue
                value = values[index]
                if kind == ball:
                    data.qpos[adr:adr + 4] = (value[3], value[0], value[1], value[2])
                else:
                    data.qpos[adr] = value[0]
            if base_mass > 0:
                pos, xyzw = mirror.link_frame(name, -1)
                adr = self._joints[name, -1][2]
                data.qpos[adr:adr + 3] = pos
                data.qpos[adr + 3:adr + 7] = (xyzw[3], xyzw[0], xyzw[1], xyzw[2])
        adr = model.jnt_qposadr[model.actuator_trnid[:, 0]]
        data.ctrl[:] = data.qpos[adr]  # the servos hold where the reset put them until driven
        mj.mj_step1(model, data)  # the state's kinematics and velocities: what a read sees
        self._need_load, self._mirror_stale = False, False

    def _reads_source(self) -> bool:
        """Whether a read after a reset is the PyBullet mirror's (which holds the state until MuJoCo runs); a
        described scene's reads are MuJoCo's, loaded now."""
        if self._need_load and self._described:
            self._ready()
        return self._need_load

    def _pose_mirror(self) -> None:
        """Pose the source at MuJoCo's joint values (a PyBullet mirror then answers geometric queries)."""
        if not self._mirror_stale or self._need_load:
            return
        qpos, ball = self.data.qpos, self._mj.mjtJoint.mjJNT_BALL
        for name, links, base_mass in self._trees:
            indices, values = [], []
            for i in range(len(links)):
                _, kind, adr = self._joints[name, i]
                if adr < 0:
                    continue
                indices.append(i)
                values.append([qpos[adr + 1], qpos[adr + 2], qpos[adr + 3], qpos[adr]] if kind == ball
                              else [qpos[adr]])
            self.source.set_joints(name, indices, values)
            if base_mass > 0:
                adr = self._joints[name, -1][2]
                w, x, y, z = qpos[adr + 3:adr + 7]
                self.source.reset_base(name, qpos[adr:adr + 3], (x, y, z, w))
        self._mirror_stale = False

    # --- dynamics --------------------------------------------------------------------------------------
    def _motors(self, motors: Sequence[tuple[str, Sequence[int]]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The actuators of ``motors``, their joints' qpos addresses and their kv / kp (cached per motor list)."""
        key = tuple((name, tuple(joints)) for name, joints in motors)
        if key not in self._actuators:
            model, n = self.model, len(self._trees)
            ids = []
            for name, joints in key:
                links = next(links for tree, links, _ in self._trees if tree == name)
                ids += [model.actuator(f"{export.model_name(name, links[j].name, n)}_joint_motor").id
                        for j in joints]
            ids_arr = np.array(ids, int)
            adr = model.jnt_qposadr[model.actuator_trnid[ids_arr, 0]]
            ratio = -model.actuator_biasprm[ids_arr, 2] / model.actuator_gainprm[ids_arr, 0]
            self._actuators[key] = (ids_arr, adr, ratio)
        return self._actuators[key]

    def servos(self, motors: Sequence[tuple[str, Sequence[int]]], force: float, position_gain: float,
               velocity_gain: float) -> None:
        """The servos of ``motors`` from now on, written into the source (:attr:`servo_settings`): MuJoCo's take
        their force limit (N or N m); their gains are the settings' (``servo_bandwidth``, module docstring), the
        PyBullet gains the source's, which its mirror and its description keep."""
        self.source.servos(motors, force, position_gain, velocity_gain)

    @property
    def servo_settings(self) -> dict[tuple[str, int], tuple[float, float, float]]:
        """The servos as set (:meth:`servos`), the source's."""
        return self.source.servo_settings

    def _force(self, motors: Sequence[tuple[str, Sequence[int]]]) -> float:
        """The force limit of the servos of ``motors``, which were set together (:meth:`servos`)."""
        name, joints = motors[0]
        return self.source.servo_settings[name, joints[0]][0]

    def drive(self, motors: Sequence[tuple[str, Sequence[int]]], targets: Vector,
              rates: Vector) -> None:
        """The servos of ``motors`` (:meth:`servos`) chase ``targets`` at ``rates`` from the next step on."""
        self._ready()
        ids, _, ratio = self._motors(motors)
        self.data.ctrl[ids] = np.asarray(targets, float) + ratio * np.asarray(rates, float)
        force = self._force(motors)
        self.model.actuator_forcerange[ids] = (-force, force)

    def ramp(self, motors: Sequence[tuple[str, Sequence[int]]], start: np.ndarray, goal: np.ndarray,
             duration: float) -> None:
        """Move the servos' targets linearly from ``start`` to ``goal`` over ``duration`` s of MuJoCo's steps
        (at least one), stepping as they go."""
        ids, inputs = self._ramp_inputs(motors, start[None], goal[None], duration, self._force(motors))
        inputs = inputs[0]
        if self.cold_periods:  # as rollout starts: no warm start, and what the state implies computed afresh
            self.data.qacc_warmstart[:] = 0.0
            self._mj.mj_step1(self.model, self.data)
        ctrl = self.data.ctrl
        if self.after_step or self._pushed:  # someone watches every step, or a push acts in the first
            for row in inputs:
                ctrl[ids] = row
                self.step()
            return
        # nothing between the steps: step() without its bookkeeping, the same calls in the same order
        model, data, step2, step1, h = self.model, self.data, self._mj.mj_step2, self._mj.mj_step1, self.time_step
        columns: np.ndarray | slice = ids
        if len(ids) == len(ctrl) and np.array_equal(ids, np.arange(len(ctrl))):
            columns = slice(None)
        for row in inputs:
            ctrl[columns] = row
            step2(model, data)
            step1(model, data)
            self.elapsed += h
        self._mirror_stale = True

    def _ramp_inputs(self, motors: Sequence[tuple[str, Sequence[int]]], start: np.ndarray, goal: np.ndarray,
                     duration: float, force: float) -> tuple[np.ndarray, np.ndarray]:
        """The actuators of ``motors`` and their inputs at every MuJoCo step of a ramp from ``start`` to ``goal``
        (M, n) over ``duration`` s, (M, steps, n): the numbers :meth:`drive` takes step by step, to the bit; their
        force limit set to ``force``."""
        self._ready()
        h = self.time_step
        steps = physics_steps(duration, h)
        rate = (goal - start) / (steps * h)
        ids, _, ratio = self._motors(motors)
        share = (np.arange(1, steps + 1) / steps)[None, :, None]
        inputs = start[:, None] + (goal - start)[:, None] * share + (ratio * rate)[:, None]
        self.model.actuator_forcerange[ids] = (-force, force)
        return ids, inputs

    def push(self, name: str, link: int, force: Vector) -> None:
        """Apply ``force`` (N, world frame) at the centre of mass of ``link`` of body ``name`` for the next step
        (MuJoCo's ``xfrc_applied``, cleared after it), as :meth:`PyBulletSim.push`."""
        self._ready()
        self.data.xfrc_applied[self._joints[name, link][0], :3] = force
        self._pushed = True

    def step(self) -> None:
        """One MuJoCo step (then the :attr:`after_step` callbacks)."""
        self._ready()
        mj = self._mj
        mj.mj_step2(self.model, self.data)
        if self._pushed:
            self.data.xfrc_applied[:] = 0.0
            self._pushed = False
        mj.mj_step1(self.model, self.data)  # the new state's kinematics and velocities, for the reads
        self.elapsed += self.time_step
        self._mirror_stale = True
        for callback in self.after_step:
            callback()

    # --- reads ------------------------------------------------------------------------------------------
    def _index(self, name: str, link: str | int) -> int:
        return self.source.link_index(name, link) if isinstance(link, str) else link

    def link_frame(self, name: str, link: str | int) -> tuple[np.ndarray, np.ndarray]:
        """World position (m) and xyzw quaternion of a link's frame (the link by name or index; -1 the base)."""
        frame = self.link_motion(name, link)
        return frame[0], frame[1]

    def link_motion(self, name: str, link: str | int, velocity: bool = False) -> tuple[np.ndarray, ...]:
        """A link's frame: world position (m), xyzw quaternion and, with ``velocity``, the linear (m/s) and
        angular (rad/s) velocity of the frame's origin, world frame."""
        if self._reads_source():  # a reset: the mirror holds the state, at rest
            return self.source.link_motion(name, link, velocity)
        b = self._joints[name, self._index(name, link)][0]
        w, x, y, z = self.data.xquat[b]
        out = (self.data.xpos[b].copy(), np.array([x, y, z, w]))
        if not velocity:
            return out
        v = np.empty(6)  # mjOBJ_XBODY: at the body's frame (mjOBJ_BODY is at its centre of mass, xipos)
        self._mj.mj_objectVelocity(self.model, self.data, self._mj.mjtObj.mjOBJ_XBODY, b, v, 0)
        return (*out, v[3:].copy(), v[:3].copy())

    def motor_positions(self, motors: Sequence[tuple[str, Sequence[int]]]) -> np.ndarray:
        """The positions of the joints of ``motors`` now, in their order (rad or m)."""
        if self._reads_source():
            return self.source.motor_positions(motors)
        return self.data.qpos[self._motors(motors)[1]].copy()

    def joint_positions(self, name: str, joints: Sequence[int]) -> np.ndarray:
        """The positions of 1-dof joints of body ``name`` now (rad or m), as PyBullet's ``joint_positions``:
        driven or passive."""
        if self._reads_source():
            return self.source.joint_positions(name, joints)
        return self.data.qpos[[self._joints[name, j][2] for j in joints]].copy()

    def set_time_step(self, time_step: float) -> None:
        """Change MuJoCo's physics step (s) from the next step on (a scene that steps a duration exactly); the
        servos and loop closures keep the gains they were written with for :attr:`settings`' step."""
        self._ready()
        self.model.opt.timestep = self.time_step = float(time_step)

    def motor_forces(self, motors: Sequence[tuple[str, Sequence[int]]]) -> np.ndarray:
        """The force (N) or torque (N m) each servo of ``motors`` applied in the last step, in their order."""
        self._ready()
        return self.data.actuator_force[self._motors(motors)[0]].copy()

    def loop_residual(self) -> float:
        """The largest gap (m) between the two points of a loop closure now, in MuJoCo (its ``connect``
        constraints' sites); 0 without loops (after a reset, before a step: the mirror's)."""
        if self._reads_source():
            return self.source.loop_residual()
        return export.mujoco_loop_gap(self.model, self.data)

    def joint_values(self, name: str) -> list[tuple[float, ...]]:
        """Every joint of body ``name`` now, as :meth:`PyBulletSim.joint_values` gives them."""
        self._pose_mirror()
        return self.source.joint_values(name)

    def clearance(self, name: str, others: Sequence[str], max_distance: float,
                  links: Sequence[int] | None = None) -> tuple[float, str | None]:
        """:meth:`PyBulletSim.clearance` at MuJoCo's state (the mirror's geometry)."""
        return self._geometry().clearance(name, others, max_distance, links)

    def render(self, width: int, height: int, target: Vector, distance: float, yaw: float, pitch: float,
               fov: float = 45.0) -> np.ndarray:
        """:meth:`PyBulletSim.render` of the mirror at MuJoCo's state."""
        return self._geometry().render(width, height, target, distance, yaw, pitch, fov)

    # --- resets: the mirror is posed, MuJoCo loads it before it runs --------------------------------
    def reset_joint(self, name: str, joint: int, value: float | Vector) -> None:
        """Put a joint at ``value`` (a number, or an xyzw quaternion), the mechanism at rest."""
        self._pose_mirror()
        self.source.reset_joint(name, joint, value)
        self._need_load = True

    def place_free(self, part: tuple[str, int], floats: Sequence[tuple[str, int]], position: Vector,
                   quaternion: Vector) -> None:
        """:meth:`PyBulletSim.place_free`, the mechanism at rest."""
        self._pose_mirror()
        self.source.place_free(part, floats, position, quaternion)
        self._need_load = True

    def reset_base(self, name: str, position: Vector, quaternion: Vector) -> None:
        """:meth:`PyBulletSim.reset_base`, the mechanism at rest."""
        self._pose_mirror()
        self.source.reset_base(name, position, quaternion)
        self._need_load = True

    def friction(self, name: str, links: Sequence[int], lateral: float) -> None:
        """Set the contact friction coefficient of ``links`` of body ``name`` (-1: the base) in MuJoCo (its geoms'
        sliding friction: a contact takes the larger of its two geoms', and the ground's is 0,
        :func:`paragym.sim.export.mjcf`) and in the mirror, from the next step on. The ground's and the fixed
        parts' stay as written (0: a contact takes the robot part's)."""
        self.source.friction(name, links, lateral)
        if all(name != tree for tree, _, _ in self._trees):
            return
        for link in links:
            self._friction[name, link] = float(lateral)
            if self.model is not None:
                self._set_friction(name, link, float(lateral))

    def _set_friction(self, name: str, link: int, lateral: float) -> None:
        self.model.geom_friction[self.model.geom_bodyid == self._joints[name, link][0], 0] = lateral

    def rebuild(self) -> None:
        """A fresh world, as :meth:`PyBulletSim.rebuild`: the mirror is rebuilt (the scene's set-up runs again,
        through this object) and MuJoCo starts from it at its next step, with nothing of what ran before."""
        self.source.rebuild()
        self._need_load, self._mirror_stale = True, False

    # --- the world's bodies: the mirror's (fixed parts reach MuJoCo at the next load) ---------------------
    def add_static(self, name: str, shape: Any, rgba: Vector = (0.7, 0.3, 0.3, 1.0)) -> None:
        self._pose_mirror()
        self.source.add_static(name, shape, rgba)
        self._need_load = True

    def add_static_group(self, name: str, shapes: Sequence[Any],
                         rgba: Vector = (0.7, 0.3, 0.3, 1.0)) -> None:
        self._pose_mirror()
        self.source.add_static_group(name, shapes, rgba)
        self._need_load = True

    def remove(self, name: str) -> None:
        self._pose_mirror()
        self.source.remove(name)  # a rebuild of the mirror re-runs the scene's set-up, through this object
        self._need_load = True

    # --- the scene's bookkeeping and set-up: the source's (its PyBullet world or its description), which a
    # --- rebuild runs again; what the MJCF holds of it was written when the model was ----------------------
    @property
    def loops(self) -> dict[tuple[str, str | None, str, str | None], tuple[tuple[float, ...], tuple[float, ...]]]:
        """The loop closures, as :attr:`PyBulletSim.loops <paragym.sim.client.PyBulletSim.loops>`."""
        return self.source.loops

    @property
    def stops(self) -> dict[tuple[str, str | None], tuple[float, float]]:
        """The joints' hard stops, as :attr:`PyBulletSim.stops <paragym.sim.client.PyBulletSim.stops>`."""
        return self.source.stops

    @property
    def recipes(self) -> dict[str, Recipe]:
        """How each body was built (:mod:`paragym.sim.recipes`)."""
        return self.source.recipes

    @property
    def body_names(self) -> tuple[str, ...]:
        return self.source.body_names

    @property
    def gui(self) -> bool:
        return bool(self.source.gui)

    def link_name(self, name: str, index: int) -> str | None:
        return self.source.link_name(name, index)

    def link_index(self, name: str, link: str) -> int:
        return self.source.link_index(name, link)

    def locate(self, link: str) -> tuple[str, int]:
        return self.source.locate(link)

    def set_physics(self, gravity: float, time_step: float, solver_iterations: int, erp: float | None = None) -> None:
        self.source.set_physics(gravity, time_step, solver_iterations, erp)

    def no_self_collision(self, *names: str) -> None:
        self.source.no_self_collision(*names)

    def passive(self, name: str, joints: Sequence[int], spherical: Sequence[int] = ()) -> None:
        self.source.passive(name, joints, spherical)

    def ball_joint(self, name: str, link_a: int, pivot_a: Vector, link_b: int, pivot_b: Vector,
                   other: str | None = None) -> None:
        self.source.ball_joint(name, link_a, pivot_a, link_b, pivot_b, other)

    def no_collision(self, name: str) -> None:
        self.source.no_collision(name)

    def joint_stops(self, name: str, joints: Sequence[int], lower: float, upper: float) -> None:
        self.source.joint_stops(name, joints, lower, upper)

    def on_rebuild(self, setup: Any) -> None:
        self.source.on_rebuild(setup)

    def contact_friction(self, name: str, link: int) -> float:
        return self.source.contact_friction(name, link)

    def close(self) -> None:
        """Close the PyBullet world (the mirror, or a described scene's picture) and drop the MuJoCo model."""
        for world in (self.source, self._picture):
            if world is not None and hasattr(world, "close"):
                world.close()
        self.model = self.data = None


def _same_parts(a: Any, b: Any) -> bool:
    """Whether two lists of fixed parts (name, shape) are the same (shapes compared by their numbers)."""
    if a is None or b is None or len(a) != len(b):
        return False
    return all(na == nb and repr(sa) == repr(sb) for (na, sa), (nb, sb) in zip(a, b, strict=True))


class RolloutPool:
    """MuJoCo's ``rollout`` on ``threads`` threads, with the work space (an ``MjData`` per thread) kept from one
    call to the next while the models keep their size. :meth:`close` ends the threads."""

    def __init__(self, threads: int) -> None:
        from mujoco import rollout

        self._rollout = rollout.Rollout(nthread=threads)
        self.threads = threads
        self._workers: list[Any] = []
        self._signature: int | None = None

    def workers(self, model: Any) -> list[Any]:
        """An ``MjData`` per thread for models of ``model``'s size."""
        if model.signature != self._signature:
            self._workers = [_import_mujoco().MjData(model) for _ in range(self.threads)]
            self._signature = model.signature
        return self._workers

    def rollout(self, *args: Any, **kwargs: Any) -> Any:
        return self._rollout.rollout(*args, **kwargs)

    def close(self) -> None:
        self._rollout.close()


def rollout_pool(robots: int) -> RolloutPool | None:
    """A :class:`RolloutPool` for a world of ``robots``: as many threads as the kernels take
    (:func:`paragym.kernels.thread_count`: ``PARAGYM_THREADS``, else a thread per core this process may use), at
    most one per robot; None where that is one thread (the caller's)."""
    threads = min(robots, thread_count())
    return RolloutPool(threads) if threads > 1 else None


def ramp_together(sims: Sequence[MuJoCoSim], motors: Sequence[tuple[str, Sequence[int]]], starts: np.ndarray,
                  goals: np.ndarray, duration: float, pool: Any = None) -> None:
    """:meth:`MuJoCoSim.ramp` of each of ``sims`` (robots of one world: one mechanism, their models of one size,
    each with :attr:`~MuJoCoSim.cold_periods`) from ``starts`` to ``goals`` (M, n), in one call of MuJoCo's
    ``rollout`` on the threads of ``pool`` (a :class:`RolloutPool`; None: the calling thread), which holds no lock
    while it steps. Each robot's motion is its own ramp's to the bit (each period starts the solver cold, which
    ``rollout`` does); its frames and velocities are computed after, its motor forces (``actuator_force``) and
    contacts are not. A robot that is watched step by step
    (``after_step``) or pushed is ramped alone."""
    from mujoco import rollout

    mj = _import_mujoco()
    spec = int(mj.mjtState.mjSTATE_FULLPHYSICS)  # what rollout takes and gives
    alone = np.array([bool(sim.after_step or sim._pushed or not sim.cold_periods) for sim in sims])
    for k in np.flatnonzero(alone).tolist():
        sims[k].ramp(motors, starts[k], goals[k], duration)
    rows = np.flatnonzero(~alone)
    if not rows.size:
        return
    batch = [sims[k] for k in rows.tolist()]
    force = batch[0]._force(motors)  # a world's robots: one mechanism, one servo force
    ids, inputs = batch[0]._ramp_inputs(motors, starts[rows], goals[rows], duration, force)
    models = [sim.model for sim in batch]
    first = models[0]
    state = np.empty((len(batch), mj.mj_stateSize(first, spec)))
    control = np.empty((len(batch), inputs.shape[1], first.nu))
    for k, sim in enumerate(batch):
        if k:
            sim._ready()
            sim.model.actuator_forcerange[ids] = (-force, force)
        mj.mj_getState(sim.model, sim.data, state[k], spec)
        control[k] = sim.data.ctrl
    control[:, :, ids] = inputs
    workers = pool.workers(first) if pool is not None else [mj.MjData(first)]
    runner = pool.rollout if pool is not None else rollout.rollout
    out = np.empty((len(batch), inputs.shape[1], state.shape[1]))
    runner(models, workers, state, control, initial_warmstart=np.zeros((len(batch), first.nv)), state=out,
           sensordata=np.empty((len(batch), inputs.shape[1], first.nsensordata)), nstep=inputs.shape[1],
           skip_checks=True)
    h, steps = batch[0].time_step, inputs.shape[1]
    for k, sim in enumerate(batch):
        mj.mj_setState(sim.model, sim.data, out[k, -1], spec)
        sim.data.ctrl[:] = control[k, -1]
        sim.data.qacc_warmstart[:] = 0.0
        for stage in (mj.mj_kinematics, mj.mj_comPos, mj.mj_comVel):  # the frames and velocities the reads read
            stage(sim.model, sim.data)
        for _ in range(steps):
            sim.elapsed += h
        sim._mirror_stale = True


def read_together(sims: Sequence[MuJoCoSim], motors: Sequence[tuple[str, Sequence[int]]],
                  frames: Sequence[tuple[str, int]]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What a batch of robots (as :func:`ramp_together` takes them) reads after a ramp, in one array each: the
    positions of ``motors`` (M, n) (:meth:`MuJoCoSim.motor_positions`), the frames of the links ``frames``
    ((body, link) each), their positions (M, F, 3) and xyzw quaternions (M, F, 4) (:meth:`MuJoCoSim.link_frame`),
    and the largest loop gap (M,) (:meth:`MuJoCoSim.loop_residual`): the same numbers, to the bit."""
    first = sims[0]
    for sim in sims:
        sim._reads_source()
    adr = first._motors(motors)[1]
    b = [first._joints[body, link][0] for body, link in frames]
    datas = [sim.data for sim in sims]
    positions = np.array([data.qpos for data in datas])[:, adr]
    frame = np.array([data.xpos for data in datas])[:, b]
    quaternion = np.array([data.xquat for data in datas])[:, b][..., [1, 2, 3, 0]]
    model = first.model
    if model.neq:
        sites = np.array([data.site_xpos for data in datas])
        gaps = sites[:, model.eq_obj1id] - sites[:, model.eq_obj2id]
        gap = np.sqrt((gaps**2).sum(axis=2)).max(axis=1)
    else:
        gap = np.zeros(len(sims))
    return positions, frame, quaternion, gap
