"""Where the physics stops moving: each task's dynamic verdicts as the time step halves and the iterations double.

For each newest id (or ``--env``) and each engine its task runs (PyBullet; MuJoCo where the task and the ``mujoco``
extra allow), the bench's reference plays the same ``--episodes`` dynamic episodes (the paper's case, then random
scenarios from reset seed 300001, as ``benchmarks/reference_dynamic.py``) at five settings: the shipped one (the
leaderboard's: the bench's dynamics in PyBullet, :class:`~paragym.sim.mujoco_sim.MuJoCoSettings` in MuJoCo), half
its step, twice its solver iterations, both, and a quarter of the step with four times the iterations, which every
other row is measured against. It is one model integrated more finely: gains that are per physics step (PyBullet's
motor position gain, MuJoCo's servo bandwidth) scale with the step, so that the servos stay as fast. Per setting:
success and KF PASS (Wilson's 95 % intervals), the episodes whose verdict (success or KF) differs from the reference
row's, the mean episode length (env steps), the largest distance between the validated body's executed path and the
reference row's, at equal times and as curves (the Hausdorff distance: where a closed-loop policy arrives a step
sooner its path at equal times moves while the path itself does not; mm), the bench metric that moved most from the
reference row (largest absolute change over the episodes), the loops' largest residual (mm, where the mechanism has
loops), the KF's executed-to-commanded distance (median, mm) and the seconds per episode. The shipped row says
whether it is converged: no verdict changes at half its step or twice its iterations, and its path within 1 mm of
theirs as a curve.

    python benchmarks/convergence.py [--env ID ...] [--engine pybullet|mujoco ...] [--episodes 10] [--quick]
                                     [--record]
"""

from __future__ import annotations

import argparse
import time
from functools import cache
from typing import Any

import gymnasium as gym
import numpy as np
from reference_dynamic import rate, scenario_of
from results_file import add_record_option, engine_versions, paragraph, record

from paragym import registry
from paragym.baselines.leaderboard.evaluate import run_dynamic
from paragym.baselines.leaderboard.suite import dynamic_engines
from paragym.baselines.policies import get_policy
from paragym.baselines.tasks import bench_of, dynamic_kwargs
from paragym.sim.client import refined
from paragym.sim.export import SERVO_BANDWIDTH

#: the settings swept: (label, the step's factor, the iterations' factor); the last is the reference row
LADDER = (("shipped", 1.0, 1), ("half step", 0.5, 1), ("2x iterations", 1.0, 2),
          ("half step, 2x iterations", 0.5, 2), ("quarter step, 4x iterations", 0.25, 4))
#: a smoke run's settings (``--quick``): the shipped one, half its step and twice its iterations, the last the
#: reference row
QUICK = LADDER[:3]
#: how far (mm) the shipped row's path may be from its half-step and 2x-iteration rows' and be converged
PATH_TOLERANCE_MM = 1.0


def settings(env_id: str, engine: str, step: float, iterations: int) -> dict[str, Any]:
    """The env's arguments for the leaderboard's dynamic episodes in ``engine`` (:func:`dynamic_kwargs`), the
    same model integrated at ``step`` times the physics step with ``iterations`` times the solver's iterations
    (:func:`paragym.sim.client.refined`, :meth:`paragym.sim.mujoco_sim.MuJoCoSettings.refined`: the servos'
    per-step gains scaled with the step, so that they stay as fast)."""
    kwargs = dynamic_kwargs(env_id, engine)
    if engine == "pybullet":
        kwargs["dynamics"] = refined(kwargs["dynamics"], step, iterations)
    else:
        kwargs["engine"] = kwargs["engine"].refined(step, iterations, scene_bandwidth(env_id),
                                                    kwargs["dynamics"].solver_iterations)
    return kwargs


@cache
def scene_bandwidth(env_id: str) -> float:
    """The share per MuJoCo step at which ``env_id``'s scene has its servos exported (its
    ``EXPORT_SERVO_BANDWIDTH``, else the export's), read once from the scene the leaderboard's MuJoCo env builds."""
    env = gym.make(env_id, **dynamic_kwargs(env_id, "mujoco"))
    try:
        return getattr(env.unwrapped.world.scene, "EXPORT_SERVO_BANDWIDTH", SERVO_BANDWIDTH)
    finally:
        env.close()


def settings_label(kwargs: dict[str, Any], engine: str) -> str:
    """The step (ms) and iterations that ``kwargs`` run at (MuJoCo's: the scene's where its settings name none),
    and the per-step gains that set the servos' speed where ``kwargs`` name them."""
    if engine == "pybullet":
        d = kwargs["dynamics"]
        gains = ", ".join(f"{name} {getattr(d, name):g}" for name in getattr(d, "PER_STEP", ()))
        return f"{d.time_step * 1e3:g} ms, {d.solver_iterations} it" + (f", {gains}" if gains else "")
    s = kwargs["engine"]
    servos = "" if s.servo_bandwidth is None else f", servos {s.servo_bandwidth / s.time_step:g}/s"
    return f"{s.time_step * 1e3:g} ms, {s.iterations or kwargs['dynamics'].solver_iterations} it" + servos


def episode(env_id: str, kwargs: dict[str, Any], i: int) -> dict[str, Any]:
    """Episode ``i`` (:func:`scenario_of`) of the bench's reference at ``kwargs``: its verdicts and measures."""
    spec = get_policy(env_id, bench_of(env_id).reference)
    scenario, seed = scenario_of(i)
    t0 = time.perf_counter()
    val, failed = run_dynamic(spec, scenario, seed, kwargs)
    metrics = bench_of(env_id).metrics(val.episode)
    loops = [info["loop_residual_m"] for info in val.episode.infos if "loop_residual_m" in info]
    return {"success": bool(val.success), "kf": bool(val.passed), "failed": failed, "steps": val.steps,
            "kf_error_mm": val.position_error * 1e3, "loop_mm": max(loops) * 1e3 if loops else None,
            "metrics": metrics, "t": val.executed.t, "path": val.executed.position,
            "seconds": time.perf_counter() - t0}


