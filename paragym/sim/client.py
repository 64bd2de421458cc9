"""A PyBullet client with bodies addressed by name.

Tasks never see PyBullet's integer ids. One :class:`PyBulletSim` per
environment: ``DIRECT`` (headless) by default, ``GUI`` on request; ``close()``
disconnects it. Rendering to an array uses the TinyRenderer, so it works
without a display.

Kinematic bodies made of several rigid parts (a parallel manipulator whose
link poses come from an analytic model) are built as *one* multibody whose
parts float on dummy joints (three prismatic, then one spherical, per part):
one ``resetJointStatesMultiDof`` call places all parts and one
``getClosestPoints`` call per obstacle answers clearance for the whole
manipulator. That is about four times faster than a body per part.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pybullet as pb

from paragym.mechanisms.capaman import PartShape
from paragym.sim.obstacles import Cylinder, Obstacle

__all__ = ["PyBulletSim"]

_IDENTITY = (0.0, 0.0, 0.0, 1.0)
_LINKS_PER_PART = 4  # prismatic x, y, z, then spherical (carries the shape)


class PyBulletSim:
    """One PyBullet connection; bodies by name.

    Args:
        gui: open the PyBullet GUI (``render_mode="human"``) instead of DIRECT.
    """

    def __init__(self, gui: bool = False) -> None:
        self._client = pb.connect(pb.GUI if gui else pb.DIRECT)
        if self._client < 0:
            raise RuntimeError("could not connect to PyBullet" + (" (GUI needs a display)" if gui else ""))
        self.gui = gui
        self._bodies: dict[str, int] = {}
        self._parts: dict[str, tuple[str, ...]] = {}
        self._joint_indices: dict[str, list[int]] = {}
        if gui:
            pb.configureDebugVisualizer(pb.COV_ENABLE_GUI, 0, physicsClientId=self._client)

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
    def _shape(self, shape: PartShape | Obstacle, rgba: Sequence[float]) -> tuple[int, int]:
        c = self._client
        if isinstance(shape, Cylinder) or (isinstance(shape, PartShape) and shape.kind == "cylinder"):
            radius = shape.radius
            length = shape.height if isinstance(shape, Cylinder) else shape.length
            col = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=radius, height=length, physicsClientId=c)
            vis = pb.createVisualShape(pb.GEOM_CYLINDER, radius=radius, length=length, rgbaColor=rgba,
                                       physicsClientId=c)
        else:
            half = list(shape.half_extents)
            col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=c)
            vis = pb.createVisualShape(pb.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=c)
        return col, vis

    def add_static(self, name: str, shape: Obstacle, rgba: Sequence[float] = (0.7, 0.3, 0.3, 1.0)) -> None:
        """Add a fixed body (an obstacle or a base plate) named ``name``."""
        self._check_new(name)
        col, vis = self._shape(shape, rgba)
        self._bodies[name] = pb.createMultiBody(0.0, col, vis, basePosition=list(shape.center),
                                                physicsClientId=self._client)

    def add_parts_body(self, name: str, parts: Sequence[PartShape],
                       colors: Sequence[Sequence[float]]) -> None:
        """Add a kinematic body made of rigid ``parts`` whose poses are set by
        :meth:`set_part_poses` (see the module docstring)."""
        self._check_new(name)
        masses, cols, vis, parents, types, axes = [], [], [], [], [], []
        for p, (part, rgba) in enumerate(zip(parts, colors, strict=False)):
            first = _LINKS_PER_PART * p
            for j, axis in enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1))):
                masses.append(1e-3)
                cols.append(-1)
                vis.append(-1)
                parents.append(0 if j == 0 else first + j)  # parent of link i is i-1 (1-based)
                types.append(pb.JOINT_PRISMATIC)
                axes.append(axis)
            col, v = self._shape(part, rgba)
            masses.append(1e-3)
            cols.append(col)
            vis.append(v)
            parents.append(first + 3)
            types.append(pb.JOINT_SPHERICAL)
            axes.append((0, 0, 1))
        n = len(masses)
        body = pb.createMultiBody(
            0.0, -1, -1, linkMasses=masses, linkCollisionShapeIndices=cols, linkVisualShapeIndices=vis,
            linkPositions=[(0, 0, 0)] * n, linkOrientations=[_IDENTITY] * n,
            linkInertialFramePositions=[(0, 0, 0)] * n, linkInertialFrameOrientations=[_IDENTITY] * n,
            linkParentIndices=parents, linkJointTypes=types, linkJointAxis=axes,
            physicsClientId=self._client)
        self._bodies[name] = body
        self._parts[name] = tuple(p.name for p in parts)
        self._joint_indices[name] = list(range(n))

    def remove(self, name: str) -> None:
        """Remove the body ``name``."""
        pb.removeBody(self._bodies.pop(name), physicsClientId=self._client)

    def _check_new(self, name: str) -> None:
        if name in self._bodies:
            raise ValueError(f"a body named {name!r} exists already")

    @property
    def body_names(self) -> tuple[str, ...]:
        """Names of the bodies in the scene."""
        return tuple(self._bodies)

    # --- state and queries --------------------------------------------------------------
    def set_part_poses(self, name: str, centres: Sequence[Sequence[float]],
                       quaternions: Sequence[Sequence[float]]) -> None:
        """Place every part of body ``name``: centres (P, 3) m, quaternions (P, 4) xyzw."""
        targets: list[Sequence[float]] = []
        for (x, y, z), q in zip(centres, quaternions, strict=False):
            targets += [(x,), (y,), (z,), q]
        pb.resetJointStatesMultiDof(self._bodies[name], self._joint_indices[name], targets,
                                    physicsClientId=self._client)

    def clearance(self, name: str, others: Sequence[str], max_distance: float) -> tuple[float, str | None]:
        """Smallest signed distance (m; negative when penetrating) between body
        ``name`` and the bodies ``others``, capped at ``max_distance``; and the
        part of ``name`` where it occurs (None when nothing is within the cap)."""
        best, where = max_distance, -1
        body = self._bodies[name]
        for other in others:
            for pt in pb.getClosestPoints(body, self._bodies[other], max_distance, physicsClientId=self._client):
                if pt[8] < best:
                    best, where = pt[8], pt[3]
        if where < 0:
            return max_distance, None
        parts = self._parts.get(name)
        return best, (parts[where // _LINKS_PER_PART] if parts else name)

    def render(self, width: int, height: int, target: Sequence[float], distance: float,
               yaw: float, pitch: float, fov: float = 45.0) -> np.ndarray:
        """An RGB image (height, width, 3) uint8 from an orbit camera (degrees),
        drawn by the TinyRenderer (no display needed)."""
        c = self._client
        view = pb.computeViewMatrixFromYawPitchRoll(list(target), distance, yaw, pitch, 0.0, 2,
                                                    physicsClientId=c)
        proj = pb.computeProjectionMatrixFOV(fov, width / height, 0.01, 10.0, physicsClientId=c)
        _, _, rgba, _, _ = pb.getCameraImage(width, height, view, proj, renderer=pb.ER_TINY_RENDERER,
                                             physicsClientId=c)
        return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3].copy()
