"""Two engines on one mechanism: PyBullet's scene and its MJCF export in MuJoCo, holding a pose under gravity.

For each mechanism with loop closures (the newest ids' dynamic scenes, or ``--env``), after ``reset(seed)`` every
joint sits where the task's kinematics has it; the motors then hold their targets for ``--seconds`` of simulated
time under gravity, in PyBullet (the scene's own settings: its step, solver iterations and motor gains) and in
MuJoCo (the file ``paragym export`` writes, with the same step and iterations; position servos at the same force
limits), the latter both with the exported loop settings and with MuJoCo's default ``solref``/``solimp`` (the
sag that mujoco #2698 reports). The table gives, per engine, the loop-closure residual over the run (mean and
largest, mm), how far any link ended from its kinematic pose (mm: the sag under gravity, the gap to the
kinematic model), the motors' holding forces at the end (the largest, and the largest difference from
PyBullet's, motor by motor: the statics of one mechanism, which two engines must agree on) and the physics
steps per second of this machine (each engine's step with the residual's
measurement after it, in Python: a measure of the run here, not of either engine's speed alone).

    python benchmarks/conformance.py [--env ID ...] [--seconds 1.0] [--seed 0] [--record]
"""

from __future__ import annotations

import argparse
import re
import time
import warnings

import numpy as np
from results_file import add_record_option, paragraph, record

from paragym import registry
from paragym.sim import export
from paragym.sim.client import motors_of


def pybullet_hold(scene, seconds: float) -> tuple[np.ndarray, float, float, np.ndarray]:
    """Loop residuals (m) at every physics step, the largest link drift (m) at the end, steps per second, and
    each motor's force (N or N m) in the last step, in the order of ``scene.motor_limits()``."""
    body, links = export.tree_of(scene)
    start = export.tree_frames(links, scene.sim.joint_values(body))
    h = scene.sim.time_step
    steps = max(1, int(round(seconds / h)))
    residuals = []

    def record_gap() -> None:
        residuals.append(scene.sim.loop_residual())

    scene.sim.after_step.append(record_gap)
    t0 = time.perf_counter()
    scene.hold(steps * h)
    rate = steps / (time.perf_counter() - t0)
    scene.sim.after_step.remove(record_gap)
    drift = max(float(np.linalg.norm(scene.sim.link_frame(body, i)[0] - start[link.name][0]))
                for i, link in enumerate(links))
    forces = scene.sim.motor_forces(motors_of([(b, j) for b, j, _ in scene.motor_limits()]))
    return np.array(residuals), drift, rate, forces


def mujoco_hold(scene, text: str, seconds: float) -> tuple[np.ndarray, float, float, np.ndarray]:
    """:func:`pybullet_hold` for the exported MJCF ``text`` in MuJoCo, from the scene's joint values; the forces
    the mean over the last fifth of the hold (a servo's spring may ring about its holding force)."""
    import mujoco

    body, links = export.tree_of(scene)
    values = scene.sim.joint_values(body)
    start = export.tree_frames(links, values)
    model = mujoco.MjModel.from_xml_string(text)
    data = export.mujoco_pose(model, links, values, urdf=False)
    data.ctrl[:] = export.mujoco_motor_positions(model, data)
    steps = max(1, int(round(seconds / model.opt.timestep)))
    residuals, forces = np.zeros(steps), np.zeros((steps, model.nu))
    t0 = time.perf_counter()
    for i in range(steps):
        mujoco.mj_step(model, data)
        residuals[i] = export.mujoco_loop_gap(model, data)
        forces[i] = data.actuator_force
    rate = steps / (time.perf_counter() - t0)
    drift = max(float(np.linalg.norm(data.xpos[model.body(link.name).id] - start[link.name][0])) for link in links)
    return residuals, drift, rate, forces[-max(1, steps // 5):].mean(axis=0)


def with_default_loops(text: str) -> str:
    """The MJCF with its loops' solref/solimp removed: MuJoCo's defaults."""
    return re.sub(r' solref="[^"]*" solimp="[^"]*"', "", text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", default=None, help="an env id (repeatable; default: newest)")
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated seconds of holding")
    parser.add_argument("--seed", type=int, default=0, help="the reset seed: the pose held")
    add_record_option(parser)
    args = parser.parse_args()
    if args.seconds <= 0:
        parser.error(f"--seconds must be positive, got {args.seconds}")
    rows = []
    for env_id in args.env or list(registry.newest()):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            env = export.dynamic_env(env_id)
        try:
            env.reset(seed=args.seed)
            scene = export.scene_of(env)
            if not scene.sim.loops or not hasattr(scene, "hold"):
                print(f"{env_id}: no loop closure to hold (its loops close through the ground)")
                continue
            text = export.mjcf(scene, env_id.split("/")[1])
            runs = [("MuJoCo, exported loops", *mujoco_hold(scene, text, args.seconds)),
                    ("MuJoCo, default loops", *mujoco_hold(scene, with_default_loops(text), args.seconds)),
                    ("PyBullet (the env's)", *pybullet_hold(scene, args.seconds))]
        finally:
            env.close()
        held = runs[-1][-1]  # PyBullet's holding forces: the reference the MuJoCo rows are compared with
        for engine, residuals, drift, rate, forces in runs:
            gap = "-" if forces is held else f"{np.max(np.abs(forces - held)):.3g}"
            rows.append([env_id, engine, f"{residuals.mean() * 1e3:.3g}", f"{residuals.max() * 1e3:.3g}",
                         f"{drift * 1e3:.3g}", f"{np.max(np.abs(forces)):.3g}", gap, f"{rate:,.0f}"])
            print(" | ".join(rows[-1]), flush=True)
    columns = ["env", "engine", "loop residual, mean [mm]", "loop residual, max [mm]", "largest link drift [mm]",
               "largest holding force [N or N m]", "largest difference to PyBullet's [N or N m]", "physics steps/s"]
    if args.record:
        record("conformance", "Two engines on one mechanism: holding a pose under gravity", paragraph(__doc__),
               columns, rows, order=62, folder=args.record)


if __name__ == "__main__":
    main()
