"""Where the dynamic fidelity's time goes, and the most PyBullet's physics alone would allow.

For every dynamic env and physics preset, one core, random actions (resets
included), PandaReach-v3 measured in the same run as the anchor:

* the env's steps/s, and the share of its time inside ``stepSimulation``;
* the physics steps per env step (the control period over the time step);
* the cost of one physics step at the preset's settings, and with the
  constraint solver cut to one iteration (the same preset otherwise);
* the ceilings: the env steps/s that the physics alone would allow, with
  every line of Python free, at the preset's settings and at one solver
  iteration, as ratios to the anchor. Where the first is under the goal of
  2x PandaReach-v3, only fewer iterations (or a longer step) could reach
  it; where the second is near or under it, not even those.

Each row alternates the anchor, the env at its preset and the env at one
iteration in three rounds and gives the medians: the machine's load moved
the anchor alone between 406 and 708 steps/s from one run to the next.

    python benchmarks/dynamic_floor.py [--seconds 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
import warnings

import gymnasium as gym
import numpy as np
import pybullet as pb
from env_speed import run_for  # the measuring loop of benchmarks/env_speed.py (this script's folder is on the path)

import paragym  # noqa: F401
from paragym.sim import capaman_dynamic, hybrid_dynamic, orthoglide_dynamic, tripod_dynamic

GOAL = 2.0  # x PandaReach-v3
ROUNDS = 3
#: (env id, scenario, preset label, the dynamics)
ROWS = (
    ("paragym/CaPaManCollisionFree-v1", "random", "fast", capaman_dynamic.CaPaManDynamics.fast()),
    ("paragym/CaPaManCollisionFree-v1", "random", "split", capaman_dynamic.CaPaManDynamics.split()),
    ("paragym/HybridSingularityFree-v1", "random", "default", hybrid_dynamic.HybridDynamics.fast()),
    ("paragym/HybridSingularityFree-v1", "random", "split", hybrid_dynamic.HybridDynamics.split()),
    ("paragym/Orthoglide2PRRKappa-v0", "random", "default", orthoglide_dynamic.OrthoglideDynamics()),
    ("paragym/MobileTripodOdometry-v1", "push", "default", tripod_dynamic.TripodDynamics()),
)


class _PhysicsClock:
    """Counts PyBullet's ``stepSimulation`` calls and their time (it wraps the module's function)."""

    def __init__(self) -> None:
        self.calls, self.seconds = 0, 0.0
        self._step = pb.stepSimulation

    def __enter__(self) -> _PhysicsClock:
        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            out = self._step(*args, **kwargs)
            self.seconds += time.perf_counter() - t0
            self.calls += 1
            return out

        pb.stepSimulation = timed
        return self

    def __exit__(self, *exc) -> None:
        pb.stepSimulation = self._step


def _run(env_id: str, seconds: float, **kwargs) -> tuple[float, float, float]:
    """Env steps/s, physics steps per env step, and physics seconds per physics step."""
    env = gym.make(env_id, **kwargs)
    with _PhysicsClock() as clock:
        steps, elapsed = run_for(env, seconds)
    env.close()
    return steps / elapsed, clock.calls / steps, clock.seconds / max(clock.calls, 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="duration of each measurement")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    try:
        import panda_gym  # noqa: F401

        anchored = True
    except ImportError:
        anchored = False
        print("panda-gym is not installed: no anchor, no ratios (pip install panda-gym to add them)")
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    print(f"goal: {GOAL:.0f}x PandaReach-v3, measured beside each row ({ROUNDS} rounds of the anchor, the env at "
          "its preset and at one iteration; medians)\n")
    head = (f"{'environment':34s} {'preset':8s} {'anchor':>7s} {'steps/s':>8s} {'x':>5s} {'physics':>8s} "
            f"{'steps':>6s} {'us/step':>8s} {'us@1it':>7s} {'ceil x':>7s} {'@1it x':>7s}")
    print(head)
    share = args.seconds / ROUNDS
    for env_id, scenario, label, dynamics in ROWS:
        kwargs = {"scenario": scenario, "fidelity": "dynamic", "dynamics": dynamics}
        one = {**kwargs, "dynamics": dataclasses.replace(dynamics, solver_iterations=1)}
        rounds = []
        for _ in range(ROUNDS):  # alternating, so that the machine's load moves the anchor and the env alike
            anchor = _run("PandaReach-v3", share)[0] if anchored else float("nan")
            sps, n, per_step = _run(env_id, share, **kwargs)
            _, n_one, per_step_one = _run(env_id, share, **one)
            rounds.append((anchor, sps, sps / anchor, n * per_step * sps, n, per_step, per_step_one,
                           1.0 / (n * per_step) / anchor, 1.0 / (n * per_step_one) / anchor))
        a, sps, ratio, physics, n, per_step, per_step_one, at_preset, at_one = np.median(rounds, axis=0)
        shown = lambda value, width, spec: f"{value:{width}{spec}}" if anchored else f"{'-':>{width}}"  # noqa: E731
        print(f"{env_id.split('/')[1]:34s} {label:8s} {shown(a, 7, '.0f')} {sps:8.0f} {shown(ratio, 5, '.1f')} "
              f"{physics:8.0%} {n:6.1f} {per_step * 1e6:8.0f} {per_step_one * 1e6:7.0f} {shown(at_preset, 7, '.1f')} "
              f"{shown(at_one, 7, '.1f')}")
    print("\nanchor: PandaReach-v3's steps/s beside the row; x: the env's ratio to it; physics: the share of the "
          "env's time in stepSimulation; steps: physics steps per env step; us/step: one physics step at the preset, "
          "us@1it: at one solver iteration; ceil x: the env steps/s the physics alone allows at the preset, as a "
          "ratio to the anchor; @1it x: the same at one solver iteration")


if __name__ == "__main__":
    main()
