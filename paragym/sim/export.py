"""A dynamic scene's mechanism as a model file: MJCF (MuJoCo) or URDF with a loop-closure sidecar.

The files are written from what the scene itself built (:class:`~paragym.sim.client.PyBulletSim`'s
``recipes``, its ``loops`` and the scene's ``motor_limits()``), so the exported geometry is the simulated one:
every link's joint frame, axis, part and mass, every loop closure and every motor's force limit.

* **MJCF**: the links nested as bodies with hinge, slide and ball joints; each loop closure an equality
  ``connect`` between two sites, one on each link, so that both points are stated (not read off the model's
  reference pose); the motors as ``position`` servos whose ``forcerange`` is the scene's force limit, critically
  damped at a bandwidth the physics step h integrates stably, 0.5 / h rad/s (or a scene's own), for the
  inertia each one moves (:func:`servo_gains`); the fixed parts (guides, obstacles) as world geoms. The
  robot's parts do not collide with each other (``contype`` 2, ``conaffinity`` 1) but with the fixed parts
  (1, 2), as in the scene; the fixed parts' contacts take the loops' ``solref``/``solimp``: with MuJoCo's
  defaults the CaPaMan pushed into a box at its torque limit sank 1.8 mm deeper than in PyBullet, with these
  0.5 mm (``benchmarks/conformance.py``). A part that slides along a fixed guide (a scene's
  ``RIDING`` links, the 2PRR's sliders) touches nothing: its joint is the guide. Ground (the tripod's plane
  or heightfield) is a world geom (a heightfield an ``hfield`` asset) that takes each robot part's friction
  coefficient, on MuJoCo's elliptic friction cone at an ``impratio`` of 10, under which friction holds below
  its limit (with the defaults, a pyramid at 1, a loaded wheel creeps; the dynamics guide has the figures).
  A written file (:func:`write`) stands on its own: its ``qpos0`` and ``home`` keyframe are the pose after
  ``reset(seed=0)``, where the loops close, and its servos are ``general`` actuators whose ``ctrl`` is the
  target's displacement from home (zero holds it), so that ``MjData`` stepped as loaded holds its loops.
  The loops' ``solref``/``solimp`` (:func:`loop_solref`, :data:`LOOP_SOLIMP`) are stiffer than MuJoCo's
  defaults, with which a closed chain under gravity sags at its pins (mujoco #2698;
  ``benchmarks/conformance.py`` measures both). Gravity and the solver iterations are the scene's; the physics
  step is at most 1 ms (:func:`mujoco_time_step`), with MuJoCo's default integrator (semi-implicit Euler: on the
  CaPaMan ``implicitfast`` let the loops open 40 times as far).
* **URDF**: the open tree (every link, its joint to its parent with the motors' force limits as ``effort``),
  the fixed parts as links fixed to the base; URDF has no ball joint, so a spherical joint is three revolute
  joints (about z, y, x, in that order from the parent) through two links of 1e-6 kg. The loop closures and
  actuators go to a JSON sidecar (``<file>.loops.json``): each closure names the two links and the point on each,
  in that link's frame (m), to be closed by a ball joint, as the Extended-URDF proposal and urdfdom's
  ``<constraint>`` discussion suggest. The sidecar's ``home`` gives every joint's value at the pose where
  the loops close (URDF has no reference pose), and ``missing`` what the URDF cannot hold (a ground).

Lengths in m, angles in rad, masses in kg, force limits in N (slides) or N m (hinges).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from paragym.mechanisms.geometry import PartShape, quat_to_matrix
from paragym.sim.client import LinkSpec, depth_first
from paragym.sim.obstacles import Box, Capsule, Cylinder
from paragym.sim.recipes import GROUND, Plane, StaticBody, StaticGroup, TreeBody

__all__ = ["FORMATS", "LOOP_SOLIMP", "MUJOCO_STEP", "bodies_of", "check_mjcf", "check_urdf", "fixed_parts",
           "loop_solref", "mjcf", "model_name", "mujoco_loop_gap", "mujoco_motor_positions", "mujoco_pose",
           "mujoco_time_step", "servo_gains", "tree_frames", "tree_of", "urdf", "with_fixed_parts"]

#: the formats :func:`write` writes, and each one's file suffix
FORMATS = {"mjcf": ".xml", "urdf": ".urdf"}
#: the loop closures' impedance in MJCF: harder than MuJoCo's default (0.9, 0.95, 0.001, 0.5, 2)
LOOP_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
#: the exported servos' bandwidth times the physics step (rad): how stiff they are against what the step
#: integrates stably (semi-implicit Euler goes unstable as it nears 2)
SERVO_BANDWIDTH = 0.5


#: MuJoCo's physics step (s): the default of :class:`~paragym.sim.mujoco_sim.MuJoCoSettings`, and an exported
#: MJCF's where the scene's is longer (the longest a setting may take is
#: :data:`paragym.sim.mujoco_sim.MAX_STEP`)
MUJOCO_STEP = 1e-3


def mujoco_time_step(time_step: float) -> float:
    """The exported MJCF's physics step (s): the scene's, at most :data:`MUJOCO_STEP`. MuJoCo's position
    servos are springs integrated step by step, where PyBullet's motors are velocity constraints solved in the
    step: holding a 4 kg platform on 0.2 kg legs, the hybrid's servos at its 5 ms step are either too soft to
    hold it or unstable; at 1 ms they hold it (``benchmarks/conformance.py``)."""
    return min(time_step, MUJOCO_STEP)


def loop_solref(time_step: float) -> tuple[float, float]:
    """The loop closures' ``solref`` in MJCF: a time constant of two physics steps (the shortest MuJoCo takes;
    its default, 0.02 s, lets a loop sag under load), critically damped."""
    return (2.0 * time_step, 1.0)


def servo_gains(links: list[LinkSpec], frames: dict[str, tuple[np.ndarray, np.ndarray]], link: str,
                time_step: float, bandwidth: float = SERVO_BANDWIDTH) -> tuple[float, float]:
    """A position servo's ``kp`` and ``kv`` for the joint of ``link``: critically damped at ``bandwidth`` / h
    rad/s (h: the physics step; :data:`SERVO_BANDWIDTH`, or a scene's ``EXPORT_SERVO_BANDWIDTH``) for what it
    moves: the mass of the link's subtree for a slide, its moment of inertia about the axis for a hinge (point
    masses at the parts' centres, the links placed at ``frames``, :func:`tree_frames`; where those all sit on
    the axis, as a wheel's, the parts' own moments about it, as solids). The loop closures add
    what they carry on top; the servo is then softer than the one paragym simulates, by at most that ratio."""
    children: dict[str | None, list[LinkSpec]] = {}
    for spec in links:
        children.setdefault(spec.parent, []).append(spec)
    spec = next(s for s in links if s.name == link)
    subtree, stack = [], [spec]
    while stack:
        item = stack.pop()
        subtree.append(item)
        stack.extend(children.get(item.name, []))
    pos, rot = frames[link]
    axis = rot @ (np.asarray(spec.axis, float) / np.linalg.norm(spec.axis))
    if spec.joint == "prismatic":
        inertia = sum(item.mass for item in subtree)
    else:
        inertia = 0.0
        for item in subtree:
            p, r = frames[item.name]
            arm = p + r @ np.asarray(item.shape_offset, float) - pos
            inertia += item.mass * float(np.sum((arm - np.dot(arm, axis) * axis) ** 2))
        if inertia < 1e-6:  # the masses sit on the axis (a wheel): the parts' own moments about it instead
            for item in subtree:
                local = frames[item.name][1].T @ axis
                shape = item.shape if isinstance(item.shape, PartShape) else None
                inertia += float(local @ (np.asarray(_inertia(shape, item.mass)) * local))
        inertia = max(inertia, 1e-6)
    omega = bandwidth / time_step
    return inertia * omega**2, 2.0 * inertia * omega
#: the mass (kg) of the two links that carry a spherical joint's first two axes in URDF
AXIS_LINK_MASS = 1e-6


def _num(values: Any) -> str:
    """Numbers as MJCF and URDF take them: space-separated, each exact (``repr`` of a float)."""
    return " ".join(repr(float(v)) for v in np.atleast_1d(values))


def _wxyz(xyzw: Any) -> tuple[float, ...]:
    x, y, z, w = (float(v) for v in xyzw)
    return (w, x, y, z)


def bodies_of(sim: Any) -> tuple[list[tuple[str, list[LinkSpec], float, PartShape | None]], list[tuple[str, Any]]]:
    """The tree bodies (name, links, base mass, base shape) and fixed parts (name, shape) of the PyBullet ``sim``,
    in the order they were built; ground (a plane or a heightfield: the scenario's terrain) and drawn-only bodies
    are left out."""
    trees, fixed = [], []
    for name, recipe in sim.recipes.items():
        if isinstance(recipe, TreeBody):
            trees.append((name, list(recipe.links), float(recipe.base_mass), recipe.base_shape))
        elif isinstance(recipe, StaticBody):
            fixed.append((name, recipe.shape))
        elif isinstance(recipe, StaticGroup):
            fixed += [(f"{name}_{k}", shape) for k, shape in enumerate(recipe.shapes)]
    return trees, fixed


def _motors(scene: Any) -> dict[tuple[str, str], float]:
    """(body, link name) -> the motor's force limit."""
    return {(body, scene.sim.link_name(body, joint)): float(limit) for body, joint, limit in scene.motor_limits()}


# --- MJCF ---------------------------------------------------------------------------------------------------------


def _mjcf_geom(parent: ET.Element, shape: PartShape | Any, pos: Any, robot: bool, mass: float | None = None,
               rgba: Any = None, name: str | None = None, friction: float | None = None) -> None:
    attrs: dict[str, str] = {"pos": _num(pos)}
    if name:
        attrs["name"] = name
    if isinstance(shape, Capsule):
        attrs.update(type="capsule", size=_num([shape.radius, shape.height / 2]))
    elif isinstance(shape, Cylinder):
        attrs.update(type="cylinder", size=_num([shape.radius, shape.height / 2]))
    elif isinstance(shape, Box):
        attrs.update(type="box", size=_num(shape.half_extents))
    elif shape.kind == "sphere":
        attrs.update(type="sphere", size=_num(shape.radius))
    elif shape.kind == "cylinder":
        attrs.update(type="cylinder", size=_num([shape.radius, shape.length / 2]))
    else:
        attrs.update(type="box", size=_num(shape.half_extents))
    attrs.update(contype="2" if robot else "1", conaffinity="1" if robot else "2")
    if mass is not None:
        attrs["mass"] = _num(mass)
    if rgba is not None:
        attrs["rgba"] = _num(rgba)
    if friction is not None:  # sliding; MuJoCo's default torsional and rolling friction
        attrs["friction"] = _num([friction, 0.005, 0.0001])
    ET.SubElement(parent, "geom", attrs)


def mjcf(scene: Any, model: str = "paragym", time_step: float | None = None, bandwidth: float | None = None,
         iterations: int | None = None, home: bool = False) -> str:
    """The scene's mechanism as an MJCF document (module docstring). ``time_step`` (s), the servos'
    ``bandwidth`` (:func:`servo_gains`) and the solver's ``iterations`` replace the exported defaults
    (:func:`mujoco_time_step`, the scene's ``EXPORT_SERVO_BANDWIDTH`` or :data:`SERVO_BANDWIDTH`, the scene's
    iterations) where given: a MuJoCo dynamic fidelity's settings (:mod:`paragym.sim.mujoco_sim`).

    With ``home`` the file stands on its own at the scene's pose now (a closed one after a reset): every body is
    written where that pose puts it, so that the model's reference configuration ``qpos0`` is the pose (a hinge's
    or slide's ``ref`` is its value there, so its ``qpos`` still means the scene's joint value; a ball's ``qpos``
    is its rotation from the pose; a free body starts where it is), a keyframe ``home`` holds ``qpos0``, and the
    servos are ``general`` actuators whose ``ctrl`` is the target's displacement from home (a ``ctrl`` of zero,
    ``MjData``'s, holds the pose). Without it the bodies are written at joint values of zero and the servos as
    ``position`` actuators: the form :class:`~paragym.sim.mujoco_sim.MuJoCoSim` compiles and poses itself."""
    trees, fixed = bodies_of(scene.sim)
    motors = _motors(scene)
    d = scene.dynamics
    root = ET.Element("mujoco", model=model)
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    h = mujoco_time_step(d.time_step) if time_step is None else float(time_step)
    option = ET.SubElement(root, "option", timestep=_num(h), gravity=_num([0.0, 0.0, -d.gravity]),
                           iterations=str(int(d.solver_iterations if iterations is None else iterations)))
    world = ET.SubElement(root, "worldbody")
    ground = _ground(root, world, scene.sim, h)
    if ground:  # friction that holds below its limit: MuJoCo's pyramid cone at an impratio of 1 lets a loaded
        # wheel creep; the elliptic cone at 10 holds it (the dynamics guide)
        option.set("cone", "elliptic")
        option.set("impratio", "10")
    _fixed_geoms(world, fixed, h)
    stops = getattr(scene.sim, "stops", {})
    for body, links, base_mass, base_shape in trees:
        posed = dict(zip((link.name for link in depth_first(links)), scene.sim.joint_values(body), strict=True)) \
            if home else {}
        base = ET.SubElement(world, "body", name=body)
        if base_mass > 0:  # a free body
            if home:
                pos, xyzw = scene.sim.link_frame(body, -1)
                base.set("pos", _num(pos))
                base.set("quat", _num(_wxyz(xyzw)))
            ET.SubElement(base, "freejoint", name=f"{body}_free")
            _mjcf_geom(base, base_shape, (0.0, 0.0, 0.0), robot=True, mass=base_mass,
                       friction=scene.sim.contact_friction(body, -1) if ground else None)
        elements: dict[str | None, ET.Element] = {None: base}
        for link in depth_first(links):
            pos, rot = np.asarray(link.position, float), quat_to_matrix(np.asarray(link.orientation, float))
            kind = {"revolute": "hinge", "prismatic": "slide", "spherical": "ball"}.get(link.joint)
            attrs = {}
            if link.name in posed and kind is not None:  # the joint's value at the pose goes into the body's frame
                pos, rot, ref = _posed_frame(link, pos, rot, posed[link.name])
                if ref is not None:
                    attrs["ref"] = _num(ref)
            quat = Rotation.from_matrix(rot).as_quat() if posed else link.orientation
            el = ET.SubElement(elements[link.parent], "body", name=model_name(body, link.name, len(trees)),
                               pos=_num(pos), quat=_num(_wxyz(quat)))
            elements[link.name] = el
            if kind is not None:
                attrs = {"name": f"{el.get('name')}_joint", "type": kind, **attrs}
                if kind != "ball":
                    attrs["axis"] = _num(link.axis)
                if (body, link.name) in stops:  # a hard stop: MuJoCo's joint limit
                    attrs["range"] = _num(stops[body, link.name])
                ET.SubElement(el, "joint", attrs)
            if link.shape is None:
                ET.SubElement(el, "inertial", pos=_num(link.shape_offset), mass=_num(link.mass),
                              diaginertia=_num([1e-9] * 3))
            else:
                friction = scene.sim.contact_friction(body, scene.sim.link_index(body, link.name)) if ground else None
                _mjcf_geom(el, link.shape, link.shape_offset, robot=True, mass=link.mass, rgba=link.rgba,
                           friction=friction)
                if link.name in getattr(scene, "RIDING", ()):  # it slides along its guide: its joint is the guide
                    el[-1].set("contype", "0")
                    el[-1].set("conaffinity", "0")
    sites = []
    for k, ((body_a, link_a, body_b, link_b), (point_a, point_b)) in enumerate(scene.sim.loops.items()):
        for side, body, link, point in (("a", body_a, link_a, point_a), ("b", body_b, link_b, point_b)):
            owner = _element(root, f".//body[@name='{model_name(body, link, len(trees)) if link else body}']")
            ET.SubElement(owner, "site", name=f"loop{k}_{side}", pos=_num(point), size="0.005")
        sites.append((f"loop{k}_a", f"loop{k}_b"))
    if sites:
        equality = ET.SubElement(root, "equality")
        for a, b in sites:
            ET.SubElement(equality, "connect", site1=a, site2=b, solref=_num(loop_solref(h)),
                          solimp=_num(LOOP_SOLIMP))
    if motors:
        actuator = ET.SubElement(root, "actuator")
        if bandwidth is None:
            bandwidth = getattr(scene, "EXPORT_SERVO_BANDWIDTH", SERVO_BANDWIDTH)
        # body -> its links in PyBullet's order and their frames now: once per body, not per motor
        trees_now: dict[str, tuple[list[LinkSpec], dict[str, tuple[np.ndarray, np.ndarray]]]] = {}
        for body, links, _, _ in trees:
            ordered = depth_first(links)
            trees_now[body] = ordered, tree_frames(ordered, scene.sim.joint_values(body))
        for (body, driven), limit in motors.items():
            joint = f"{model_name(body, driven, len(trees))}_joint"
            kp, kv = servo_gains(*trees_now[body], driven, h, bandwidth)
            if home:  # ctrl: the target's displacement from home, so that a ctrl of zero holds the home pose
                ref = float(_element(root, f".//joint[@name='{joint}']").get("ref", "0"))
                ET.SubElement(actuator, "general", name=f"{joint}_motor", joint=joint, gainprm=_num(kp),
                              biastype="affine", biasprm=_num([kp * ref, -kp, -kv]),
                              forcerange=_num([-limit, limit]))
            else:
                ET.SubElement(actuator, "position", name=f"{joint}_motor", joint=joint, kp=_num(kp), kv=_num(kv),
                              forcerange=_num([-limit, limit]))
    if home:
        _home_key(root)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


def _posed_frame(link: LinkSpec, pos: np.ndarray, rot: np.ndarray, value: tuple[float, ...]
                 ) -> tuple[np.ndarray, np.ndarray, float | None]:
    """A link's body frame in its parent's (position, rotation) with its joint at ``value`` (:func:`mjcf`'s
    ``home``), and the joint's ``ref`` there (None for a ball, whose qpos0 is the identity)."""
    axis = np.asarray(link.axis, float) / np.linalg.norm(link.axis)
    if link.joint == "revolute":
        return pos, rot @ Rotation.from_rotvec(axis * value[0]).as_matrix(), float(value[0])
    if link.joint == "prismatic":
        return pos + rot @ (axis * value[0]), rot, float(value[0])
    return pos, rot @ quat_to_matrix(np.asarray(value, float)), None


def _home_key(root: ET.Element) -> None:
    """The keyframe ``home`` of an MJCF written with ``home`` (:func:`mjcf`): ``qpos0`` as MuJoCo compiles it
    (the joints in the document's order: a free joint's body pose, a ball's identity, a hinge's or slide's
    ``ref``), and every servo's ``ctrl`` at zero (a displacement from home)."""
    qpos = []
    for body in root.iter("body"):
        for joint in body:
            if joint.tag == "freejoint":
                qpos += [float(v) for v in (body.get("pos", "0 0 0") + " " + body.get("quat", "1 0 0 0")).split()]
            elif joint.tag == "joint" and joint.get("type") == "ball":
                qpos += [1.0, 0.0, 0.0, 0.0]
            elif joint.tag == "joint":
                qpos.append(float(joint.get("ref", "0")))
    attrs = {"name": "home", "qpos": _num(qpos)}
    servos = root.find("actuator")
    if servos is not None:
        attrs["ctrl"] = _num([0.0] * len(servos))
    ET.SubElement(ET.SubElement(root, "keyframe"), "key", attrs)


def _ground(root: ET.Element, world: ET.Element, sim: Any, time_step: float) -> bool:
    """The scene's ground, if it has one, as a geom of ``world`` (a heightfield's elevations an ``hfield`` asset
    of ``root``, placed before ``world``): fixed, frictionless itself so that a contact takes the robot part's
    coefficient (MuJoCo takes the larger of the two; PyBullet multiplies them, and paragym's ground has 1), as
    stiff as the loops at the physics step ``time_step`` (s), its impedance the contact's (a ``solmix`` that
    outweighs the robot part's MuJoCo default, which, averaged in, let a loaded wheel slide on a sideways load
    well below its friction limit). True where there was ground."""
    grounds = [r for r in sim.recipes.values() if isinstance(r, GROUND)]
    for ground in grounds:
        attrs = {"name": ground.name, "contype": "1", "conaffinity": "2", "friction": "0 0 0",
                 "solref": _num(loop_solref(time_step)), "solimp": _num(LOOP_SOLIMP), "solmix": "1000000",
                 "rgba": _num(ground.rgba)}
        if isinstance(ground, Plane):  # z = 0, without bounds
            attrs.update(type="plane", size="0 0 1")
        else:
            heights, cell, centre = np.asarray(ground.heights, float), float(ground.cell), ground.position
            ny, nx = heights.shape
            low, span = float(heights.min()), float(heights.max() - heights.min())
            assets = root.find("asset")
            if assets is None:
                assets = ET.Element("asset")
                root.insert(list(root).index(world), assets)
            # MuJoCo scales the elevations to [0, 1], times size[2], above the geom's z; its first row is at +y
            # (paragym's at -y); to a nanometre, as MuJoCo keeps float32
            ET.SubElement(assets, "hfield", name=ground.name, nrow=str(ny), ncol=str(nx),
                          size=_num([(nx - 1) * cell / 2, (ny - 1) * cell / 2, max(span, 1e-9), 0.1]),
                          elevation=_num(np.round(heights[::-1] - low, 9).ravel()))
            attrs.update(type="hfield", hfield=ground.name, pos=_num([centre[0], centre[1], low]))
        ET.SubElement(world, "geom", attrs)
    return bool(grounds)


def _fixed_geoms(world: ET.Element, fixed: list[tuple[str, Any]], time_step: float) -> None:
    """The fixed parts (name, shape) as world geoms of ``world``, their contacts as stiff as the loops (module
    docstring) at the physics step ``time_step`` (s)."""
    for name, shape in fixed:
        _mjcf_geom(world, shape, shape.center, robot=False, name=name)
        world[-1].set("solref", _num(loop_solref(time_step)))
        world[-1].set("solimp", _num(LOOP_SOLIMP))


def fixed_parts(sim: Any) -> list[tuple[str, Any]]:
    """The fixed parts (guides, obstacles) of a PyBullet scene now: (name, shape), as :func:`mjcf` writes them."""
    return bodies_of(sim)[1]


def with_fixed_parts(text: str, fixed: list[tuple[str, Any]]) -> str:
    """The MJCF ``text`` with its fixed parts (the world geoms that the robot collides with) replaced by
    ``fixed`` (:func:`fixed_parts`): a scene's new obstacles in a model whose robot stays as it was written."""
    root = ET.fromstring(text)
    world = _element(root, "worldbody")
    for geom in world.findall("geom"):
        if geom.get("contype") == "1" and geom.get("type") not in ("plane", "hfield"):  # the ground stays
            world.remove(geom)
    _fixed_geoms(world, fixed, float(_element(root, "option").get("timestep", "")))
    return ET.tostring(root, encoding="unicode") + "\n"


def _element(root: ET.Element, path: str) -> ET.Element:
    """The element at ``path`` (ElementTree's XPath subset) under ``root``, which a model this module wrote has."""
    found = root.find(path)
    if found is None:
        raise ValueError(f"the model has no element at {path!r}: not one paragym.sim.export wrote")
    return found


def model_name(body: str, link: str, n_trees: int) -> str:
    """A link's name in the model: its own, prefixed by its body's where the scene has several tree bodies."""
    return link if n_trees == 1 else f"{body}/{link}"



# --- URDF ---------------------------------------------------------------------------------------------------------


def _rpy(xyzw: Any) -> tuple[float, float, float]:
    """URDF's fixed-axis roll, pitch, yaw of an xyzw quaternion: R = Rz(yaw) Ry(pitch) Rx(roll) (at a pitch of
    +-90 deg, where roll and yaw are one rotation, scipy puts it all in yaw: the same R)."""
    import warnings

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Gimbal lock")
        roll, pitch, yaw = Rotation.from_quat(np.asarray(xyzw, float)).as_euler("xyz")
    return float(roll), float(pitch), float(yaw)


def _inertia(shape: PartShape | None, mass: float) -> tuple[float, float, float]:
    """The principal moments (kg m^2) of a solid part about its centre (tiny for a link without a part)."""
    if shape is None:
        return (1e-9, 1e-9, 1e-9)
    if shape.kind == "sphere":
        i = 0.4 * mass * shape.radius**2
        return (i, i, i)
    if shape.kind == "cylinder":
        r, h = shape.radius, shape.length
        side = mass * (3 * r * r + h * h) / 12
        return (side, side, 0.5 * mass * r * r)
    x, y, z = (2 * v for v in shape.half_extents)
    return (mass * (y * y + z * z) / 12, mass * (x * x + z * z) / 12, mass * (x * x + y * y) / 12)


def _urdf_shape(parent: ET.Element, shape: Any) -> None:
    geometry = ET.SubElement(parent, "geometry")
    if isinstance(shape, Capsule):  # URDF has no capsule: the cylinder between its caps' centres
        ET.SubElement(geometry, "cylinder", radius=_num(shape.radius), length=_num(shape.height))
    elif isinstance(shape, Cylinder):
        ET.SubElement(geometry, "cylinder", radius=_num(shape.radius), length=_num(shape.height))
    elif isinstance(shape, Box):
        ET.SubElement(geometry, "box", size=_num([2 * v for v in shape.half_extents]))
    elif shape.kind == "sphere":
        ET.SubElement(geometry, "sphere", radius=_num(shape.radius))
    elif shape.kind == "cylinder":
        ET.SubElement(geometry, "cylinder", radius=_num(shape.radius), length=_num(shape.length))
    else:
        ET.SubElement(geometry, "box", size=_num([2 * v for v in shape.half_extents]))


def _urdf_link(root: ET.Element, name: str, shape: Any, offset: Any, mass: float) -> None:
    link = ET.SubElement(root, "link", name=name)
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=_num(offset), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=_num(mass))
    ixx, iyy, izz = _inertia(shape if isinstance(shape, PartShape) else None, mass)
    ET.SubElement(inertial, "inertia", ixx=_num(ixx), iyy=_num(iyy), izz=_num(izz), ixy="0", ixz="0", iyz="0")
    if shape is not None:
        for tag in ("visual", "collision"):
            part = ET.SubElement(link, tag)
            ET.SubElement(part, "origin", xyz=_num(offset), rpy="0 0 0")
            _urdf_shape(part, shape)


