"""Steps per second of every registered paragym env, kinematic and dynamic fidelity, no render.

Measured as Gymnasium's ``benchmark_step`` does (uniformly random actions,
resets included whenever an episode ends, through ``gym.make``'s wrappers),
pinned to one core, except that the actions are drawn before the clock
starts: ``Box.sample`` alone can cost more than a fast env's step, and it is
the same for every env. Both figures are printed. When
panda-gym is installed, its PandaReach-v3 (a PyBullet serial arm) is measured
in the same run as the anchor, and every figure is also given as a ratio to it.

The dynamic fidelity (PyBullet's dynamics under force-limited motors) is
measured for every env that has it, after the kinematic rows, with the
target of at least twice PandaReach-v3's steps/s: each env with its default
settings and, where the task has them, with its faster opt-in presets
(``CaPaManDynamics.fast()`` and ``.split()``, ``HybridDynamics.split()``).
A dynamic row alternates the env and the anchor in three rounds and gives
the medians of the env's steps/s and of the rounds' ratios: a machine's load
moves the anchor from one run to the next, and a ratio of two measurements
taken seconds apart moves with it.

    python benchmarks/env_speed.py [--seconds 5] [--dynamic-only] [--env ID ...] [--record]

``--record`` writes the table to ``benchmarks/results/env_speed.json``, which
``python docs/build.py`` puts on the speed page.
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

import gymnasium as gym
import numpy as np
from gymnasium.utils.performance import benchmark_step
from results_file import add_record_option, paragraph, record

import paragym
from paragym import registry

TARGETS = {"paragym/CaPaManCollisionFree-v0": 5000.0, "paragym/HybridSingularityFree-v0": 5000.0,
           "paragym/Orthoglide2PRRKappa-v0": 20000.0, "paragym/MobileTripodOdometry-v0": 5000.0}
#: the dynamic rows: (env id, label, physics settings: a preset of the task's dynamics dataclass, or None for the
#: env's default); the target is DYNAMIC_TARGET x the anchor
DYNAMIC = (("paragym/CaPaManCollisionFree-v1", "released", None),
           ("paragym/CaPaManCollisionFree-v1", "fast", "CaPaManDynamics.fast"),
           ("paragym/CaPaManCollisionFree-v1", "split", "CaPaManDynamics.split"),
           ("paragym/HybridSingularityFree-v1", "default", None),
           ("paragym/HybridSingularityFree-v1", "split", "HybridDynamics.split"),
           ("paragym/Orthoglide2PRRKappa-v0", "default", None),
           ("paragym/MobileTripodOdometry-v1", "default", None))
DYNAMIC_TARGET = 2.0
#: a dynamic row's measurement: this many rounds of the env then the anchor, each a share of --seconds; the
#: figures are the medians (the env's steps/s, and the ratio of each round)
ROUNDS = 3


def _random_actions(space: gym.Space, n: int, seed: int) -> list:
    """``n`` uniform random actions of ``space``: one numpy draw for a bounded Box (``Box.sample``
    one at a time took about 90 us each, 0.4 s of every short measurement), else ``sample``."""
    if isinstance(space, gym.spaces.Box) and space.is_bounded():
        draws = np.random.default_rng(seed).uniform(space.low, space.high, size=(n, *space.shape))
        return list(draws.astype(space.dtype))
    space.seed(seed)
    return [space.sample() for _ in range(n)]


def run_for(env: gym.Env, seconds: float, seed: int = 0) -> tuple[int, float]:
    """Step ``env`` with pre-drawn random actions (resets included) for ``seconds`` (checked every 20
    steps, so that a slow env is not held to a fixed number of steps); the steps taken and the time (s)."""
    env.reset(seed=seed)
    actions = _random_actions(env.action_space, 4_000, seed)
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        start = steps % len(actions)
        for action in actions[start:start + 20]:
            _, _, terminated, truncated, _ = env.step(action)
            steps += 1
            if terminated or truncated:
                env.reset()
    return steps, time.perf_counter() - t0


def steps_per_second(env: gym.Env, seconds: float, seed: int = 0) -> float:
    """Env steps per second with pre-drawn random actions (resets included): :func:`run_for`."""
    steps, elapsed = run_for(env, seconds, seed)
    return steps / elapsed


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
    parser.add_argument("--env", action="append", default=None,
                        help="only this env id's rows (repeatable; the 'paragym/' may be omitted)")
    add_record_option(parser)
    args = parser.parse_args()
    only = None if args.env is None else {registry.check_env_id(e) for e in args.env}
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    rows = []
    anchor = None
    try:
        import panda_gym  # noqa: F401

        anchor_env = gym.make("PandaReach-v3")
        anchor = steps_per_second(anchor_env, args.seconds)
        rows.append(("PandaReach-v3 (panda-gym, anchor)", "-", anchor, benchmark_step(anchor_env, args.seconds, 0),
                     reset_seconds(anchor_env), None, 1.0))
    except ImportError:
        print("panda-gym is not installed: no anchor (pip install panda-gym to add it)")
    warnings.filterwarnings("ignore", message=".*is out of date.*")  # v0 is measured beside v1 on purpose
    for env_id in () if args.dynamic_only else paragym.ENVIRONMENTS:
        if only is not None and env_id not in only:
            continue
        for scenario in ("random", registry.row(env_id).paper_scenario):
            env = gym.make(env_id, scenario=scenario)
            sps = steps_per_second(env, args.seconds)
            rows.append((env_id, scenario, sps, benchmark_step(env, target_duration=args.seconds, seed=0),
                         reset_seconds(env), TARGETS.get(env_id), sps / anchor if anchor else None))
            env.close()
    from paragym.sim import capaman_dynamic, hybrid_dynamic

    presets = {"CaPaManDynamics": capaman_dynamic.CaPaManDynamics, "HybridDynamics": hybrid_dynamic.HybridDynamics}
    for env_id, label, preset in DYNAMIC:
        if only is not None and env_id not in only:
            continue
        kwargs = {}
        if preset is not None:
            cls, method = preset.split(".")
            kwargs["dynamics"] = getattr(presets[cls], method)()
        env = gym.make(env_id, scenario=registry.row(env_id).paper_scenario, fidelity="dynamic", **kwargs)
        if anchor:  # the anchor and the env alternate, so that the machine's load moves both alike
            pairs = [(steps_per_second(env, args.seconds / ROUNDS, r), steps_per_second(anchor_env,
                                                                                      args.seconds / ROUNDS, r))
                     for r in range(ROUNDS)]
            sps = float(np.median([e for e, _ in pairs]))
            ratio = float(np.median([e / a for e, a in pairs]))
        else:
            sps, ratio = steps_per_second(env, args.seconds), None
        rows.append((f"{env_id} dynamic", label, sps, benchmark_step(env, target_duration=args.seconds, seed=0),
                     reset_seconds(env, 5), f"{DYNAMIC_TARGET:.0f}x anchor", ratio))
        env.close()
    print(f"\n{'environment':50s} {'scenario':8s} {'steps/s':>9s} {'x anchor':>9s} {'with sample':>12s} "
          f"{'reset ms':>9s} {'target':>14s}")
    for name, scenario, sps, with_sample, reset_s, target, ratio in rows:
        shown = f"{ratio:9.1f}" if ratio is not None else f"{'-':>9s}"
        if target is None:
            verdict = ""
        elif isinstance(target, str):  # relative to the anchor
            verdict = f"{target:>14s} " + ("-" if ratio is None else "ok" if ratio >= DYNAMIC_TARGET else "MISSED")
        else:
            verdict = f"{target:14.0f} " + ("ok" if sps >= target else "MISSED")
        print(f"{name:50s} {scenario:8s} {sps:9.0f} {shown} {with_sample:12.0f} {reset_s * 1000:9.2f} {verdict}")
    print("steps/s: pre-drawn actions; 'with sample': gymnasium's benchmark_step, which draws each action in the loop")
    if args.record:
        record("env_speed", "Steps per second of every env", paragraph(__doc__, 1),
               ["environment", "scenario", "steps/s", "x anchor", "with sample (steps/s)", "reset (ms)", "target"],
               [[name, scenario, f"{sps:,.0f}", "-" if ratio is None else f"{ratio:.1f}", f"{with_sample:,.0f}",
                 f"{reset_s * 1000:.2f}", "" if target is None else target if isinstance(target, str)
                 else f"{target:,.0f}"] for name, scenario, sps, with_sample, reset_s, target, ratio in rows],
               order=10, folder=args.record)


if __name__ == "__main__":
    main()
