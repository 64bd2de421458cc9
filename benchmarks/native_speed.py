"""Robot-steps per second of the native vector envs at N robots, with autoresets, beside the anchor.

Each env id (default: every one with a native vector env) is made with
``gym.make_vec(ID, num_envs=N, vectorization_mode="vector_entry_point")``,
reset with seed 0 and stepped with uniformly random actions (16 batches drawn
once) for ``--seconds``; the robots whose episodes end are reset by the env
itself, so the rate counts autoresets, as training sees them. When panda-gym
is installed its PandaReach-v3 (one robot, steps/s) is measured in the same
run, between the rows, and each rate is also given as a ratio to it. The last
columns say how many robots were reset per batch step and the share of the
time their resets took (the task's ``_start``).

    python benchmarks/native_speed.py --env CaPaManCollisionFree-v1 --env CaPaManCollisionFree-v0
"""

from __future__ import annotations

import argparse
import time
import warnings

import gymnasium as gym
import numpy as np

import paragym
from paragym.registry import check_env_id


def robot_steps_per_second(env_id: str, n: int, seconds: float, resets: dict[str, float] | None = None) -> float:
    """The native env's robot-steps/s at ``n`` robots, random actions, autoresets counted (a few warm-up steps
    first: numba's kernels load, the first scenarios are drawn). ``resets``, when given, receives the robots
    reset during the measurement (``robots``) and the share of the time their resets took (``share``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = [rng.uniform(env.action_space.low, env.action_space.high).astype(env.action_space.dtype)
               for _ in range(16)]
    for k in range(5):
        env.step(actions[k])
    clock = {"seconds": 0.0, "robots": 0}
    start = env._start  # the task's reset of the given robots, which every native env calls (ParagymVectorEnv)

    def timed(rows: np.ndarray, *args: object) -> object:
        t = time.perf_counter()
        try:
            return start(rows, *args)
        finally:
            clock["seconds"] += time.perf_counter() - t
            clock["robots"] += len(rows)

    env._start = timed
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        env.step(actions[steps % 16])
        steps += 1
    total = time.perf_counter() - t0
    env.close()
    if resets is not None:
        resets.update(robots=clock["robots"], share=clock["seconds"] / total, steps=steps)
    return steps * n / total


def anchor_steps_per_second(seconds: float) -> float | None:
    """PandaReach-v3's steps/s (None without panda-gym)."""
    try:
        import panda_gym  # noqa: F401
    except ImportError:
        return None
    env = gym.make("PandaReach-v3")
    env.reset(seed=0)
    env.action_space.seed(0)
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        steps += 1
        if terminated or truncated:
            env.reset()
    env.close()
    return steps / (time.perf_counter() - t0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", help="only this env id (repeatable; the 'paragym/' may be omitted)")
    parser.add_argument("--robots", type=int, default=1024, help="N (default %(default)s)")
    parser.add_argument("--seconds", type=float, default=4.0, help="duration of each measurement")
    args = parser.parse_args()
    ids = [check_env_id(e) for e in args.env] if args.env else list(paragym.VECTOR_ENTRY_POINTS)
    rows = []
    for env_id in ids:
        before = anchor_steps_per_second(args.seconds / 2)
        resets: dict[str, float] = {}
        rate = robot_steps_per_second(env_id, args.robots, args.seconds, resets)
        after = anchor_steps_per_second(args.seconds / 2)
        anchor = None if before is None else (before + after) / 2
        rows.append((env_id, rate, anchor, resets))
    print(f"\n{'environment':40s} {'N':>6s} {'robot-steps/s':>14s} {'anchor steps/s':>15s} {'x anchor':>9s} "
          f"{'resets/step':>12s} {'resets':>7s}")
    for env_id, rate, anchor, resets in rows:
        ratio = f"{rate / anchor:9.0f}" if anchor else f"{'-':>9s}"
        shown = f"{anchor:15,.0f}" if anchor else f"{'-':>15s}"
        print(f"{env_id.split('/')[-1]:40s} {args.robots:6d} {rate:14,.0f} {shown} {ratio} "
              f"{resets['robots'] / resets['steps']:12.1f} {100 * resets['share']:6.0f}%")


if __name__ == "__main__":
    main()
