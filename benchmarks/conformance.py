"""Two engines on one mechanism: PyBullet's and MuJoCo's physics, held, pushed and driven by the paper's method.

Three tables from one run, each engine on the same mechanism, commands and seeds.
*Holding*: for each mechanism with loop closures (the newest ids' dynamic scenes, or ``--env``), after
``reset(seed)`` every joint sits where the task's kinematics has it; the motors then hold their targets for
``--seconds`` of simulated time under gravity, in PyBullet (the scene's own settings: its step, solver iterations
and motor gains) and in MuJoCo (the file ``paragym export`` writes; position servos at the same force limits),
the latter both with the exported loop settings and with MuJoCo's default ``solref``/``solimp`` (the sag that
mujoco #2698 reports). The table gives, per engine, the loop-closure residual over the run (mean and largest,
mm), how far any link ended from its kinematic pose (mm: the sag under gravity, the gap to the kinematic model),
the motors' holding forces at the end (the largest, the largest difference from PyBullet's, motor by motor, and
from the hand statics: virtual work on the mechanism's tree and loops, :mod:`paragym.sim.statics`, which neither
engine computes) and the physics steps per second of this machine
(each engine's step with the residual's measurement after it, in Python: a measure of the run here, not of
either engine's speed alone).

*Contact*: the CaPaMan's scene, the same code in both engines (``engine=``), drives its cranks into each box of
the contact contract (:data:`paragym.sim.capaman_dynamic.CONTACT_PUSHES`) at the motors' torque limit: where the
tool stops, how far from PyBullet's stop, and the loops' largest gap under the push.

*The reference*: the bench's reference of each id whose task runs MuJoCo plays ``--episodes`` dynamic episodes
(the paper's case, then random scenarios from reset seed 300001, the leaderboard's physics settings) in each
engine, judged as the leaderboard judges them (success, and the KF check of the executed against the commanded
motion), at the settings it runs there (step and iterations), with the mean episode length (env steps), the
loop residual over every step, the largest distance of the validated body from its command (mm), how far its
executed path runs from PyBullet's on the same seed (at equal times, and as curves: mm) and the env steps per
second.

    python benchmarks/conformance.py [--env ID ...] [--seconds 1.0] [--seed 0] [--episodes 10] [--record]
"""

from __future__ import annotations

import argparse
import re
import time
import warnings

import numpy as np
from convergence import curve_gap_mm, path_gap_mm, settings_label
from reference_dynamic import scenario_of
from results_file import add_record_option, engine_versions, paragraph, record

from paragym import registry
from paragym.baselines.stats import wilson
from paragym.envs import export as envs_export
from paragym.sim import export
from paragym.sim.client import motors_of
from paragym.sim.statics import holding_forces


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


def holding(env_ids: list[str], seconds: float, seed: int) -> list[list[str]]:
    """The holding table's rows (module docstring)."""
    rows = []
    for env_id in env_ids:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            env = envs_export.dynamic_env(env_id)
        try:
            env.reset(seed=seed)
            scene = envs_export.scene_of(env)
            if not scene.sim.loops or not hasattr(scene, "hold"):
                print(f"{env_id}: no loop closure to hold (its loops close through the ground)")
                continue
            text = export.mjcf(scene, env_id.split("/")[1])
            statics = holding_forces(scene)  # at the pose the kinematics gives, before either engine moves it
            runs = [("MuJoCo, exported loops", *mujoco_hold(scene, text, seconds)),
                    ("MuJoCo, default loops", *mujoco_hold(scene, with_default_loops(text), seconds)),
                    ("PyBullet (the env's)", *pybullet_hold(scene, seconds))]
        finally:
            env.close()
        held = runs[-1][-1]  # PyBullet's holding forces: the reference the MuJoCo rows are compared with
        for engine, residuals, drift, rate, forces in runs:
            gap = "-" if forces is held else f"{np.max(np.abs(forces - held)):.3g}"
            rows.append([env_id, engine, f"{residuals.mean() * 1e3:.3g}", f"{residuals.max() * 1e3:.3g}",
                         f"{drift * 1e3:.3g}", f"{np.max(np.abs(forces)):.3g}", gap,
                         f"{np.max(np.abs(forces - statics)):.3g}", f"{rate:,.0f}"])
            print(" | ".join(rows[-1]), flush=True)
    return rows


def contact() -> list[list[str]]:
    """The contact table's rows: the CaPaMan pushed into each box in each engine (module docstring)."""
    from paragym.mechanisms import capaman
    from paragym.sim.capaman_dynamic import CONTACT_PUSHES, CaPaManDynamicScene, push_into
    from paragym.sim.mujoco_sim import MuJoCoSettings

    rows = []
    for push in CONTACT_PUSHES:
        stops = {}
        for engine, settings in (("PyBullet", None), ("MuJoCo", MuJoCoSettings())):
            scene = CaPaManDynamicScene(capaman.DEFAULT_GEOMETRY, engine=settings)
            try:
                t0 = time.perf_counter()
                tips, gap = push_into(scene, push)
                wall = time.perf_counter() - t0
            finally:
                scene.close()
            stops[engine] = tips[-1]
            apart = "-" if engine == "PyBullet" else f"{np.linalg.norm(tips[-1] - stops['PyBullet']) * 1e3:.2f}"
            rows.append([f"CaPaMan, pushed {push}", engine, " ".join(f"{v * 1e3:.1f}" for v in tips[-1]), apart,
                         f"{gap * 1e3:.3g}", f"{2.0 / wall:.1f}"])
            print(" | ".join(rows[-1]), flush=True)
    return rows