def _urdf_joint(root: ET.Element, name: str, kind: str, parent: str, child: str, xyz: Any, rpy: Any,
                axis: Any = None, effort: float = 0.0) -> None:
    joint = ET.SubElement(root, "joint", name=name, type=kind)
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)
    ET.SubElement(joint, "origin", xyz=_num(xyz), rpy=_num(rpy))
    if kind != "fixed":
        ET.SubElement(joint, "axis", xyz=_num(axis))
        limit = {"effort": _num(effort), "velocity": "100.0"}
        if kind == "prismatic":
            limit.update(lower="-10.0", upper="10.0")
        ET.SubElement(joint, "limit", limit)


def urdf(scene: Any, model: str = "paragym") -> tuple[str, dict[str, Any]]:
    """The scene's mechanism as a URDF document of its open tree, and the loop-closure sidecar (a JSON-able
    dict; module docstring). A scene of one tree body only: a split layout has no single tree to write."""
    _, fixed = bodies_of(scene.sim)
    body, links = tree_of(scene)
    motors = {link: limit for (_, link), limit in _motors(scene).items()}
    root = ET.Element("robot", name=model)
    base = "base"
    ET.SubElement(root, "link", name=base)
    for name, shape in fixed:
        _urdf_link(root, name, shape, (0.0, 0.0, 0.0), 0.0)
        _urdf_joint(root, f"{name}_fixed", "fixed", base, name, shape.center, (0.0, 0.0, 0.0))
    joints, home = [], {}
    for link, value in zip(links, scene.sim.joint_values(body), strict=True):
        parent = link.parent or base
        if link.joint == "spherical":  # three revolute joints about z, y, x
            z, y, x = Rotation.from_quat(np.asarray(value, float)).as_euler("ZYX")
            home.update({f"{link.name}_rz_joint": float(z), f"{link.name}_ry_joint": float(y),
                         f"{link.name}_joint": float(x)})
            first, second = f"{link.name}_rz", f"{link.name}_ry"
            for child in (first, second):
                _urdf_link(root, child, None, (0.0, 0.0, 0.0), AXIS_LINK_MASS)
            _urdf_joint(root, f"{first}_joint", "continuous", parent, first, link.position, _rpy(link.orientation),
                        (0.0, 0.0, 1.0))
            _urdf_joint(root, f"{second}_joint", "continuous", first, second, (0, 0, 0), (0, 0, 0), (0.0, 1.0, 0.0))
            _urdf_link(root, link.name, link.shape, link.shape_offset, link.mass)
            _urdf_joint(root, f"{link.name}_joint", "continuous", second, link.name, (0, 0, 0), (0, 0, 0),
                        (1.0, 0.0, 0.0))
            joints.append({"link": link.name, "type": "spherical",
                           "joints": [f"{first}_joint", f"{second}_joint", f"{link.name}_joint"]})
            continue
        _urdf_link(root, link.name, link.shape, link.shape_offset, link.mass)
        kind = {"revolute": "continuous", "prismatic": "prismatic", "fixed": "fixed"}[link.joint]
        _urdf_joint(root, f"{link.name}_joint", kind, parent, link.name, link.position, _rpy(link.orientation),
                    link.axis, motors.get(link.name, 0.0))
        joints.append({"link": link.name, "type": link.joint, "joints": [f"{link.name}_joint"]})
        if link.joint != "fixed":
            home[f"{link.name}_joint"] = float(value[0])
    sidecar = {
        "format": "paragym loop closures 1",
        "robot": model,
        "units": "m, rad, kg; force limits in N (prismatic) or N m (revolute)",
        "loops": [{"type": "ball", "link_a": link_a or base, "point_a": list(point_a),
                   "link_b": link_b or base, "point_b": list(point_b)}
                  for (_, link_a, _, link_b), (point_a, point_b) in scene.sim.loops.items()],
        "actuators": [{"joint": f"{link}_joint", "force_limit": limit} for link, limit in motors.items()],
        "joints": joints,
        "home": home,
        "missing": [f"{type(r).__name__.lower()} {name!r}: URDF has no ground; the MJCF export carries it"
                    for name, r in scene.sim.recipes.items() if isinstance(r, GROUND)],
        "note": "URDF has no ball joint: a spherical joint is three continuous joints about z, y and x through two "
                f"links of {AXIS_LINK_MASS:g} kg; each loop closes by a ball joint between point_a on link_a "
                "and point_b on link_b, each in its link's frame; home gives every joint's value (rad or m) at "
                "a pose where the loops close",
    }
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n", sidecar


