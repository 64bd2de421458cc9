"""Soak: a million CaPaMan steps (random in-Box actions, random scenarios) and the RSS along the way.

    python benchmarks/soak.py [--steps 1000000] [--vector 64]

Prints the resident memory every tenth of the run, for the single env and, with --vector N,
for the native vector env with N robots (steps counted per robot). Flat figures mean that
nothing a reset makes is kept: before paragym 0.2.0 PyBullet kept every removed obstacle's
collision shapes and memory grew linearly (about 5 KiB a reset).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
import psutil

import paragym  # noqa: F401

ENV = "paragym/CaPaManCollisionFree-v0"


def rss() -> float:
    return psutil.Process().memory_info().rss / 2 ** 20


def soak_single(steps: int) -> None:
    env = gym.make(ENV)
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    resets, t0 = 0, time.perf_counter()
    for i in range(steps):
        _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, 3).astype(np.float32))
        if term or trunc:
            env.reset()
            resets += 1
        if i % (steps // 10) == 0 or i == steps - 1:
            print(f"single  step {i + 1:>9,}  resets {resets:>7,}  RSS {rss():7.1f} MiB  "
                  f"{time.perf_counter() - t0:6.0f} s", flush=True)
    env.close()


def soak_vector(steps: int, n: int) -> None:
    venv = gym.make_vec(ENV, num_envs=n, vectorization_mode="vector_entry_point")
    rng = np.random.default_rng(0)
    venv.reset(seed=0)
    rounds, t0, ended = steps // n, time.perf_counter(), 0
    for i in range(rounds):
        _, _, term, trunc, _ = venv.step(rng.uniform(-1, 1, (n, 3)))
        ended += int(np.sum(term | trunc))
        if i % max(1, rounds // 10) == 0 or i == rounds - 1:
            print(f"vector  robot-steps {(i + 1) * n:>9,}  robot resets {ended:>7,}  RSS {rss():7.1f} MiB  "
                  f"{time.perf_counter() - t0:6.0f} s", flush=True)
    venv.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--vector", type=int, default=0, help="also soak the native vector env with N robots")
    args = parser.parse_args()
    soak_single(args.steps)
    if args.vector:
        soak_vector(args.steps, args.vector)


if __name__ == "__main__":
    main()