def dynamic_settings(env_id: str, engine: str) -> str:
    """The physics step and iterations the leaderboard's dynamic episodes of ``env_id`` run at in ``engine``."""
    from paragym.baselines.tasks import dynamic_kwargs

    return settings_label(dynamic_kwargs(env_id, engine), engine)


def reference(env_ids: list[str], episodes: int) -> list[list[str]]:
    """The reference's table's rows: each id's reference in each engine (module docstring)."""
    import gymnasium as gym

    from paragym.baselines.policies import get_policy
    from paragym.baselines.tasks import bench_of, dynamic_kwargs
    from paragym.validation.episode import validate_episode

    def rate(k: int, n: int) -> str:
        low, high = wilson(k, n)
        return f"{k}/{n} [{low:.2f}, {high:.2f}]"

    rows = []
    for env_id in env_ids:
        engines = registry.row(env_id).engines
        if len(engines) < 2:
            continue
        spec = get_policy(env_id, bench_of(env_id).reference)
        paths: dict[str, list[dict[str, np.ndarray]]] = {}
        for engine in engines:
            won = passed = steps = 0
            residuals, errors, wall = [], [], 0.0
            paths[engine] = []
            for i in range(episodes):
                scenario, seed = scenario_of(i)
                arg = registry.row(env_id).paper_scenario if scenario == "paper" else scenario
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    env = gym.make(env_id, scenario=arg, **dynamic_kwargs(env_id, engine))
                try:
                    t0 = time.perf_counter()
                    val = validate_episode(env, spec.factory(env, seed), seed=seed, sensor_seed=seed)
                    wall += time.perf_counter() - t0
                finally:
                    env.close()
                won, passed, steps = won + val.success, passed + val.passed, steps + val.steps
                residuals += [info["loop_residual_m"] for info in val.episode.infos if "loop_residual_m" in info]
                errors.append(val.position_error)
                paths[engine].append({"t": val.executed.t, "path": val.executed.position})
            pairs = list(zip(paths[engine], paths[engines[0]], strict=True))
            apart = (f"{max(path_gap_mm(a, b) for a, b in pairs):.3g}",
                     f"{max(curve_gap_mm(a, b) for a, b in pairs):.3g}")
            rows.append([env_id, engine, spec.name, dynamic_settings(env_id, engine), rate(won, episodes),
                         rate(passed, episodes), f"{steps / episodes:.1f}",
                         f"{np.mean(residuals) * 1e3:.3g}" if residuals else "-",
                         f"{np.max(residuals) * 1e3:.3g}" if residuals else "-",
                         f"{np.max(errors) * 1e3:.3g}", *(("-", "-") if engine == engines[0] else apart),
                         f"{steps / wall:.0f}"])
            print(" | ".join(rows[-1]), flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", default=None, help="an env id (repeatable; default: newest)")
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated seconds of holding")
    parser.add_argument("--seed", type=int, default=0, help="the reset seed: the pose held")
    parser.add_argument("--episodes", type=int, default=10, help="the reference's dynamic episodes per engine")
    add_record_option(parser)
    args = parser.parse_args()
    if args.seconds <= 0:
        parser.error(f"--seconds must be positive, got {args.seconds}")
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    env_ids = args.env or list(registry.newest())
    held, pushed, played = holding(env_ids, args.seconds, args.seed), contact(), reference(env_ids, args.episodes)
    if not args.record:
        return
    intro = paragraph(__doc__)
    record("conformance", "Two engines on one mechanism: holding a pose under gravity",
           f"{intro} {paragraph(__doc__, 1)}",
           ["env", "engine", "loop residual, mean [mm]", "loop residual, max [mm]", "largest link drift [mm]",
            "largest holding force [N or N m]", "largest difference to PyBullet's [N or N m]",
            "largest difference to the hand statics [N or N m]", "physics steps/s"],
           held, order=62, folder=args.record, source=engine_versions())
    record("conformance_contact", "Two engines on one mechanism: contact stops", paragraph(__doc__, 2),
           ["push", "engine", "tool stopped at x y z [mm]", "from PyBullet's stop [mm]", "loop gap, max [mm]",
            "simulated seconds per second"], pushed, order=63, folder=args.record, source=engine_versions())
    record("conformance_reference", "Two engines on one mechanism: the paper's method", paragraph(__doc__, 3),
           ["env", "engine", "policy", "settings (the leaderboard's)", "success [95% CI]", "KF PASS [95% CI]",
            "env steps per episode", "loop residual, mean [mm]", "loop residual, max [mm]",
            "largest distance from the command [mm]", "path from PyBullet's at equal times [mm]",
            "path from PyBullet's as a curve [mm]", "env steps/s"], played,
           order=64, folder=args.record, source=engine_versions())


if __name__ == "__main__":
    main()