# --- checks -------------------------------------------------------------------------------------------------------



def tree_frames(links: list[LinkSpec], values: list[tuple[float, ...]]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every link's frame (world position, m; rotation matrix) for joint values ``values`` (in ``links``'
    depth-first order, as :meth:`~paragym.sim.client.PyBulletSim.joint_values` gives them), in double precision:
    the tree the scene simulates, from its base at the origin (PyBullet reports link frames in single precision)."""
    frames: dict[str | None, tuple[np.ndarray, np.ndarray]] = {None: (np.zeros(3), np.eye(3))}
    for link, value in zip(links, values, strict=True):
        pos, rot = frames[link.parent]
        pos = pos + rot @ np.asarray(link.position, float)
        rot = rot @ quat_to_matrix(np.asarray(link.orientation, float))
        axis = np.asarray(link.axis, float) / np.linalg.norm(link.axis)
        if link.joint == "revolute":
            rot = rot @ Rotation.from_rotvec(axis * value[0]).as_matrix()
        elif link.joint == "prismatic":
            pos = pos + rot @ (axis * value[0])
        elif link.joint == "spherical":
            rot = rot @ quat_to_matrix(np.asarray(value, float))
        frames[link.name] = (pos, rot)
    return {name: frame for name, frame in frames.items() if name is not None}


def _gaps(frames: dict[str, tuple[np.ndarray, np.ndarray]], got: Any) -> dict[str, float]:
    """The largest position (m) and orientation (rad) gap between ``frames`` and ``got(name)`` -> (pos, R)."""
    frame_m = frame_rad = 0.0
    for name, (pos, rot) in frames.items():
        p, r = got(name)
        frame_m = max(frame_m, float(np.linalg.norm(p - pos)))
        cos = (np.trace(rot.T @ r) - 1.0) / 2.0
        frame_rad = max(frame_rad, float(np.linalg.norm(rot.T @ r - np.eye(3))) if cos > 0.999 else math.acos(cos))
    return {"frame_m": frame_m, "frame_rad": frame_rad}


def tree_of(scene: Any) -> tuple[str, list[LinkSpec]]:
    """The scene's mechanism as one fixed-base tree body: its name and its links in PyBullet's (depth-first)
    order. A split layout (several bodies, free bases) is refused: URDF and the checks need one tree."""
    trees, _ = bodies_of(scene.sim)
    if len(trees) != 1 or trees[0][2] > 0:
        raise ValueError("the mechanism must be one fixed-base tree body (the dynamics' layout \"tree\"); this "
                         f"scene has {[t[0] for t in trees]}")
    return trees[0][0], depth_first(trees[0][1])


def mujoco_loop_gap(model: Any, data: Any) -> float:
    """The largest gap (m) between the two sites of a loop closure of an exported MJCF (its equality
    constraints, each a ``connect`` of two sites) in MuJoCo's ``data`` now; 0 without loops."""
    if not model.neq:
        return 0.0
    gaps = data.site_xpos[model.eq_obj1id] - data.site_xpos[model.eq_obj2id]
    return float(np.sqrt((gaps**2).sum(axis=1)).max())


