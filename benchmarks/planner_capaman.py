"""RRT + GA (paper 000) against OMPL on CaPaMan scenarios, side by side.

On the paper scenario and on ``--scenarios`` seeded random ones, every planner
gets the same validity checker (:class:`paragym.planners.rrt_ga.JointSpaceModel`:
Theta, eq 2 near the task points, segments sampled every degree) and the same
via points (T.P.1 -> T.P.2 -> T.P.3 -> T.P.1, one query per leg):

* RRT + GA: :class:`paragym.planners.RrtGaPlanner`;
* OMPL RRTConnect, then OMPL's path simplification;
* OMPL RRT* with the path-length objective, given the time RRT + GA spent
  searching on the same scenario (RRT, GA and final check; the model is built
  once for all and not counted for anyone), split equally over the legs but
  never less than 0.1 s a leg (so at least an equal budget), then simplified.

Each result is scored the same way: success, planning time, joint-space path
length, minimum PyBullet clearance along it (every 0.25 deg), and the fitness
J of eq 3 (see ``score``). Needs ``pip install ompl`` (the ``ompl`` extra) for the
OMPL rows; without it RRT + GA is reported alone.

    python benchmarks/planner_capaman.py [--scenarios 50] [--paper-runs 10]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from results_file import add_record_option, record  # this folder is on the path when it runs
from tqdm import tqdm

from paragym.planners import PlanningError, RrtGaPlanner
from paragym.planners.rrt_ga import LEG_INTERVALS, JointSpaceModel
from paragym.sim.capaman_scene import CaPaManScene
from paragym.tasks.capaman import paper_scenario, random_scenario
from paragym.trajectories import JointPath
from paragym.units import DEG

#: the speed page's paragraph above this script's table (``--record``)
PARAGRAPH = (
    "The reference planner (paper 000's RRT + GA) and OMPL's RRTConnect and RRT* (each with "
    "simplification) on the paper scenario and 50 seeded random ones, all with the same validity model "
    "and via points. "
)

MIN_LEG_BUDGET = 0.1  # s: RRT* gets at least this per leg, even when RRT + GA needed less
LEGS = ((0, 1), (1, 2), (2, 0))


def to_21(legs: list[np.ndarray]) -> np.ndarray:
    """Three leg polylines -> the paper's 21 configurations (corners kept when they fit)."""
    parts = [RrtGaPlanner._resample(leg, n)[:-1] for leg, n in zip(legs, LEG_INTERVALS, strict=True)]
    return np.vstack(parts + [legs[-1][-1:]])


def score(model: JointSpaceModel, legs: list[np.ndarray]) -> tuple[float, float, np.ndarray]:
    """(J, length, path) of a tour given as three leg polylines, for any planner.

    J follows eq 3: Lambda from the model's segment checks on the path as
    planned, its joint-space length, and beta times the number of its 21 via
    configurations closer than delta to a collision (the configurations
    themselves for RRT + GA; for OMPL's paths, 21 configurations spread along
    the path, corners kept when they fit).
    """
    raw = np.vstack([legs[0]] + [leg[1:] for leg in legs[1:]])
    length = float(np.linalg.norm(np.diff(raw, axis=0), axis=1).sum())
    free = bool(model.free(raw[:-1], raw[1:]).all())
    close = int((model.rho(to_21(legs)) < model.settings.delta).sum())
    return (0.0 if free else np.inf) + length + model.settings.beta * close, length, raw


def clearance(scene: CaPaManScene, waypoints: np.ndarray) -> float:
    """Smallest PyBullet distance along the polyline (m)."""
    best = np.inf
    for q in JointPath(waypoints, (0,)).densify(0.25 * DEG):
        scene.set_configuration(q)
        best = min(best, scene.clearance()[0])
    return float(best)


