"""Steps per second of every registered paragym env, kinematic and dynamic fidelity, no render.

Measured as Gymnasium's ``benchmark_step`` does (uniformly random actions,
resets included whenever an episode ends, through ``gym.make``'s wrappers),
pinned to one core, except that the actions are drawn before the clock
starts: ``Box.sample`` alone costs about 35 us here, more than a fast env's
step, and it is the same for every env. Both figures are printed. When
panda-gym is installed, its PandaReach-v3 (a PyBullet serial arm) is measured
in the same run as the anchor, and every figure is also given as a ratio to it.

The dynamic fidelity (PyBullet's dynamics under force-limited motors) is
measured for every env that has it, after the kinematic rows, with the
target of at least twice PandaReach-v3's steps/s; the CaPaMan twice, with the
released settings (its default) and with ``CaPaManDynamics.fast()``.

    python benchmarks/env_speed.py [--seconds 5] [--dynamic-only]
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

import gymnasium as gym
from gymnasium.utils.performance import benchmark_step

import paragym

TARGETS = {"paragym/CaPaManCollisionFree-v0": 5000.0, "paragym/HybridSingularityFree-v0": 5000.0,
           "paragym/Orthoglide2PRRKappa-v0": 20000.0, "paragym/MobileTripodOdometry-v0": 5000.0}
#: the dynamic rows: (env id, label, keyword arguments); the target is DYNAMIC_TARGET x the anchor
DYNAMIC = (("paragym/CaPaManCollisionFree-v1", "released", {}),
           ("paragym/CaPaManCollisionFree-v1", "fast", {"dynamics": "capaman-fast"}),
           ("paragym/HybridSingularityFree-v1", "default", {}),
           ("paragym/Orthoglide2PRRKappa-v0", "default", {}),
           ("paragym/MobileTripodOdometry-v1", "default", {}))
DYNAMIC_TARGET = 2.0
SCENARIOS = {"paragym/MobileTripodOdometry-v0": ("random", "push"),  # the paper's drives are named
             "paragym/MobileTripodOdometry-v1": ("random", "push")}


def steps_per_second(env: gym.Env, seconds: float, seed: int = 0) -> float:
    """Env steps per second with pre-drawn random actions (resets included)."""
    env.reset(seed=seed)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(20_000)]
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for action in actions[:1000]:
            _, _, terminated, truncated, _ = env.step(action)
            steps += 1
            if terminated or truncated:
                env.reset()
        actions = actions[1000:] + actions[:1000]
    return steps / (time.perf_counter() - t0)


def reset_seconds(env: gym.Env, n: int = 20) -> float:
    """Mean wall time of a reset (s)."""
    env.reset(seed=0)
    t0 = time.perf_counter()
    for _ in range(n):
        env.reset()
    return (time.perf_counter() - t0) / n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0, help="duration of each measurement")
    parser.add_argument("--dynamic-only", action="store_true", help="measure the anchor and the dynamic rows only")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    rows = []
    anchor = None
    try:
        import panda_gym  # noqa: F401

        env = gym.make("PandaReach-v3")
        anchor = steps_per_second(env, args.seconds)
        rows.append(("PandaReach-v3 (panda-gym, anchor)", "-", anchor, benchmark_step(env, args.seconds, 0),
                     reset_seconds(env), None))
        env.close()
    except ImportError:
        print("panda-gym is not installed: no anchor (pip install panda-gym to add it)")
    warnings.filterwarnings("ignore", message=".*is out of date.*")  # v0 is measured beside v1 on purpose
    for env_id in () if args.dynamic_only else paragym.ENVIRONMENTS:
        for scenario in SCENARIOS.get(env_id, ("random", "paper")):
            env = gym.make(env_id, scenario=scenario)
            sps = steps_per_second(env, args.seconds)
            rows.append((env_id, scenario, sps, benchmark_step(env, target_duration=args.seconds, seed=0),
                         reset_seconds(env), TARGETS.get(env_id)))
            env.close()
    from paragym.sim.capaman_dynamic import CaPaManDynamics

    for env_id, label, kwargs in DYNAMIC:
        kwargs = {k: CaPaManDynamics.fast() if v == "capaman-fast" else v for k, v in kwargs.items()}
        env = gym.make(env_id, scenario=SCENARIOS.get(env_id, ("paper",))[-1], fidelity="dynamic", **kwargs)
        sps = steps_per_second(env, args.seconds)
        rows.append((f"{env_id} dynamic", label, sps, benchmark_step(env, target_duration=args.seconds, seed=0),
                     reset_seconds(env, 5), DYNAMIC_TARGET * anchor if anchor else None))
        env.close()
    print(f"\n{'environment':50s} {'scenario':8s} {'steps/s':>9s} {'x anchor':>9s} {'with sample':>12s} "
          f"{'reset ms':>9s} {'target':>8s}")
    for name, scenario, sps, with_sample, reset_s, target in rows:
        ratio = f"{sps / anchor:9.1f}" if anchor else f"{'-':>9s}"
        verdict = "" if target is None else (f"{target:8.0f} " + ("ok" if sps >= target else "MISSED"))
        print(f"{name:50s} {scenario:8s} {sps:9.0f} {ratio} {with_sample:12.0f} {reset_s * 1000:9.2f} {verdict}")
    print("steps/s: pre-drawn actions; 'with sample': gymnasium's benchmark_step, which draws each action in the loop")


if __name__ == "__main__":
    main()