def mujoco_motor_positions(model: Any, data: Any) -> np.ndarray:
    """The position (rad or m) of each actuator's joint in MuJoCo's ``data`` now, in the actuators' order."""
    return data.qpos[model.jnt_qposadr[model.actuator_trnid[:, 0]]].copy()


def mujoco_pose(model: Any, links: list[LinkSpec], values: list[tuple[float, ...]], urdf: bool) -> Any:
    """MuJoCo's data with ``values`` set on ``model``'s joints (a URDF's spherical joints through their three
    revolute ones), forward kinematics done."""
    import mujoco

    data = mujoco.MjData(model)
    for link, value in zip(links, values, strict=True):
        if link.joint == "spherical" and urdf:
            z, y, x = Rotation.from_quat(np.asarray(value, float)).as_euler("ZYX")
            for name, angle in ((f"{link.name}_rz_joint", z), (f"{link.name}_ry_joint", y), (f"{link.name}_joint", x)):
                data.qpos[model.joint(name).qposadr[0]] = angle
        elif link.joint == "spherical":
            adr = model.joint(f"{link.name}_joint").qposadr[0]
            data.qpos[adr:adr + 4] = _wxyz(value)
        elif link.joint != "fixed":
            data.qpos[model.joint(f"{link.name}_joint").qposadr[0]] = value[0]
    mujoco.mj_kinematics(model, data)
    return data


