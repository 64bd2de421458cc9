"""A PyBullet client with bodies addressed by name.

Tasks never see PyBullet's integer ids. One :class:`PyBulletSim` per
environment: ``DIRECT`` (headless) by default, ``GUI`` on request; ``close()``
disconnects it. Rendering to an array uses the TinyRenderer, so it works
without a display.

A manipulator is *one* multibody, a tree of links (:class:`LinkSpec`): for
a parallel manipulator, the spanning tree of its closed chain, cut open where
the analytic model closes it. Its joint values come from that model; one
``resetJointStatesMultiDof`` call places every part and one
``getClosestPoints`` call per obstacle answers clearance for the whole
manipulator (one call instead of one per part).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym.mechanisms.geometry import PartShape, quat_to_matrix
from paragym.sim.obstacles import Capsule, Cylinder, Obstacle
from paragym.sim.recipes import Heightfield, Plane, Recipe, StaticBody, StaticGroup, TreeBody, Vector, VisualBody

__all__ = ["LinkBook", "LinkSpec", "Motors", "PyBulletSim", "depth_first", "divides", "exact_time_step", "motors_of",
           "physics_steps", "refined"]

#: motors on one or more bodies: (body name, its joint indices) in order; their targets are concatenated in that order
Motors = Sequence[tuple[str, Sequence[int]]]

_IDENTITY = (0.0, 0.0, 0.0, 1.0)


class _PyBullet:
    """PyBullet, imported at its first use (then this module's ``pb`` is PyBullet itself): a scene simulated
    in MuJoCo alone (:mod:`paragym.sim.description`) never imports it."""

    def __getattr__(self, name: str) -> Any:
        import pybullet

        globals()["pb"] = pybullet
        return getattr(pybullet, name)


pb: Any = _PyBullet()
#: PyBullet's joint types, by :class:`LinkSpec`'s names for them
_JOINT_TYPES = ("revolute", "prismatic", "spherical", "fixed")


def _joint_type(kind: str) -> int:
    return (pb.JOINT_REVOLUTE, pb.JOINT_PRISMATIC, pb.JOINT_SPHERICAL, pb.JOINT_FIXED)[_JOINT_TYPES.index(kind)]


def motors_of(joints: Sequence[tuple[str, int]]) -> list[tuple[str, list[int]]]:
    """:data:`Motors` for ``joints`` (body name, joint index), in their order: consecutive joints of one
    body make one group."""
    motors: list[tuple[str, list[int]]] = []
    for body, joint in joints:
        if motors and motors[-1][0] == body:
            motors[-1][1].append(joint)
        else:
            motors.append((body, [joint]))
    return motors


def physics_steps(duration: float, time_step: float) -> int:
    """Physics steps of ``time_step`` s that make up ``duration`` s of control (at least one): the duration
    rounded to whole steps (:func:`exact_time_step` gives the step that makes it up exactly)."""
    return max(1, int(round(duration / time_step)))


def refined(dynamics: Any, step: float, iterations: int) -> Any:
    """The same model as ``dynamics`` (a dynamic scene's settings: a frozen dataclass with ``time_step`` and
    ``solver_iterations``) integrated at ``step`` times its physics step with ``iterations`` times its solver
    iterations: its per-step settings (its class's ``PER_STEP`` names, e.g. PyBullet's motor position gain,
    whose bandwidth is the gain over the step) scaled with the step, so that the servos stay as fast. What a
    convergence study sweeps (``benchmarks/convergence.py``)."""
    from dataclasses import replace

    per_step = {name: getattr(dynamics, name) * step for name in getattr(dynamics, "PER_STEP", ())}
    return replace(dynamics, time_step=dynamics.time_step * step,
                   solver_iterations=int(dynamics.solver_iterations * iterations), **per_step)


def divides(duration: float, time_step: float) -> bool:
    """Whether whole physics steps of ``time_step`` s make up ``duration`` s (to 1e-9 of it)."""
    return abs(physics_steps(duration, time_step) * time_step - duration) <= 1e-9 * duration


def exact_time_step(duration: float, time_step: float) -> float:
    """The physics step (s) that makes up ``duration`` s exactly, at most ``time_step``: ``time_step`` itself
    where it :func:`divides` the duration, else the duration cut into the fewest equal steps no longer than
    ``time_step``."""
    if divides(duration, time_step):
        return time_step
    return duration / math.ceil(duration / time_step)


@dataclass(frozen=True)
class LinkSpec:
    """One link of a tree body: its joint to ``parent`` (None: the base) of
    type ``joint`` ("revolute", "prismatic", "spherical", "fixed") about
    ``axis`` (link frame), the joint frame at ``position``/``orientation``
    (xyzw) in the parent's link frame, and an optional shape (a part or an
    obstacle-like primitive) at ``shape_offset`` in the link frame."""

    name: str
    parent: str | None
    joint: str
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    orientation: tuple[float, float, float, float] = _IDENTITY
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    shape: PartShape | None = None
    shape_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rgba: tuple[float, float, float, float] = (0.5, 0.5, 0.5, 1.0)
    mass: float = 1e-3  # kg; the centre of mass sits at the shape's centre


def depth_first(links: Sequence[LinkSpec]) -> list[LinkSpec]:
    """Links in depth-first pre-order (children in the order given)."""
    children: dict[str | None, list[LinkSpec]] = {}
    for link in links:
        children.setdefault(link.parent, []).append(link)
    out: list[LinkSpec] = []
    stack = list(reversed(children.get(None, [])))
    while stack:
        link = stack.pop()
        out.append(link)
        stack.extend(reversed(children.get(link.name, [])))
    if len(out) != len(links):
        raise ValueError("links must form a tree rooted at the base (a parent is missing or a cycle exists)")
    return out


class LinkBook:
    """The bookkeeping a scene's bodies share whatever holds them (:class:`PyBulletSim`, or a
    :class:`~paragym.sim.description.SceneDescription`): each tree body's links by name and index
    (``_links``, ``_link_names``), how each body was built (``_recipe``: its :mod:`~paragym.sim.recipes`
    record), and the free parts placed through the holder's ``reset_base`` and ``reset_joint``."""

    _links: dict[str, dict[str, int]]
    _link_names: dict[str, dict[int, str]]
    _recipe: dict[str, Recipe]

    def link_name(self, name: str, index: int) -> str | None:
        """The name of link ``index`` of body ``name`` (None: the base, -1)."""
        return self._link_names[name].get(index)

    def link_index(self, name: str, link: str) -> int:
        """The index of ``link`` in body ``name`` (PyBullet's, depth-first)."""
        return self._links[name][link]

    def locate(self, link: str) -> tuple[str, int]:
        """The body holding the link named ``link``, and the link's index in it."""
        for name, links in self._links.items():
            if link in links:
                return name, links[link]
        raise ValueError(f"no link named {link!r}")

    def _in_link_frame(self, name: str, link: int, point: Vector) -> tuple[float, ...]:
        """A point given in a link's centre-of-mass frame, in its link frame (the two differ by the link's
        ``shape_offset``, their axes aligned): a base's two frames are one."""
        tree = self._recipe[name]
        links = tree.links if isinstance(tree, TreeBody) else ()
        offset = next((spec.shape_offset for spec in links if spec.name == self._link_names[name].get(link)),
                      (0.0, 0.0, 0.0))
        return tuple(float(p + o) for p, o in zip(point, offset, strict=True))

    def reset_base(self, name: str, position: Vector, quaternion: Vector) -> None:
        raise NotImplementedError

    def reset_joint(self, name: str, joint: int, value: float | Vector) -> None:
        raise NotImplementedError

    def place_free(self, part: tuple[str, int], floats: Sequence[tuple[str, int]], position: Vector,
                   quaternion: Vector) -> None:
        """Put a free rigid part at ``position`` (m), turned by the xyzw ``quaternion``, at rest: ``part`` is
        (body, link), either a free body's base (link -1, ``floats`` empty) or a link on a spherical joint
        at the end of the three prismatic joints ``floats`` (x, y, z; each (body, joint)) of a tree."""
        if part[1] < 0:
            self.reset_base(part[0], position, quaternion)
            return
        for joint, value in zip(floats, position, strict=True):
            self.reset_joint(*joint, float(value))
        self.reset_joint(*part, quaternion)


