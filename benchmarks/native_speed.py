"""Robot-steps per second of the native vector envs at N robots, with autoresets, beside the anchor.

Each env id (default: every one with a native vector env) is made with
``gym.make_vec(ID, num_envs=N, vectorization_mode="vector_entry_point")``,
reset with seed 0 and stepped for ``--seconds``, or for ``--episodes`` E
times the id's episode limit (its ``max_episode_steps``) in batch steps, so
that every robot lives through E episodes' worth of steps. The actions are
uniformly random (16 batches drawn once), or with ``--policy cem`` those of
the id's shipped linear policy (``models/<id>/cem_seed0.npz``), a policy
that survives where random actions end episodes at once; only the env's
steps are timed, not the policy's. The robots whose episodes end are reset
by the env itself, so the rate counts autoresets, as training sees them;
``--train-scenarios K`` makes the envs with a finite training set of K
scenarios (Procgen's ``num_levels``: a reset picks one of K drawn once).
When panda-gym is installed its PandaReach-v3 (one robot, steps/s) is
measured in the same run, between the rows, and each rate is also given as
a ratio to it. The last columns say how many robots were reset per batch
step and the share of the time their resets took (the task's ``_start``).
``--fidelity dynamic --engine mujoco`` times the native vector env of the dynamic fidelity (the robots under
MuJoCo's dynamics, stepped together by its ``rollout``), and prints the share of the step time that MuJoCo's
own stepping took (inside ``rollout``): the env's step over MuJoCo's alone is one over that share.
``--record`` writes the table for the speed page as
``native_speed_<policy>.json`` (``native_speed_<policy>_levels.json`` with a
training set, ``native_speed_<policy>_dynamic_<engine>.json`` for the dynamic fidelity).

    python benchmarks/native_speed.py --env CaPaManCollisionFree-v1 --env CaPaManCollisionFree-v0
    python benchmarks/native_speed.py --env HybridSingularityFree-Hard-v0 --episodes 1.25 --policy cem
    python benchmarks/native_speed.py --env CaPaManCollisionFree-Easy-v0 --fidelity dynamic --engine mujoco \
        --num-envs 64 --episodes 1.25
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
from results_file import add_record_option, paragraph, record  # this folder is on the path when the script runs

import paragym
from paragym.registry import check_env_id

MODELS = Path(__file__).resolve().parent.parent / "models"


def cem_policy(env_id: str) -> Callable[[np.ndarray], np.ndarray]:
    """The id's shipped linear policy as a batched function of the observations (N, D) -> actions (N, A)."""
    from paragym.baselines.cem import read_linear

    path = MODELS / env_id.split("/")[-1] / "cem_seed0.npz"
    if not path.exists():
        raise SystemExit(f"--policy cem: {env_id} has no shipped linear policy ({path})")
    actor = read_linear(path)
    (W, b, _), = actor.layers
    low, high = actor.low, actor.high
    return lambda obs: np.clip(obs @ W.T + b, low, high).astype(np.float32)


