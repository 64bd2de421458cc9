"""The motors' holding forces of a closed-chain mechanism by hand: virtual work on its tree and its loops.

Neither engine is asked. The mechanism is the dynamic scene's open tree (:func:`paragym.sim.export.tree_of`, the
links with their masses at their parts' centres) with its loop closures (the scene's ``loops``: two points that
must meet). At a pose q of the tree (generalised coordinates: one per hinge or slide, three per ball joint, a
small rotation of its frame) it is held still under gravity when the generalised forces balance:

    S tau + Jc(q)^T lambda = grad V(q),

V the potential energy (sum of m g z over the parts), Jc the Jacobian of the loops' gaps (three rows per loop),
lambda the loops' forces and S the columns of the motors' joints. The system is solved in the least-squares
sense (a parallelogram's loop repeats what its twin already constrains); tau, in N or N m along each motor's
axis, is what the motors must apply. Derivatives are central differences of the exact (double precision) tree
kinematics, :func:`paragym.sim.export.tree_frames`. ``benchmarks/conformance.py`` sets both engines' holding
forces against it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from paragym.sim import export

__all__ = ["holding_forces"]

#: the step (rad or m) of the central differences
STEP = 1e-6


def holding_forces(scene: Any, gravity: float | None = None) -> np.ndarray:
    """The force (N) or torque (N m) each motor of ``scene`` (a dynamic scene of one fixed-base tree body, at
    its pose now) must apply to hold the mechanism still under ``gravity`` (m/s^2; default: the scene's), in
    the order of ``scene.motor_limits()`` (module docstring)."""
    body, links = export.tree_of(scene)
    values = [tuple(v) for v in scene.sim.joint_values(body)]
    coords = [(i, k) for i, link in enumerate(links) for k in range({"spherical": 3, "fixed": 0}.get(link.joint, 1))]
    loops = [((link_a, np.asarray(pa, float)), (link_b, np.asarray(pb, float)))
             for (_, link_a, _, link_b), (pa, pb) in scene.sim.loops.items()]
    gravity = scene.dynamics.gravity if gravity is None else gravity

    def moved(coord: tuple[int, int], delta: float) -> list[tuple[float, ...]]:
        i, k = coord
        out = list(values)
        if links[i].joint == "spherical":
            turn = np.zeros(3)
            turn[k] = delta
            out[i] = tuple((Rotation.from_quat(values[i]) * Rotation.from_rotvec(turn)).as_quat())
        else:
            out[i] = (values[i][0] + delta,)
        return out

    def measures(vals: list[tuple[float, ...]]) -> tuple[float, np.ndarray]:
        frames = export.tree_frames(links, vals)
        energy = sum(link.mass * gravity * (frames[link.name][0] + frames[link.name][1]
                                            @ np.asarray(link.shape_offset, float))[2] for link in links)
        gaps = [_point(frames, a) - _point(frames, b) for a, b in loops]
        return energy, np.concatenate(gaps) if gaps else np.zeros(0)

    grad, jac = np.empty(len(coords)), np.empty((3 * len(loops), len(coords)))
    for c, coord in enumerate(coords):
        (up, gap_up), (down, gap_down) = measures(moved(coord, STEP)), measures(moved(coord, -STEP))
        grad[c] = (up - down) / (2 * STEP)
        jac[:, c] = (gap_up - gap_down) / (2 * STEP)
    index = {link.name: i for i, link in enumerate(links)}
    motors = [coords.index((index[scene.sim.link_name(b, joint)], 0)) for b, joint, _ in scene.motor_limits()]
    select = np.zeros((len(coords), len(motors)))
    select[motors, range(len(motors))] = 1.0
    solution = np.linalg.lstsq(np.hstack([select, jac.T]), grad, rcond=None)[0]
    return solution[:len(motors)]


def _point(frames: dict[str, tuple[np.ndarray, np.ndarray]], end: tuple[str | None, np.ndarray]) -> np.ndarray:
    """A loop's point in the world: on its link (in the link's frame), or fixed in the world (a base)."""
    link, point = end
    if link is None:
        return point
    pos, rot = frames[link]
    return pos + rot @ point