class Ompl:
    """OMPL planners on the CaPaMan joint space with a paragym validity model."""

    def __init__(self) -> None:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou

        ou.setLogLevel(ou.LOG_NONE)
        self.ob, self.og = ob, og

    def solve(self, model: JointSpaceModel, start: np.ndarray, goal: np.ndarray, planner: str,
              budget: float) -> np.ndarray | None:
        ob, og = self.ob, self.og
        g = model.geometry
        space = ob.RealVectorStateSpace(3)
        bounds = ob.RealVectorBounds(3)
        bounds.setLow(g.alpha_min)
        bounds.setHigh(g.alpha_max)
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)
        si.setStateValidityChecker(lambda s: model.config_free(s[0], s[1], s[2]))
        # motion checks at least as dense as the model's own (every check_step per joint):
        # OMPL spaces its checks by Euclidean distance, given as a fraction of the space's extent
        si.setStateValidityCheckingResolution(0.5 * model.step / space.getMaximumExtent())
        si.setup()
        a, b = si.allocState(), si.allocState()
        for i in range(3):
            a[i], b[i] = float(start[i]), float(goal[i])
        ss = og.SimpleSetup(si)
        ss.setStartAndGoalStates(a, b)
        if planner == "RRTConnect":
            ss.setPlanner(og.RRTConnect(si))
        else:
            ss.setOptimizationObjective(ob.PathLengthOptimizationObjective(si))
            ss.setPlanner(og.RRTstar(si))
        t_end = time.perf_counter() + budget
        solved = ss.solve(ob.PlannerTerminationCondition(lambda: time.perf_counter() > t_end)
                          if planner != "RRTConnect" else budget)
        if not ss.haveExactSolutionPath():
            del solved
            return None
        ss.simplifySolution()
        path = ss.getSolutionPath()
        return np.array([[path.getState(i)[j] for j in range(3)] for i in range(path.getStateCount())])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", type=int, default=50, help="random scenarios (seeds 0..N-1)")
    parser.add_argument("--paper-runs", type=int, default=10, help="planner seeds on the paper scenario")
    parser.add_argument("--verbose", action="store_true", help="also print every scenario's row")
    add_record_option(parser)
    args = parser.parse_args()
    try:
        ompl = Ompl()
    except ImportError:
        ompl = None
        print("OMPL is not installed (pip install ompl, or the 'ompl' extra): reporting RRT + GA alone.")

    scene = CaPaManScene()
    planner = RrtGaPlanner()
    planner.solve(paper_scenario())  # warm the joint-grid caches once, for everyone

    paper_times = []
    for seed in range(args.paper_runs):
        paper_times.append(planner.solve(paper_scenario(), seed=seed).timings["total"])
    print(f"\nRRT + GA on the paper scenario, {args.paper_runs} seeds: median {statistics.median(paper_times):.2f} s,"
          f" max {max(paper_times):.2f} s (paper: 12 s on a 2.93 GHz Core i3; target: median <= 1 s)")

    names = ["RRT+GA"] + (["OMPL RRTConnect+simplify", "OMPL RRT*+simplify"] if ompl else [])
    rows: dict[str, list[dict]] = {n: [] for n in names}
    scenarios = [("paper", paper_scenario())] + [
        (f"random {s}", random_scenario(np.random.default_rng(s), scene)) for s in range(args.scenarios)]
    for label, scenario in tqdm(scenarios, desc="scenarios"):
        tp = scenario.alpha
        scene.set_obstacles(scenario.obstacles)
        model = planner.model(scenario)
        try:
            result = planner.solve(scenario)
            search = result.timings["total"] - result.timings["theta"]
            w, via = result.path.waypoints, result.path.via_indices
            j, length, _ = score(model, [w[via[k]:via[k + 1] + 1] for k in range(3)])
            rows["RRT+GA"].append({"label": label, "ok": True, "time": result.timings["total"],
                                   "length": length, "clearance": result.min_clearance, "J": j})
        except PlanningError:
            search = planner.settings.time_budget
            rows["RRT+GA"].append({"label": label, "ok": False})
        if not ompl:
            continue
        for name, which, budget in (("OMPL RRTConnect+simplify", "RRTConnect", planner.settings.time_budget / 3),
                                    ("OMPL RRT*+simplify", "RRTstar", max(search / 3, MIN_LEG_BUDGET))):
            t0 = time.perf_counter()
            legs = [ompl.solve(model, tp[i], tp[j], which, budget) for i, j in LEGS]
            elapsed = time.perf_counter() - t0 + model.build_seconds
            if any(leg is None for leg in legs):
                rows[name].append({"label": label, "ok": False})
                continue
            j, length, raw = score(model, legs)
            rows[name].append({"label": label, "ok": True, "time": elapsed, "length": length,
                               "clearance": clearance(scene, raw), "J": j})

    if args.verbose:
        for k, (label, _) in enumerate(scenarios):
            print(label, "  ".join(f"{n}: " + (f"J {rows[n][k]['J']:.3f} len {rows[n][k]['length']:.3f} "
                                               f"t {rows[n][k]['time']:.2f}" if rows[n][k]["ok"] else "failed")
                                   for n in names))
    print(f"\n{len(scenarios)} scenarios (paper + {args.scenarios} random), the same validity model for all")
    print(f"{'planner':26s} {'success':>8s} {'t median':>9s} {'t p90':>7s} {'length':>7s} "
          f"{'min clear':>10s} {'J mean':>7s}")
    table = []
    for name in names:
        ok = [r for r in rows[name] if r["ok"]]
        times = [r["time"] for r in ok]
        finite = [r["J"] for r in ok if np.isfinite(r["J"])]
        inf = len(ok) - len(finite)
        table.append([name, f"{len(ok) / len(rows[name]):.0%}", f"{np.median(times):.2f} s",
                      f"{np.percentile(times, 90):.2f} s", f"{np.mean([r['length'] for r in ok]):.3f}",
                      f"{min(r['clearance'] for r in ok) * 1000:.1f} mm",
                      f"{np.mean(finite):.3f}" + (f" ({inf} with J = inf left out)" if inf else "")])
        print(f"{name:26s} {len(ok) / len(rows[name]):8.0%} {np.median(times):8.2f}s {np.percentile(times, 90):6.2f}s "
              f"{np.mean([r['length'] for r in ok]):7.3f} {min(r['clearance'] for r in ok) * 1000:8.1f}mm "
              f"{np.mean(finite):7.3f}" + (f"  ({inf} with J = inf left out)" if inf else ""))
    if ompl:
        ga = {r["label"]: r for r in rows["RRT+GA"] if r["ok"]}
        star = {r["label"]: r for r in rows["OMPL RRT*+simplify"]}
        rand = [label for label, _ in scenarios if label.startswith("random")]
        both = [k for k in rand if k in ga and star[k]["ok"] and np.isfinite(star[k]["J"])]
        wins = sum(1 for k in both if ga[k]["J"] <= star[k]["J"] + 1e-9)
        other = sum(1 for k in rand if k in ga and k not in both)
        print(f"\nRRT+GA's J no worse than OMPL RRT*'s (at least the same search time) on {wins + other}/{len(rand)} "
              f"random scenarios ({(wins + other) / max(1, len(rand)):.0%}; target >= 80%): {wins}/{len(both)} "
              f"where RRT* returned a valid path, and {other} where it returned none (or J = inf)")
        print("J = inf marks a path that fails the shared model's segment check (1 deg per joint); OMPL checks "
              "motions at its own resolution (half that, Euclidean)")
    scene.close()
    planner.close()
    if args.record:
        record("planner_capaman", "Planning: RRT + GA against OMPL", PARAGRAPH,
               ["planner", "success", "time median", "time p90", "joint path (rad)", "min clearance", "mean J"],
               table, order=80, folder=args.record)


if __name__ == "__main__":
    main()