def path_gap_mm(a: dict[str, Any], b: dict[str, Any]) -> float:
    """The largest distance (mm) between two episodes' executed paths at equal times (``b``'s path interpolated
    at ``a``'s sample times, over the time both cover)."""
    t = a["t"][a["t"] <= b["t"][-1]]
    other = np.stack([np.interp(t, b["t"], b["path"][:, k]) for k in range(3)], axis=1)
    return float(np.linalg.norm(a["path"][: len(t)] - other, axis=1).max()) * 1e3 if len(t) else float("nan")


def curve_gap_mm(a: dict[str, Any], b: dict[str, Any]) -> float:
    """The largest distance (mm) from a point of either episode's executed path to the other path (the
    symmetric Hausdorff distance of the two sampled paths): how far apart they run, whenever they get there."""
    from scipy.spatial.distance import directed_hausdorff

    return max(directed_hausdorff(a["path"], b["path"])[0], directed_hausdorff(b["path"], a["path"])[0]) * 1e3


def compare(runs: list[dict[str, Any]], against: list[dict[str, Any]]) -> dict[str, Any]:
    """One setting's episodes ``runs`` against the same episodes ``against``: verdict changes, the largest path
    gaps (mm; at equal times, and as curves) and the bench metric that moved most (its name and the largest
    absolute change)."""
    pairs = list(zip(runs, against, strict=True))
    flips = sum((r["success"], r["kf"]) != (a["success"], a["kf"]) for r, a in pairs)
    gap = max(path_gap_mm(r, a) for r, a in pairs)
    curve = max(curve_gap_mm(r, a) for r, a in pairs)
    moved = {key: max(abs(r["metrics"][key] - a["metrics"][key]) for r, a in zip(runs, against, strict=True))
             for key in runs[0]["metrics"]}
    name = max(moved, key=lambda k: moved[k])
    return {"flips": flips, "gap_mm": gap, "curve_mm": curve, "metric": (name, moved[name])}


def study(env_id: str, engine: str, episodes: int, ladder: tuple = LADDER) -> list[list[str]]:
    """The table's rows for ``env_id`` in ``engine``: one per setting of ``ladder`` (its last the reference)."""
    runs = {}
    for label, step, iterations in ladder:
        kwargs = settings(env_id, engine, step, iterations)
        runs[label] = (settings_label(kwargs, engine), [episode(env_id, kwargs, i) for i in range(episodes)])
    reference = runs[ladder[-1][0]][1]
    shipped = runs[ladder[0][0]][1]
    finer = [runs[label][1] for label, step, iterations in ladder[1:3]]
    checks = [compare(shipped, other) for other in finer]
    converged = ("yes" if all(c["flips"] == 0 and c["curve_mm"] <= PATH_TOLERANCE_MM for c in checks) else
                 "no: " + "; ".join(f"{c['flips']} verdicts change, path {c['curve_mm']:.2f} mm apart at {label}"
                                    for c, (label, _, _) in zip(checks, ladder[1:3], strict=True)))
    rows = []
    n = episodes
    for label, _, _ in ladder:
        at, eps = runs[label]
        c = compare(eps, reference)
        loops = [e["loop_mm"] for e in eps if e["loop_mm"] is not None]
        rows.append([env_id, engine, f"{label} ({at})", rate(sum(e["success"] for e in eps), n),
                     rate(sum(e["kf"] for e in eps), n), str(c["flips"]), f"{np.mean([e['steps'] for e in eps]):.1f}",
                     f"{c['gap_mm']:.3f}", f"{c['curve_mm']:.3f}",
                     f"{c['metric'][0]} {c['metric'][1]:.3g}", f"{max(loops):.4f}" if loops else "-",
                     f"{np.median([e['kf_error_mm'] for e in eps]):.3f}",
                     f"{np.mean([e['seconds'] for e in eps]):.1f}",
                     converged if label == ladder[0][0] else ""])
        print(" | ".join(rows[-1]), flush=True)
    return rows


COLUMNS = ["env", "engine", "setting", "success", "KF PASS", "verdicts unlike the reference row", "env steps",
           "path from the reference row's at equal times (mm)", "path from the reference row's (mm)",
           "metric moved most", "loop residual (mm)", "KF distance (mm)",
           "s/episode", "converged"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", default=None, help="an env id (repeatable; default: newest ids)")
    parser.add_argument("--engine", action="append", default=None, choices=("pybullet", "mujoco"),
                        help="an engine (repeatable; default: every engine each task runs here)")
    parser.add_argument("--episodes", type=int, default=10, help="episodes per setting, the paper's first")
    parser.add_argument("--quick", action="store_true",
                        help="a smoke run: the shipped setting, half its step and twice its iterations only")
    add_record_option(parser)
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    rows = []
    for env_id in args.env or list(registry.newest()):
        for engine in dynamic_engines(env_id):
            if args.engine is None or engine in args.engine:
                rows += study(env_id, engine, args.episodes, QUICK if args.quick else LADDER)
    if args.record:
        smoke = " (a smoke run: --quick)" if args.quick else ""
        record("convergence", "Converged physics: the verdicts as the step halves and the iterations double" + smoke,
               paragraph(__doc__), COLUMNS, rows, order=40, folder=args.record, source=engine_versions())


if __name__ == "__main__":
    main()