def check_mjcf(scene: Any, text: str) -> dict[str, float]:
    """The exported MJCF, loaded in MuJoCo at the scene's joint values now (at its ``home`` keyframe, for a file
    written at a pose), against the scene's tree
    (:func:`tree_frames`): the largest gap of a link's frame (``frame_m``, m; ``frame_rad``, rad), and the largest
    gap at a loop closure (``loop_m``, m: zero where those joint values close the loops, as the kinematics'
    do)."""
    import mujoco

    body, links = tree_of(scene)
    values = scene.sim.joint_values(body)
    model = mujoco.MjModel.from_xml_string(text)
    if model.nkey:  # written at its pose (:func:`mjcf`'s ``home``): load that
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        mujoco.mj_kinematics(model, data)
    else:
        data = mujoco_pose(model, links, values, urdf=False)

    def got(name: str) -> tuple[np.ndarray, np.ndarray]:
        b = model.body(name).id
        return data.xpos[b].copy(), data.xmat[b].reshape(3, 3).copy()

    out = _gaps(tree_frames(links, values), got)
    out["loop_m"] = mujoco_loop_gap(model, data)
    return out


def check_urdf(scene: Any, text: str, sidecar: dict[str, Any]) -> dict[str, float]:
    """The exported URDF, loaded in MuJoCo (its URDF importer, static bodies kept), and its sidecar's loop
    closures, at the scene's joint values now: as :func:`check_mjcf`."""
    import mujoco

    body, links = tree_of(scene)
    values = scene.sim.joint_values(body)
    keep = '<mujoco><compiler fusestatic="false" discardvisual="true" balanceinertia="true"/></mujoco>'
    model = mujoco.MjModel.from_xml_string(text.replace(">", ">" + keep, 1) if "<mujoco>" not in text else text)
    data = mujoco_pose(model, links, values, urdf=True)

    def got(name: str) -> tuple[np.ndarray, np.ndarray]:
        if name == "base":
            return np.zeros(3), np.eye(3)
        b = model.body(name).id
        return data.xpos[b].copy(), data.xmat[b].reshape(3, 3).copy()

    out = _gaps(tree_frames(links, values), got)
    loop_m = 0.0
    for loop in sidecar["loops"]:
        (pa, ra), (pb_, rb) = got(loop["link_a"]), got(loop["link_b"])
        gap = pa + ra @ np.asarray(loop["point_a"]) - (pb_ + rb @ np.asarray(loop["point_b"]))
        loop_m = max(loop_m, float(np.linalg.norm(gap)))
    out["loop_m"] = loop_m
    return out
