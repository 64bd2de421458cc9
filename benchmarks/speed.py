"""The speed report: single envs, gymnasium's vector modes, the native vector envs, PPO.

One table, every figure measured in this run on this machine, random
scenarios (each env's default), uniformly random actions drawn before the
clock starts, resets included:

* ``single``: ``gym.make(ENV_ID)`` (kinematic), one core;
* ``sync 2`` / ``async 2``: ``gym.make_vec(ENV_ID, 2, vectorization_mode="sync" | "async")``;
* ``native N``: ``gym.make_vec(ENV_ID, N, vectorization_mode="vector_entry_point")``
  for N = 1, 64, 1024, 4096, one core. Each is timed over at least one full
  episode of every robot (so that the autoresets are in the figure; at most
  60 s), after a reset that is not; ``@4096, 20 steps``: the first 20 steps
  after that reset at N = 4096, which few robots outlive (about the cost of
  the step alone);
* PandaReach-v3 (panda-gym, when installed) as the anchor, and each figure's
  ratio to it;
* the peak resident memory of a fresh process that builds and steps the
  native env at N = 4096;
* PPO training throughput (env steps per second of ``model.learn``,
  Stable-Baselines3, the yml's PPO settings with 64 copies): 64 single envs in
  a DummyVecEnv against the native vector env with 64 robots.

    python benchmarks/speed.py [--seconds 3] [--skip-ppo] [--envs ID ...] [--sizes N ...]
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import resource
import time

import gymnasium as gym
import numpy as np
from env_speed import steps_per_second  # this folder is on the path when the script runs
from results_file import add_record_option, record  # this folder is on the path when it runs

import paragym

#: the speed page's paragraph above this script's table (``--record``)
PARAGRAPH = (
    "The single env, gymnasium's sync and async modes with two copies, and the native vector env at N = "
    "1, 64, 1024 and 4096 robots, each timed over at least one full episode of every robot (robot-"
    "steps/s, random scenarios, one core; in brackets the ratio to PandaReach-v3, 391 in that run), with "
    "the first 20 steps after the reset at N = 4096 and the peak resident memory. "
)

TARGET_4096 = {"paragym/Orthoglide2PRRKappa-v0": 1_000_000, "paragym/HybridSingularityFree-v0": 1_000_000,
               "paragym/CaPaManCollisionFree-v0": 250_000, "paragym/MobileTripodOdometry-v0": 250_000}
SIZES = (1, 64, 1024, 4096)


def single_rate(env_id: str, seconds: float) -> float:
    """Steps/s of ``gym.make(env_id)`` (any vectorisation mode's sub-env), as env_speed.py measures it."""
    env = gym.make(env_id)
    rate = steps_per_second(env, seconds)
    env.close()
    return rate


def vector_rate(env: gym.vector.VectorEnv, seconds: float, min_steps: int = 0, max_seconds: float = 60.0,
                reset: bool = True) -> float:
    """Robot-steps/s of a vector env over at least ``seconds`` and ``min_steps``
    batch steps (but no more than ``max_seconds``), after a reset (``reset``)."""
    if reset:
        env.reset(seed=0)
    rng = np.random.default_rng(0)
    space = env.action_space
    actions = rng.uniform(space.low, space.high, (8, *space.shape)).astype(space.dtype)
    steps, t0 = 0, time.perf_counter()
    while (time.perf_counter() - t0 < seconds or steps < min_steps) and time.perf_counter() - t0 < max_seconds:
        env.step(actions[steps % 8])
        steps += 1
    return steps * env.num_envs / (time.perf_counter() - t0)


def _native(env_id: str, n: int, seconds: float, queue: mp.Queue) -> None:
    """In a fresh process: the native env's rate at ``n`` robots (resets
    included), its rate over the first 20 steps after a reset (few robots
    finish so soon: about the step alone) and the process's peak RSS (MiB)."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point")
    episode = paragym.ENVIRONMENTS[env_id][1]
    env.reset(seed=0)
    first = vector_rate(env, 0.0, min_steps=20, reset=False)
    rate = vector_rate(env, seconds, min_steps=episode + 1 if n > 1 else 0, reset=False)
    queue.put((rate, first, _peak_rss_mib()))


def _peak_rss_mib() -> float:
    """This process's peak resident set (MiB): VmHWM, which starts afresh at exec (ru_maxrss
    does not: a spawned child would report its parent's peak)."""
    try:
        for line in open("/proc/self/status"):
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def native_rate(env_id: str, n: int, seconds: float) -> tuple[float, float, float]:
    """:func:`_native` in a spawned process: (rate, rate of the first 20 steps, peak RSS MiB)."""
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    proc = ctx.Process(target=_native, args=(env_id, n, seconds, queue))
    proc.start()
    out = queue.get()
    proc.join()
    return out


def ppo_rate(env_id: str, vectorized: bool, steps: int = 16_384, n_envs: int = 64) -> float:
    """Env steps/s during ``PPO.learn`` (one torch thread)."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    from paragym.baselines.sb3_vec import as_sb3_vecenv
    from paragym.baselines.training import PARAGYM_KEYS, console_logger, load_hyperparams

    torch.set_num_threads(1)
    hp = load_hyperparams("ppo", env_id)
    kwargs = {k: v for k, v in hp.items() if k not in PARAGYM_KEYS and k != "policy"}
    kwargs.update(n_steps=64, batch_size=1024)
    env = as_sb3_vecenv(env_id, n_envs) if vectorized else make_vec_env(env_id, n_envs=n_envs, seed=0)
    model = PPO("MlpPolicy", env, seed=0, device="cpu", **kwargs)
    model.set_logger(console_logger())
    model.learn(n_envs * 64)  # warm-up: one rollout and one update
    t0 = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    return steps / (time.perf_counter() - t0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="least duration of each measurement")
    parser.add_argument("--skip-ppo", action="store_true", help="leave out the PPO throughput")
    parser.add_argument("--envs", nargs="*", default=list(paragym.ENVIRONMENTS), help="env ids to measure")
    parser.add_argument("--sizes", nargs="*", type=int, default=list(SIZES),
                        help="numbers of robots of the native env (the targets are for 4096)")
    add_record_option(parser)
    args = parser.parse_args()
    sizes, big = args.sizes, max(args.sizes)

    anchor = None
    try:
        import panda_gym  # noqa: F401

        anchor = single_rate("PandaReach-v3", args.seconds)
    except ImportError:
        print("panda-gym is not installed: no anchor (pip install panda-gym to add it)")

    def fmt(rate: float | None) -> str:
        if rate is None:
            return "-"
        return f"{rate:,.0f}" + (f" ({rate / anchor:,.0f}x)" if anchor else "")

    header = ["environment", "single", "sync 2", "async 2"] + [f"native {n}" for n in sizes] + [
        "target @4096", f"@{big}, 20 steps", f"peak RSS @{big}"]
    rows = []
    if anchor:
        rows.append(["PandaReach-v3 (anchor)", f"{anchor:,.0f}"] + ["-"] * (len(header) - 2))
    ppo = []
    for env_id in args.envs:
        name = env_id.split("/")[-1]
        single = single_rate(env_id, args.seconds)
        sync = vector_rate(gym.make_vec(env_id, 2, vectorization_mode="sync"), args.seconds)
        asyn = gym.make_vec(env_id, 2, vectorization_mode="async")
        a_rate = vector_rate(asyn, args.seconds)
        asyn.close()
        native, first, rss = [], "-", "-"
        if env_id in paragym.VECTOR_ENTRY_POINTS:
            for n in sizes:
                rate, first_rate, peak = native_rate(env_id, n, args.seconds)
                native.append(fmt(rate))
                first, rss = f"{first_rate:,.0f}", f"{peak:,.0f} MiB"
        else:
            native = ["no native env"] + ["-"] * (len(sizes) - 1)
        rows.append([name, fmt(single), fmt(sync), fmt(a_rate), *native, f"{TARGET_4096[env_id]:,}", first, rss])
        print(" | ".join(rows[-1]), flush=True)
        if not args.skip_ppo and env_id in paragym.VECTOR_ENTRY_POINTS:
            ppo.append((name, ppo_rate(env_id, False), ppo_rate(env_id, True)))

    if args.record:
        record("speed_at_scale", "At scale: the single env, gymnasium's vector modes and the native env at N robots",
               PARAGRAPH, header, rows, order=70, folder=args.record)
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    print("\nsteps/s (robot-steps/s for vector envs), one core; in brackets: ratio to PandaReach-v3\n")
    for r in [header, ["-" * w for w in widths], *rows]:
        print("  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True))))
    if ppo:
        print("\nPPO training throughput (env steps/s in model.learn, 64 copies, one torch thread)\n")
        print(f"{'environment':28s} {'64 single envs':>15s} {'native, 64 robots':>18s} {'ratio':>6s}")
        for name, single, native in ppo:
            print(f"{name:28s} {single:15,.0f} {native:18,.0f} {native / single:6.1f}")


if __name__ == "__main__":
    main()