def robot_steps_per_second(env_id: str, n: int, seconds: float, resets: dict[str, float] | None = None,
                           policy: Callable[[np.ndarray], np.ndarray] | None = None, steps: int | None = None,
                           **kwargs: object) -> float:
    """The native env's robot-steps/s at ``n`` robots, autoresets counted (a few warm-up steps first: numba's
    kernels load, the first scenarios are drawn), over ``seconds`` or, given, ``steps`` batch steps. Actions:
    uniformly random, or ``policy``'s (its time is not counted). ``kwargs`` go to the env. ``resets``, when given,
    receives the robots reset during the measurement (``robots``), the share of the time their resets took
    (``share``), the batch steps (``steps``) and, in MuJoCo's dynamic fidelity, the share of the time MuJoCo's own
    stepping took (``physics``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = [rng.uniform(env.action_space.low, env.action_space.high).astype(env.action_space.dtype)
               for _ in range(16)]

    def act(k: int, obs: np.ndarray) -> np.ndarray:
        return actions[k % 16] if policy is None else policy(obs)

    for k in range(5):
        obs = env.step(act(k, obs))[0]
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
    pool = getattr(getattr(env, "world", None), "_pool", None)  # MuJoCo's rollout, for the dynamic fidelity
    physics = {"seconds": 0.0}
    if pool is not None:
        rollout = pool.rollout

        def stepping(*args: object, **kwargs: object) -> object:
            t = time.perf_counter()
            try:
                return rollout(*args, **kwargs)
            finally:
                physics["seconds"] += time.perf_counter() - t

        pool.rollout = stepping
    done, total, began = 0, 0.0, time.perf_counter()
    while (done < steps) if steps is not None else (time.perf_counter() - began < seconds):
        a = act(done, obs)
        t = time.perf_counter()
        obs = env.step(a)[0]
        total += time.perf_counter() - t
        done += 1
    env.close()
    if resets is not None:
        resets.update(robots=clock["robots"], share=clock["seconds"] / total, steps=done,
                      physics=physics["seconds"] / total if pool is not None else None)
    return done * n / total


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
    parser.add_argument("--robots", "--num-envs", type=int, default=1024, help="N (default %(default)s)")
    parser.add_argument("--seconds", type=float, default=4.0, help="duration of each measurement")
    parser.add_argument("--episodes", type=float, default=None,
                        help="instead of --seconds: this many times the id's episode limit, in batch steps")
    parser.add_argument("--policy", choices=("random", "cem"), default="random",
                        help="the actions: uniformly random, or the id's shipped linear policy (default random)")
    parser.add_argument("--train-scenarios", type=int, default=None, metavar="K",
                        help="a finite training set of K scenarios (the envs' train_scenarios)")
    parser.add_argument("--fidelity", choices=("kinematic", "dynamic"), default="kinematic",
                        help="the fidelity (default %(default)s; dynamic needs --engine mujoco)")
    parser.add_argument("--engine", choices=("mujoco",), default=None, help="the dynamic fidelity's engine")
    add_record_option(parser)
    args = parser.parse_args()
    if (args.fidelity == "dynamic") != (args.engine is not None):
        parser.error("the native vector env's dynamic fidelity runs in MuJoCo: --fidelity dynamic --engine mujoco")
    ids = [check_env_id(e) for e in args.env] if args.env else list(paragym.VECTOR_ENTRY_POINTS)
    extra = {} if args.train_scenarios is None else {"train_scenarios": args.train_scenarios}
    if args.engine is not None:
        extra.update(fidelity=args.fidelity, engine=args.engine)
    rows = []
    for env_id in ids:
        limit = gym.spec(env_id).max_episode_steps
        steps = None if args.episodes is None else math.ceil(args.episodes * limit)
        policy = cem_policy(env_id) if args.policy == "cem" else None
        before = anchor_steps_per_second(args.seconds / 2)
        resets: dict[str, float] = {}
        rate = robot_steps_per_second(env_id, args.robots, args.seconds, resets, policy, steps, **extra)
        after = anchor_steps_per_second(args.seconds / 2)
        anchor = None if before is None else (before + after) / 2
        rows.append((env_id, rate, anchor, resets))
    dynamic = args.engine is not None
    digits = 1 if dynamic else 0  # a few x the anchor: a decimal says more
    print(f"\n{'environment':40s} {'N':>6s} {'robot-steps/s':>14s} {'anchor steps/s':>15s} {'x anchor':>9s} "
          f"{'resets/step':>12s} {'resets':>7s}" + (f" {'MuJoCo':>7s} {'x MuJoCo':>9s}" if dynamic else ""))
    table = []
    for env_id, rate, anchor, resets in rows:
        ratio = f"{rate / anchor:9.{digits}f}" if anchor else f"{'-':>9s}"
        shown = f"{anchor:15,.0f}" if anchor else f"{'-':>15s}"
        physics = [f"{100 * resets['physics']:.0f} %", f"{1 / resets['physics']:.2f}"] if dynamic else []
        print(f"{env_id.split('/')[-1]:40s} {args.robots:6d} {rate:14,.0f} {shown} {ratio} "
              f"{resets['robots'] / resets['steps']:12.1f} {100 * resets['share']:6.0f}%"
              + (f" {physics[0]:>7s} {physics[1]:>9s}" if dynamic else ""))
        table.append([env_id.split("/")[-1], f"{rate:,.0f}", f"{rate / anchor:.{digits}f}" if anchor else "-",
                      f"{resets['robots'] / resets['steps']:.1f}", f"{100 * resets['share']:.0f} %", *physics])
    how = (f"{args.episodes:g} episode limits" if args.episodes is not None else f"{args.seconds:g} s") + \
        f", {args.policy} actions" + ("" if args.train_scenarios is None else
                                      f", train_scenarios={args.train_scenarios}") + \
        (f", dynamic fidelity in {args.engine}" if dynamic else "")
    if args.record:
        name = f"native_speed_{args.policy}" + ("" if args.train_scenarios is None else "_levels") + \
            (f"_dynamic_{args.engine}" if dynamic else "")
        record(name, f"The native vector envs at N = {args.robots}, {how}",
               paragraph(__doc__, 1), ["env", "robot-steps/s", "x PandaReach-v3", "resets/step", "time in resets",
                                       *(["time in MuJoCo's stepping", "env step / MuJoCo's"] if dynamic else [])],
               table, folder=Path(args.record))


if __name__ == "__main__":
    main()
