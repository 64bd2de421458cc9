"""A dynamic scene as data: what a scene builds and where it poses its joints, with no engine behind it.

A dynamic scene (:mod:`paragym.sim.capaman_dynamic` and the others) builds its mechanism through a handful of
calls (``add_tree_body``, ``ball_joint``, ``joint_stops``, ``add_static_group``, ...) and poses it through
others (``reset_joint``, ``place_free``, ``reset_base``). :class:`SceneDescription` answers those calls as
:class:`~paragym.sim.client.PyBulletSim` does, keeping what they say as data and doing nothing else: the bodies
and how each was built (:attr:`recipes`), the loop closures (:attr:`loops`), the joints' stops (:attr:`stops`),
the parts' friction, and every joint's value. It is what :func:`paragym.sim.export.mjcf` writes and what
:class:`~paragym.sim.mujoco_sim.MuJoCoSim` loads, so that a scene simulated in MuJoCo is built without PyBullet;
:meth:`SceneDescription.build_in` replays it in a :class:`~paragym.sim.client.PyBulletSim` where a picture is
wanted.

Joints are addressed as in PyBullet: (body name, link index in :func:`~paragym.sim.client.depth_first` order),
-1 a body's base. Lengths in m, angles in rad.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from paragym.sim.client import LinkBook, LinkSpec, depth_first
from paragym.sim.recipes import Heightfield, Plane, Recipe, StaticBody, StaticGroup, TreeBody, Vector, VisualBody

__all__ = ["SceneDescription"]

#: PyBullet's default contact friction coefficient, which a part keeps until :meth:`SceneDescription.friction`
DEFAULT_FRICTION = 0.5


class SceneDescription(LinkBook):
    """A scene's bodies, loops, stops and joint values as data (module docstring).

    Args:
        gui: the scene was asked for PyBullet's GUI: whoever simulates it builds the picture
            (:meth:`build_in`) at once.
    """

    draws = False

    def __init__(self, gui: bool = False) -> None:
        self.gui = gui
        self._recipe: dict[str, Recipe] = {}
        self._links: dict[str, dict[str, int]] = {}
        self._link_names: dict[str, dict[int, str]] = {}
        self._kinds: dict[str, list[str]] = {}
        #: the loop closures, as :attr:`PyBulletSim.loops <paragym.sim.client.PyBulletSim.loops>`
        self.loops: dict[tuple[str, str | None, str, str | None], tuple[tuple[float, ...], tuple[float, ...]]] = {}
        #: the joints' hard stops, as :attr:`PyBulletSim.stops <paragym.sim.client.PyBulletSim.stops>`
        self.stops: dict[tuple[str, str | None], tuple[float, float]] = {}
        #: the servos, as :attr:`PyBulletSim.servo_settings <paragym.sim.client.PyBulletSim.servo_settings>`
        self.servo_settings: dict[tuple[str, int], tuple[float, float, float]] = {}
        self._friction: dict[tuple[str, int], float] = {}
        self._values: dict[str, list[tuple[float, ...]]] = {}
        self._bases: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        #: gravity (m/s^2), physics step (s), solver iterations and error reduction as the scene set them
        self.physics: tuple[float, float, int, float | None] | None = None

    # --- building ----------------------------------------------------------------------------------------
    def _add(self, recipe: Recipe) -> None:
        if recipe.name in self._recipe:
            raise ValueError(f"a body named {recipe.name!r} exists already")
        self._recipe[recipe.name] = recipe

    def add_tree_body(self, name: str, links: Sequence[LinkSpec], base_mass: float = 0.0,
                      base_shape: Any = None, base_rgba: Vector = (0.5, 0.5, 0.5, 1.0)) -> None:
        """A tree of ``links`` (as :meth:`PyBulletSim.add_tree_body <paragym.sim.client.PyBulletSim.add_tree_body>`),
        every joint at zero, a free base (``base_mass`` > 0) at the origin."""
        ordered = depth_first(links)
        self._add(TreeBody(name, links, base_mass, base_shape, base_rgba))
        self._links[name] = {link.name: i for i, link in enumerate(ordered)}
        self._link_names[name] = {i: link.name for i, link in enumerate(ordered)}
        self._kinds[name] = [link.joint for link in ordered]
        self._values[name] = [_ZERO[kind] for kind in self._kinds[name]]
        if base_mass > 0:
            self._bases[name] = (np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))

    def add_static(self, name: str, shape: Any, rgba: Vector = (0.7, 0.3, 0.3, 1.0)) -> None:
        """A fixed part named ``name``."""
        self._add(StaticBody(name, shape, rgba))

    def add_static_group(self, name: str, shapes: Sequence[Any], rgba: Vector = (0.7, 0.3, 0.3, 1.0)
                         ) -> None:
        """Fixed parts (obstacles) as one body named ``name``."""
        self._add(StaticGroup(name, shapes, rgba))

    def add_visual(self, name: str, shape: Any, rgba: Vector, position: Vector = (0.0, 0.0, 0.0),
                   quaternion: Vector = (0.0, 0.0, 0.0, 1.0)) -> None:
        """A part that is only drawn."""
        self._add(VisualBody(name, shape, rgba, position, quaternion))

    def add_heightfield(self, name: str, heights: np.ndarray, cell: float, position: Vector,
                        rgba: Vector) -> None:
        """Ground named ``name`` on a grid of ``heights`` (m)."""
        self._add(Heightfield(name, heights, cell, position, rgba))

    def add_plane(self, name: str, rgba: Vector) -> None:
        """Flat ground named ``name``: the plane z = 0."""
        self._add(Plane(name, rgba))

    def remove(self, name: str) -> None:
        """Remove the body ``name`` (and the loops and stops that name it)."""
        if name not in self._recipe:
            raise ValueError(f"no body named {name!r}; bodies: {', '.join(self._recipe)}")
        del self._recipe[name]
        for table in (self._links, self._link_names, self._kinds, self._values, self._bases):
            table.pop(name, None)
        self.loops = {key: points for key, points in self.loops.items() if name not in (key[0], key[2])}
        self.stops = {key: stop for key, stop in self.stops.items() if key[0] != name}

    def rebuild(self) -> None:
        """Nothing to rebuild: data holds no engine's state."""

    def on_rebuild(self, setup: Callable[[], None]) -> None:
        """Run the scene's set-up (its loops, stops, physics) now: it is written down once."""
        setup()

    # --- the set-up's calls ---------------------------------------------------------------------------------
    def set_physics(self, gravity: float, time_step: float, solver_iterations: int, erp: float | None = None
                    ) -> None:
        self.physics = (gravity, time_step, solver_iterations, erp)

    def servos(self, motors: Sequence[tuple[str, Sequence[int]]], force: float, position_gain: float,
               velocity_gain: float) -> None:
        for name, joints in motors:
            for joint in joints:
                self.servo_settings[name, joint] = (force, position_gain, velocity_gain)

    def no_self_collision(self, *names: str) -> None:
        """The parts of one mechanism never collide with each other (every export writes them so)."""

    def passive(self, name: str, joints: Sequence[int], spherical: Sequence[int] = ()) -> None:
        """Joints without a motor: every joint is, unless a scene drives it."""

    def no_collision(self, name: str) -> None:
        """Kept by the scene's export as it is: nothing to write down here."""

    def ball_joint(self, name: str, link_a: int, pivot_a: Vector, link_b: int, pivot_b: Vector,
                   other: str | None = None) -> None:
        """A loop closure between a point of ``link_a`` of ``name`` and one of ``link_b`` of ``other`` (default:
        the same body; -1 a base), each in its link's centre-of-mass frame (m)."""
        other = other or name
        key = (name, self.link_name(name, link_a), other, self.link_name(other, link_b))
        self.loops[key] = (self._in_link_frame(name, link_a, pivot_a), self._in_link_frame(other, link_b, pivot_b))

    def joint_stops(self, name: str, joints: Sequence[int], lower: float, upper: float) -> None:
        for joint in joints:
            self.stops[name, self.link_name(name, joint)] = (float(lower), float(upper))

    def friction(self, name: str, links: Sequence[int], lateral: float) -> None:
        for link in links:
            self._friction[name, link] = float(lateral)

    def contact_friction(self, name: str, link: int) -> float:
        """The contact friction coefficient of ``link`` of body ``name`` as set (PyBullet's default where not)."""
        return self._friction.get((name, link), DEFAULT_FRICTION)

    # --- bookkeeping ---------------------------------------------------------------------------------------
    @property
    def recipes(self) -> dict[str, Recipe]:
        """How each body was built, in order: name -> its record (:mod:`paragym.sim.recipes`)."""
        return dict(self._recipe)

    @property
    def body_names(self) -> tuple[str, ...]:
        return tuple(self._recipe)

    # --- the pose ---------------------------------------------------------------------------------------
    def reset_joint(self, name: str, joint: int, value: float | Vector) -> None:
        """Put a joint at ``value`` (a number, or an xyzw quaternion for a spherical joint)."""
        if isinstance(value, int | float | np.floating):
            self._values[name][joint] = (float(value),)
        else:
            self._values[name][joint] = tuple(float(v) for v in value)

    def set_joints(self, name: str, joints: Sequence[int], values: Sequence[Vector]) -> None:
        for joint, value in zip(joints, values, strict=True):
            self._values[name][joint] = tuple(float(v) for v in value)

    def reset_base(self, name: str, position: Vector, quaternion: Vector) -> None:
        """Put the free base of body ``name`` at ``position`` (m), turned by the xyzw ``quaternion``."""
        self._bases[name] = (np.array(position, float), np.array(quaternion, float))

    def joint_values(self, name: str) -> list[tuple[float, ...]]:
        """Every joint of body ``name`` as posed, in depth-first order: ``(q,)``, an xyzw quaternion or ``()``."""
        return list(self._values[name])

    def link_frame(self, name: str, link: int) -> tuple[np.ndarray, np.ndarray]:
        """Where the free base of body ``name`` (``link`` -1: only a base's frame is data) was put: position (m)
        and xyzw quaternion."""
        if link != -1:
            raise ValueError(f"a description holds a free base's frame only (link -1); got link {link!r}")
        position, quaternion = self._bases[name]
        return position.copy(), quaternion.copy()

    def build_in(self, sim: Any) -> None:
        """Build these bodies in ``sim`` (a :class:`~paragym.sim.client.PyBulletSim`) and pose them: the
        scene's picture, without its physics' set-up."""
        for recipe in self._recipe.values():
            recipe.build_in(sim)
        self.pose(sim)

    def pose(self, sim: Any) -> None:
        """Pose the bodies of ``sim`` (built by :meth:`build_in`) as described."""
        for name, values in self._values.items():
            joints = [j for j, kind in enumerate(self._kinds[name]) if kind != "fixed"]
            if joints:
                sim.set_joints(name, joints, [list(values[j]) for j in joints])
        for name, (position, quaternion) in self._bases.items():
            sim.reset_base(name, position, quaternion)


#: a joint's value at zero, by its kind
_ZERO: dict[str, tuple[float, ...]] = {"revolute": (0.0,), "prismatic": (0.0,), "spherical": (0.0, 0.0, 0.0, 1.0),
                                       "fixed": ()}