class PyBulletSim(LinkBook):
    """One PyBullet connection; bodies by name.

    Args:
        gui: open the PyBullet GUI (``render_mode="human"``) instead of DIRECT.
        draws: give the bodies visual shapes. A scene that is never drawn (an env without a render mode, a
            checker of scenarios) builds collision shapes only: the same contacts and distances, and a body
            built in about half the time (the CaPaMan's obstacles at every reset).
    """

    def __init__(self, gui: bool = False, draws: bool = True) -> None:
        if gui and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            # PyBullet's GUI kills the whole process when there is no X server: refuse first.
            raise RuntimeError('render_mode="human" opens the PyBullet GUI and needs a display (DISPLAY is '
                               'not set); use render_mode="rgb_array" on a headless machine')
        self._client = pb.connect(pb.GUI if gui else pb.DIRECT)
        if self._client < 0:
            raise RuntimeError("could not connect to PyBullet" + (" (GUI needs a display)" if gui else ""))
        self.gui = gui
        self.draws = draws or gui
        self._bodies: dict[str, int] = {}
        #: how each body was built (method, arguments), in order: replayed when the world is rebuilt
        self._recipe: dict[str, Recipe] = {}
        #: set-up that lives outside the bodies (gravity, constraints, filters), run again after a rebuild
        self._setup: list[Any] = []
        self._removed = 0
        self._links: dict[str, dict[str, int]] = {}
        self._link_names: dict[str, dict[int, str]] = {}
        #: the loop closures (:meth:`ball_joint`), by (body, link, other body, other link) names (None: a base):
        #: the two points, each in its link's frame (m); what :mod:`paragym.sim.export` writes
        self.loops: dict[tuple[str, str | None, str, str | None], tuple[tuple[float, ...], tuple[float, ...]]] = {}
        #: the joints' hard stops (:meth:`joint_stops`), by (body, link name): (lower, upper) (rad or m)
        self.stops: dict[tuple[str, str | None], tuple[float, float]] = {}
        #: each servo's force limit (N or N m) and PyBullet's gains, (body, joint) -> (force, position gain, velocity
        #: gain), as :meth:`servos` set them
        self.servo_settings: dict[tuple[str, int], tuple[float, float, float]] = {}
        #: functions called after every physics step (:meth:`step`), e.g. to record a body's motion
        self.after_step: list[Any] = []
        #: the physics step (s) and the simulated time (s) so far
        self.time_step = 1.0 / 240.0  # PyBullet's default
        self.elapsed = 0.0
        self._drawing = True
        if gui:
            pb.configureDebugVisualizer(pb.COV_ENABLE_GUI, 0, physicsClientId=self._client)
            self._draw(False)  # until the world is built: the GUI redraws after every body otherwise

    def _draw(self, on: bool) -> None:
        """Let the GUI draw (``on``) or not. A GUI that draws while bodies are made redraws the scene after
        each of them: building the tripod's terrain took 14 s instead of 2. Bodies are made with drawing off,
        and drawing comes back with the first step, pose or picture."""
        if self.gui and on != self._drawing:
            pb.configureDebugVisualizer(pb.COV_ENABLE_RENDERING, int(on), physicsClientId=self._client)
            self._drawing = on

    # --- lifetime -------------------------------------------------------------------
    @property
    def connected(self) -> bool:
        """True until :meth:`close`."""
        return self._client >= 0 and pb.isConnected(physicsClientId=self._client)

    def close(self) -> None:
        """Disconnect (idempotent)."""
        if self._client >= 0:
            if pb.isConnected(physicsClientId=self._client):
                pb.disconnect(physicsClientId=self._client)
            self._client = -1
            self._bodies.clear()

    def __del__(self) -> None:  # a forgotten close() must not leak a connection
        try:
            self.close()
        except Exception:
            pass

    # --- building ---------------------------------------------------------------------
    def _shape(self, shape: PartShape | Obstacle, rgba: Vector,
               offset: Vector = (0.0, 0.0, 0.0)) -> tuple[int, int]:
        c = self._client
        frame = {"collisionFramePosition": list(offset)}
        vframe = {"visualFramePosition": list(offset)}
        vis = -1
        if isinstance(shape, PartShape) and shape.kind == "sphere":
            col = pb.createCollisionShape(pb.GEOM_SPHERE, radius=shape.radius, physicsClientId=c, **frame)
            if self.draws:
                vis = pb.createVisualShape(pb.GEOM_SPHERE, radius=shape.radius, rgbaColor=rgba, physicsClientId=c,
                                           **vframe)
        elif isinstance(shape, Capsule):
            col = pb.createCollisionShape(pb.GEOM_CAPSULE, radius=shape.radius, height=shape.height,
                                          physicsClientId=c, **frame)
            if self.draws:
                vis = pb.createVisualShape(pb.GEOM_CAPSULE, radius=shape.radius, length=shape.height,
                                           rgbaColor=rgba, physicsClientId=c, **vframe)
        elif isinstance(shape, Cylinder) or (isinstance(shape, PartShape) and shape.kind == "cylinder"):
            radius = shape.radius
            length = shape.height if isinstance(shape, Cylinder) else shape.length
            col = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=radius, height=length, physicsClientId=c,
                                          **frame)
            if self.draws:
                vis = pb.createVisualShape(pb.GEOM_CYLINDER, radius=radius, length=length, rgbaColor=rgba,
                                           physicsClientId=c, **vframe)
        else:
            half = list(shape.half_extents)
            col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=c, **frame)
            if self.draws:
                vis = pb.createVisualShape(pb.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=c,
                                           **vframe)
        return col, vis

    def add_static(self, name: str, shape: Obstacle, rgba: Vector = (0.7, 0.3, 0.3, 1.0)) -> None:
        """Add a fixed body (an obstacle or a base plate) named ``name``."""
        self._draw(False)
        self._check_new(name)
        self._recipe[name] = StaticBody(name, shape, rgba)
        col, vis = self._shape(shape, rgba)
        self._bodies[name] = pb.createMultiBody(0.0, col, vis, basePosition=list(shape.center),
                                                physicsClientId=self._client)

    def add_static_group(self, name: str, shapes: Sequence[Obstacle],
                         rgba: Vector = (0.7, 0.3, 0.3, 1.0)) -> None:
        """Add fixed shapes (obstacles) as one body named ``name``: one
        ``getClosestPoints`` call then answers for all of them."""
        self._draw(False)
        self._check_new(name)
        self._recipe[name] = StaticGroup(name, shapes, rgba)
        cols, vis = zip(*(self._shape(o, rgba) for o in shapes), strict=True)
        n = len(shapes)
        self._bodies[name] = pb.createMultiBody(
            0.0, -1, -1, linkMasses=[0.0] * n, linkCollisionShapeIndices=list(cols),
            linkVisualShapeIndices=list(vis), linkPositions=[o.center for o in shapes],
            linkOrientations=[_IDENTITY] * n, linkInertialFramePositions=[(0, 0, 0)] * n,
            linkInertialFrameOrientations=[_IDENTITY] * n, linkParentIndices=[0] * n,
            linkJointTypes=[pb.JOINT_FIXED] * n, linkJointAxis=[(0, 0, 1)] * n, physicsClientId=self._client)

    def add_visual(self, name: str, shape: PartShape | Obstacle, rgba: Vector,
                   position: Vector = (0.0, 0.0, 0.0),
                   quaternion: Vector = (0.0, 0.0, 0.0, 1.0)) -> None:
        """Add a body named ``name`` that is only drawn (no collision, no
        mass), at ``position`` (m) turned by the xyzw ``quaternion``."""
        self._draw(False)
        self._check_new(name)
        self._recipe[name] = VisualBody(name, shape, rgba, position, quaternion)
        self._bodies[name] = pb.createMultiBody(0.0, -1, self._shape(shape, rgba)[1], basePosition=list(position),
                                                baseOrientation=list(quaternion), physicsClientId=self._client)

    def add_heightfield(self, name: str, heights: np.ndarray, cell: float, position: Vector,
                        rgba: Vector) -> None:
        """Add ground named ``name``: ``heights`` (rows along y, columns along
        x; m) on a grid of ``cell`` (m), its centre at ``position``."""
        self._draw(False)
        self._check_new(name)
        self._recipe[name] = Heightfield(name, heights, cell, position, rgba)
        c = self._client
        ny, nx = heights.shape
        shape = pb.createCollisionShape(pb.GEOM_HEIGHTFIELD, meshScale=[cell, cell, 1.0],
                                        heightfieldData=heights.ravel().tolist(), numHeightfieldRows=nx,
                                        numHeightfieldColumns=ny, physicsClientId=c)
        body = pb.createMultiBody(0, shape, basePosition=list(position), physicsClientId=c)
        pb.changeVisualShape(body, -1, rgbaColor=list(rgba), physicsClientId=c)
        self._bodies[name] = body

    def add_plane(self, name: str, rgba: Vector) -> None:
        """Add flat ground named ``name``: the plane z = 0 (cheaper to collide with than a flat heightfield)."""
        self._draw(False)
        self._check_new(name)
        self._recipe[name] = Plane(name, rgba)
        c = self._client
        shape = pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=c)
        visual = pb.createVisualShape(pb.GEOM_BOX, halfExtents=[14.0, 5.0, 0.001], rgbaColor=list(rgba),
                                      visualFramePosition=[11.0, 0.0, -0.001], physicsClientId=c)
        self._bodies[name] = pb.createMultiBody(0, shape, visual, physicsClientId=c)

    def place(self, name: str, position: Vector, quaternion: Vector) -> None:
        """Move body ``name``'s base to ``position`` (m), turned by the xyzw ``quaternion``."""
        if not self._drawing:
            self._draw(True)
        pb.resetBasePositionAndOrientation(self._bodies[name], list(position), list(quaternion),
                                           physicsClientId=self._client)

    def add_tree_body(self, name: str, links: Sequence[LinkSpec], base_mass: float = 0.0,
                      base_shape: PartShape | None = None,
                      base_rgba: Vector = (0.5, 0.5, 0.5, 1.0)) -> None:
        """Add a multibody whose base sits at the world origin and whose
        ``links`` form a tree; a link is addressed by its name, its parent by
        name (None: the base, link index -1). Link frames are placed by the
        joint values given to :meth:`set_joints`. The base is fixed and has no
        shape unless ``base_mass`` (kg) > 0: then it is a free rigid body (its
        centre of mass at its frame's origin, with ``base_shape``), placed by
        :meth:`reset_base`."""
        self._draw(False)
        self._check_new(name)
        self._recipe[name] = TreeBody(name, links, base_mass, base_shape, base_rgba)
        base_col, base_vis = (-1, -1) if base_shape is None else self._shape(base_shape, base_rgba)
        links = depth_first(links)  # PyBullet stores links in this order whatever order it is given
        index = {link.name: i for i, link in enumerate(links)}
        cols, vis = [], []
        for link in links:
            if link.shape is None:
                cols.append(-1)
                vis.append(-1)
            else:
                c, v = self._shape(link.shape, link.rgba, link.shape_offset)
                cols.append(c)
                vis.append(v)
        n = len(links)
        body = pb.createMultiBody(
            base_mass, base_col, base_vis, linkMasses=[link.mass for link in links], linkCollisionShapeIndices=cols,
            linkVisualShapeIndices=vis,
            linkPositions=[link.position for link in links],
            linkOrientations=[link.orientation for link in links],
            linkInertialFramePositions=[link.shape_offset for link in links],
            linkInertialFrameOrientations=[_IDENTITY] * n,
            linkParentIndices=[0 if link.parent is None else index[link.parent] + 1 for link in links],
            linkJointTypes=[_joint_type(link.joint) for link in links],
            linkJointAxis=[link.axis for link in links],
            physicsClientId=self._client)
        self._bodies[name] = body
        self._links[name] = index
        self._link_names[name] = {i: link for link, i in index.items()}

    def set_joints(self, name: str, joints: Sequence[int], values: Sequence[Vector]) -> None:
        """Set joint positions of body ``name``: one list per joint (``[q]`` for
        revolute/prismatic, an xyzw quaternion for spherical)."""
        if not self._drawing:
            self._draw(True)
        pb.resetJointStatesMultiDof(self._bodies[name], joints, values, physicsClientId=self._client)

    def body(self, name: str) -> int:
        """PyBullet id of body ``name`` now (it changes when the world is rebuilt)."""
        return self._bodies[name]

    def link_frame(self, name: str, link: str | int) -> tuple[np.ndarray, np.ndarray]:
        """World position (m) and xyzw quaternion of a link's frame (the link by name or index)."""
        frame = self.link_motion(name, link)
        return frame[0], frame[1]

    def link_motion(self, name: str, link: str | int, velocity: bool = False) -> tuple[np.ndarray, ...]:
        """A link's frame: world position (m), xyzw quaternion and, with
        ``velocity``, the linear (m/s) velocity of the frame's origin and the angular (rad/s) velocity, as
        :class:`~paragym.sim.mujoco_sim.MuJoCoSim` gives them. PyBullet reports the linear velocity of the link's
        centre of mass; the origin's is v_com + omega x (p_origin - p_com)."""
        index = self._links[name][link] if isinstance(link, str) else link
        if index < 0:  # the base
            body, c = self._bodies[name], self._client
            base = pb.getBasePositionAndOrientation(body, physicsClientId=c)
            if velocity:
                base += pb.getBaseVelocity(body, physicsClientId=c)
            return tuple(np.array(v) for v in base)
        state = pb.getLinkState(self._bodies[name], index, computeLinkVelocity=velocity, computeForwardKinematics=True,
                                physicsClientId=self._client)
        if not velocity:
            return np.array(state[4]), np.array(state[5])
        (ox, oy, oz), (cx, cy, cz), (wx, wy, wz) = state[4], state[0], state[7]
        rx, ry, rz = ox - cx, oy - cy, oz - cz  # omega x r, written out (np.cross of two 3-vectors is slow)
        vx, vy, vz = state[6]
        return (np.array(state[4]), np.array(state[5]),
                np.array([vx + (wy * rz - wz * ry), vy + (wz * rx - wx * rz), vz + (wx * ry - wy * rx)]),
                np.array(state[7]))

    # --- dynamics -------------------------------------------------------------------------
    def set_physics(self, gravity: float, time_step: float, solver_iterations: int, erp: float | None = None) -> None:
        """Gravity (m/s^2, along -z), the fixed time step (s), the constraint
        solver's iterations and, if given, its error reduction parameter (the
        share of a constraint's drift corrected per step; PyBullet's default
        otherwise)."""
        pb.setGravity(0, 0, -gravity, physicsClientId=self._client)
        pb.setPhysicsEngineParameter(fixedTimeStep=time_step, numSolverIterations=solver_iterations,
                                     physicsClientId=self._client)
        self.time_step = time_step
        if erp is not None:
            pb.setPhysicsEngineParameter(erp=erp, physicsClientId=self._client)

    def no_self_collision(self, *names: str) -> None:
        """The parts of the bodies ``names`` (one mechanism) do not collide with each other."""
        c = self._client
        parts = [(self._bodies[name], link) for name in names
                 for link in range(-1, pb.getNumJoints(self._bodies[name], physicsClientId=c))]
        for i, (body_a, link_a) in enumerate(parts):
            for body_b, link_b in parts[i + 1:]:
                pb.setCollisionFilterPair(body_a, body_b, link_a, link_b, 0, physicsClientId=c)

    def passive(self, name: str, joints: Sequence[int], spherical: Sequence[int] = ()) -> None:
        """Make joints free (no motor): PyBullet's default velocity motors off,
        for 1-dof ``joints`` and ``spherical`` ones."""
        body, c = self._bodies[name], self._client
        pb.setJointMotorControlArray(body, list(joints), pb.VELOCITY_CONTROL, forces=[0.0] * len(joints),
                                     physicsClientId=c)
        for joint in spherical:
            pb.setJointMotorControlMultiDof(body, joint, pb.POSITION_CONTROL, targetPosition=[0, 0, 0, 1],
                                            force=[0.0, 0.0, 0.0], physicsClientId=c)

    def ball_joint(self, name: str, link_a: int, pivot_a: Vector, link_b: int,
                   pivot_b: Vector, other: str | None = None) -> None:
        """Close a loop: a ball joint (point-to-point constraint) between a
        point of ``link_a`` of body ``name`` and a point of ``link_b`` of body
        ``other`` (default: the same body; -1: a base), each in its link's
        centre-of-mass frame (m)."""
        pb.createConstraint(self._bodies[name], link_a, self._bodies[other or name], link_b, pb.JOINT_POINT2POINT,
                            [0, 0, 0], list(pivot_a), list(pivot_b), physicsClientId=self._client)
        other = other or name
        key = (name, self._link_names[name].get(link_a), other, self._link_names[other].get(link_b))
        self.loops[key] = (self._in_link_frame(name, link_a, pivot_a), self._in_link_frame(other, link_b, pivot_b))

    def loop_residual(self) -> float:
        """The largest gap (m) between the two points of a loop closure (:attr:`loops`) now; 0 without loops.
        From PyBullet's link frames, which it reports in single precision: about 1e-8 m at best."""
        gaps = [0.0]
        for (name_a, link_a, name_b, link_b), points in self.loops.items():
            ends = []
            for name, link, point in ((name_a, link_a, points[0]), (name_b, link_b, points[1])):
                pos, xyzw = self.link_frame(name, -1 if link is None else link)
                ends.append(pos + quat_to_matrix(xyzw) @ np.asarray(point))
            gaps.append(float(np.linalg.norm(ends[0] - ends[1])))
        return max(gaps)

    def no_collision(self, name: str) -> None:
        """No part of body ``name`` collides with anything (a mechanism alone in its scene, whose parts
        meet at their joints): the parts leave the collision detection altogether."""
        body, c = self._bodies[name], self._client
        for link in range(-1, pb.getNumJoints(body, physicsClientId=c)):
            pb.setCollisionFilterGroupMask(body, link, 0, 0, physicsClientId=c)

    def joint_stops(self, name: str, joints: Sequence[int], lower: float, upper: float) -> None:
        """Hard stops on 1-dof ``joints`` of body ``name`` at ``lower`` and ``upper`` (rad or m): PyBullet's
        joint-limit constraint, which acts only when a joint reaches a stop (a unilateral row, like a contact)."""
        for joint in joints:
            pb.changeDynamics(self._bodies[name], joint, jointLowerLimit=lower, jointUpperLimit=upper,
                              physicsClientId=self._client)
            self.stops[name, self._link_names[name].get(joint)] = (float(lower), float(upper))

    def friction(self, name: str, links: Sequence[int], lateral: float) -> None:
        """Set the contact friction coefficient of ``links`` of body ``name`` (-1: the base)."""
        for link in links:
            pb.changeDynamics(self._bodies[name], link, lateralFriction=lateral, physicsClientId=self._client)

    def contact_friction(self, name: str, link: int) -> float:
        """The contact friction coefficient of ``link`` of body ``name`` (-1: the base) now, as
        :meth:`friction` set it (PyBullet's default, 0.5, where nothing did)."""
        return float(pb.getDynamicsInfo(self._bodies[name], link, physicsClientId=self._client)[1])

    def push(self, name: str, link: int, force: Vector) -> None:
        """Apply ``force`` (N, world frame) at the centre of mass of ``link`` of body ``name`` for the next step."""
        pos = self.link_frame(name, link)[0]
        pb.applyExternalForce(self._bodies[name], link, list(force), list(pos), pb.WORLD_FRAME,
                              physicsClientId=self._client)

    def reset_joint(self, name: str, joint: int, value: float | Vector) -> None:
        """Put a joint at ``value`` (a number, or an xyzw quaternion for a spherical joint), at rest."""
        body, c = self._bodies[name], self._client
        if isinstance(value, int | float | np.floating):
            pb.resetJointState(body, joint, float(value), 0.0, physicsClientId=c)
        else:
            pb.resetJointStateMultiDof(body, joint, list(value), [0.0, 0.0, 0.0], physicsClientId=c)

    def servos(self, motors: Motors, force: float, position_gain: float, velocity_gain: float) -> None:
        """The position servos on the joints of ``motors`` from now on: each at most ``force`` (N or N m), with
        PyBullet's normalised gains (:attr:`servo_settings`); :meth:`drive` and :meth:`ramp` command them."""
        for name, joints in motors:
            for joint in joints:
                self.servo_settings[name, joint] = (force, position_gain, velocity_gain)

    def drive(self, motors: Motors, targets: Vector, rates: Vector) -> None:
        """The servos of ``motors`` (:meth:`servos`) chase ``targets`` at ``rates`` from the next step on."""
        start, c = 0, self._client
        targets, rates = [float(v) for v in targets], [float(v) for v in rates]  # one conversion, not per body
        for name, joints in motors:
            n = len(joints)
            force, position_gain, velocity_gain = zip(*(self.servo_settings[name, j] for j in joints), strict=True)
            pb.setJointMotorControlArray(self._bodies[name], joints, pb.POSITION_CONTROL,
                                         targetPositions=targets[start:start + n],
                                         targetVelocities=rates[start:start + n], forces=list(force),
                                         positionGains=list(position_gain), velocityGains=list(velocity_gain),
                                         physicsClientId=c)
            start += n

    def ramp(self, motors: Motors, start: np.ndarray, goal: np.ndarray, duration: float) -> None:
        """Move the targets of the servos of ``motors`` linearly from ``start`` to ``goal`` over ``duration`` s (at
        least one physics step), stepping the physics as they go; the servos chase the moving targets (and their
        constant rate)."""
        steps = physics_steps(duration, self.time_step)
        rate = (goal - start) / (steps * self.time_step)
        for i in range(1, steps + 1):
            self.drive(motors, start + (goal - start) * (i / steps), rate)
            self.step()

    def set_time_step(self, time_step: float) -> None:
        """Change the physics step (s) from the next step on."""
        pb.setPhysicsEngineParameter(fixedTimeStep=time_step, physicsClientId=self._client)
        self.time_step = time_step

    def step(self) -> None:
        """One step of the physics (then the :attr:`after_step` callbacks: a recorder's)."""
        if not self._drawing:
            self._draw(True)
        pb.stepSimulation(physicsClientId=self._client)
        self.elapsed += self.time_step
        for callback in self.after_step:
            callback()

    def joint_positions(self, name: str, joints: Sequence[int]) -> np.ndarray:
        """The positions of 1-dof joints now (rad or m)."""
        return np.array([s[0] for s in pb.getJointStates(self._bodies[name], list(joints),
                                                         physicsClientId=self._client)])

    def motor_positions(self, motors: Motors) -> np.ndarray:
        """The positions of the joints of ``motors`` now, in their order (rad or m)."""
        c = self._client
        return np.array([s[0] for name, joints in motors
                         for s in pb.getJointStates(self._bodies[name], list(joints), physicsClientId=c)])

    def motor_forces(self, motors: Motors) -> np.ndarray:
        """The force (N) or torque (N m) each joint of ``motors`` applied in the last physics step, in their
        order."""
        c = self._client
        return np.array([s[3] for name, joints in motors
                         for s in pb.getJointStates(self._bodies[name], list(joints), physicsClientId=c)])

    def reset_base(self, name: str, position: Vector, quaternion: Vector) -> None:
        """Put the free base of body ``name`` at ``position`` (m), turned by the xyzw ``quaternion``, at rest."""
        body, c = self._bodies[name], self._client
        pb.resetBasePositionAndOrientation(body, list(position), list(quaternion), physicsClientId=c)
        pb.resetBaseVelocity(body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)

    def on_rebuild(self, setup: Any) -> None:
        """Run ``setup()`` now and again whenever :meth:`remove` rebuilds the
        world: whatever a scene sets up beside its bodies (gravity, engine
        parameters, constraints, collision filters, motors)."""
        self._setup.append(setup)
        setup()

    #: removed bodies that PyBullet still holds, at most, before the world is rebuilt to free them
    REBUILD_AFTER = 64

    def remove(self, name: str) -> None:
        """Remove the body ``name``; the joints of the other bodies may be reset
        (the caller poses the scene again).

        PyBullet never frees a removed body's collision shapes (its
        ``removeCollisionShape`` refuses them as still in use), so a scene
        that swaps obstacles at every reset grew by about 5 KiB a swap,
        without bound. Every :data:`REBUILD_AFTER` removals the world is
        therefore reset (``resetSimulation``, which frees everything) and
        every remaining body is built again from its recipe, with the same
        names and link indices, then the :meth:`on_rebuild` set-ups run
        again: memory stays bounded, and the rebuild's cost is spread over
        that many removals. Body ids change
        at a rebuild: address bodies by name."""
        if name not in self._bodies:
            raise ValueError(f"no body named {name!r}; bodies: {', '.join(self._bodies)}")
        pb.removeBody(self._bodies.pop(name), physicsClientId=self._client)
        del self._recipe[name]
        self._links.pop(name, None)
        self._link_names.pop(name, None)
        self.loops = {key: points for key, points in self.loops.items() if name not in (key[0], key[2])}
        self.stops = {key: stop for key, stop in self.stops.items() if key[0] != name}
        self._removed += 1
        if self._removed >= self.REBUILD_AFTER:
            self._rebuild()

    def rebuild(self) -> None:
        """Reset the PyBullet world and build every body and set-up again (:meth:`remove`): a fresh
        world, with nothing cached from what ran before (contacts and their impulses included)."""
        self._rebuild()

    def _rebuild(self) -> None:
        """Reset the PyBullet world and build every body and set-up again."""
        recipe = list(self._recipe.values())
        self._draw(False)
        pb.resetSimulation(physicsClientId=self._client)
        self._bodies.clear()
        self._recipe.clear()
        self._links.clear()
        self._link_names.clear()
        self.loops.clear()
        self.stops.clear()
        self._removed = 0
        for built in recipe:
            built.build_in(self)
        for setup in self._setup:
            setup()

    def _check_new(self, name: str) -> None:
        if name in self._bodies:
            raise ValueError(f"a body named {name!r} exists already")

    @property
    def recipes(self) -> dict[str, Recipe]:
        """How each body now in the scene was built, in order: name -> its record (:mod:`paragym.sim.recipes`)."""
        return dict(self._recipe)

    def joint_values(self, name: str) -> list[tuple[float, ...]]:
        """Every joint of body ``name`` now, in PyBullet's order (:meth:`add_tree_body`'s depth-first one):
        ``(q,)`` for a revolute or prismatic joint (rad or m), an xyzw quaternion for a spherical one, ``()``
        for a fixed one."""
        body, c = self._bodies[name], self._client
        return [tuple(pb.getJointStateMultiDof(body, j, physicsClientId=c)[0])
                for j in range(pb.getNumJoints(body, physicsClientId=c))]

    @property
    def body_names(self) -> tuple[str, ...]:
        """Names of the bodies in the scene."""
        return tuple(self._bodies)

    # --- state and queries --------------------------------------------------------------
    def clearance(self, name: str, others: Sequence[str], max_distance: float,
                  links: Sequence[int] | None = None) -> tuple[float, str | None]:
        """Smallest signed distance (m; negative when penetrating) between body
        ``name`` and the bodies ``others``, capped at ``max_distance``; and the
        link of ``name`` where it occurs (None when nothing is within the cap).
        Every link counts, the base (link -1) included: a free body's base,
        named after its body, is a part like any other.

        ``links`` restricts the query to those links of ``name`` (PyBullet
        runs the narrow phase on every link pair of two multibodies, so
        leaving out links that cannot come within the cap saves time).
        """
        best, where = max_distance, None
        body, c = self._bodies[name], self._client
        for other in others:
            target = self._bodies[other]
            if links is None:
                points = pb.getClosestPoints(body, target, max_distance, physicsClientId=c)
            else:
                points = [pt for link in links for pt in
                          pb.getClosestPoints(body, target, max_distance, linkIndexA=link, physicsClientId=c)]
            for pt in points:
                if pt[8] < best:
                    best, where = pt[8], pt[3]
        if where is None:
            return max_distance, None
        return best, name if where < 0 else self._link_names[name][where]

    def render(self, width: int, height: int, target: Vector, distance: float,
               yaw: float, pitch: float, fov: float = 45.0) -> np.ndarray:
        """An RGB image (height, width, 3) uint8 from an orbit camera (degrees),
        drawn by the TinyRenderer (no display needed)."""
        if not self._drawing:
            self._draw(True)
        c = self._client
        view = pb.computeViewMatrixFromYawPitchRoll(list(target), distance, yaw, pitch, 0.0, 2,
                                                    physicsClientId=c)
        proj = pb.computeProjectionMatrixFOV(fov, width / height, 0.01, 10.0, physicsClientId=c)
        _, _, rgba, _, _ = pb.getCameraImage(width, height, view, proj, renderer=pb.ER_TINY_RENDERER,
                                             physicsClientId=c)
        return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3].copy()
