"""MuJoCo alone stepping N copies of a dynamic scene's mechanism, by four routes, beside the anchor.

For each env id (default: the CaPaMan's and the hybrid's easy rungs) the MuJoCo dynamic env is made (the default 1
ms step, and ``MuJoCoSettings.fast``'s 2 ms) and reset with seed 0; its compiled model and posed state are what the
env simulates. N copies of that state (``--num-envs``, 64) are stepped through control periods, each the task's
``control_period`` in physics steps, their servos' targets swinging about the held pose so that the mechanisms move,
by four routes: ``sequential``, ``mj_step`` on N MjData in turn from Python; ``threads-2``, the same on two threads,
each stepping half the copies (MuJoCo releases the GIL while it steps); ``rollout-1`` and ``rollout-2``, MuJoCo's
``rollout`` module over the N states for one control period per call, on one and two threads. Each route's copies
are compared, after ten control periods, with the same copies stepped in turn: ``rollout`` starts every call from a
state without the solver's warm start, which moves the last bits. The table gives robot control steps per second
(one control period of one robot), physics steps per second and the ratio to PandaReach-v3's steps per second
measured in the same run, before and after each env's rows (panda-gym installed). This is the physics alone: the
ceiling of a native dynamic vector env, whose own work (observation, reward, clearance, the loops' check) comes on
top of it.

    python benchmarks/mujoco_batch.py [--env ID ...] [--num-envs 64] [--seconds 2] [--record]
"""

from __future__ import annotations

import argparse
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import gymnasium as gym
import numpy as np
from native_speed import anchor_steps_per_second
from results_file import add_record_option, engine_versions, paragraph, record

import paragym  # noqa: F401  (registers the ids)
from paragym.sim.client import physics_steps
from paragym.sim.mujoco_sim import MuJoCoSettings

DEFAULT_IDS = ("paragym/CaPaManCollisionFree-Easy-v0", "paragym/HybridSingularityFree-Easy-v2")
#: the servos' targets swing by this share of their range about the held pose, one cycle per second
SWING = 0.05
#: the control periods after which each route's state is compared with the sequential route's
CHECKED = 10


def _sequential_qpos(model: Any, start: np.ndarray, spec: Any, controls: Any, n: int, k: int) -> np.ndarray:
    """The N copies' joint positions after :data:`CHECKED` control periods stepped one MjData at a time."""
    import mujoco

    out = []
    for i in range(n):
        d = mujoco.MjData(model)
        mujoco.mj_setState(model, d, start, spec)
        for period in range(CHECKED):
            ctrl = controls(period)
            for j in range(k):
                d.ctrl[:] = ctrl[i, j]
                mujoco.mj_step(model, d)
        out.append(d.qpos.copy())
    return np.array(out)


def routes(env_id: str, settings: MuJoCoSettings, n: int, seconds: float
           ) -> tuple[int, list[tuple[str, float, float]]]:
    """Physics steps per control period, and each route's robot control steps/s and how far its copies' joints
    lie, after :data:`CHECKED` control periods, from the same copies stepped one MjData at a time."""
    import mujoco
    from mujoco import rollout

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, fidelity="dynamic", engine=settings)
    env.reset(seed=0)
    sim = env.unwrapped.world.scene.sim
    model, data = sim.model, sim.data
    k = physics_steps(env.unwrapped.params.control_period, model.opt.timestep)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    start = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, start, spec)
    held = data.ctrl.copy()
    span = np.where(model.actuator_ctrllimited, model.actuator_ctrlrange[:, 1] - model.actuator_ctrlrange[:, 0], 1.0)
    phase = np.linspace(0, 2 * np.pi, n, endpoint=False)[:, None, None]
    times = (np.arange(k) * model.opt.timestep)[None, :, None]

    def controls(period: int) -> np.ndarray:  # (n, k, nu)
        t = period * k * model.opt.timestep + times
        return held + SWING * span * np.sin(2 * np.pi * t + phase)

    out = []
    datas = [mujoco.MjData(model) for _ in range(n)]
    for d in datas:
        mujoco.mj_setState(model, d, start, spec)
    periods, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        ctrl = controls(periods)
        for i, d in enumerate(datas):
            for j in range(k):
                d.ctrl[:] = ctrl[i, j]
                mujoco.mj_step(model, d)
        periods += 1
    out.append(("sequential", n * periods / (time.perf_counter() - t0), 0.0))
    reference = _sequential_qpos(model, start, spec, controls, n, k)
    datas = [mujoco.MjData(model) for _ in range(n)]  # fresh: a state's FULLPHYSICS leaves the warm start as it was
    for d in datas:
        mujoco.mj_setState(model, d, start, spec)
    halves = [datas[: n // 2], datas[n // 2:]]

    def advance(part: list, rows: range, ctrl: np.ndarray) -> None:
        for i, d in zip(rows, part, strict=True):
            for j in range(k):
                d.ctrl[:] = ctrl[i, j]
                mujoco.mj_step(model, d)  # MuJoCo's bindings release the GIL while it steps

    with ThreadPoolExecutor(2) as pool:
        periods, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds or periods < CHECKED:
            ctrl = controls(periods)
            list(pool.map(advance, halves, (range(0, n // 2), range(n // 2, n)), (ctrl, ctrl)))
            periods += 1
            if periods == CHECKED:
                apart = max(float(np.abs(d.qpos - q).max()) for d, q in zip(datas, reference, strict=True))
        out.append(("threads-2", n * periods / (time.perf_counter() - t0), apart))
    for threads in (1, 2):
        state = np.tile(start, (n, 1))
        with rollout.Rollout(nthread=threads) as pool:
            workers = [mujoco.MjData(model) for _ in range(threads)]
            periods, t0 = 0, time.perf_counter()
            while time.perf_counter() - t0 < seconds or periods < CHECKED:
                states, _ = pool.rollout(model, workers, state, controls(periods), nstep=k)
                state = states[:, -1, :]
                periods += 1
                if periods == CHECKED:  # FULLPHYSICS: time, qpos, qvel, act, ...; qpos from the second entry
                    apart = float(np.abs(state[:, 1:1 + model.nq] - reference).max())
            out.append((f"rollout-{threads}", n * periods / (time.perf_counter() - t0), apart))
    env.close()
    return k, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", default=None, help="an id whose dynamic fidelity runs in MuJoCo "
                        "(repeatable; default: " + ", ".join(DEFAULT_IDS) + ")")
    parser.add_argument("--num-envs", type=int, default=64, help="copies stepped together")
    parser.add_argument("--seconds", type=float, default=2.0, help="seconds per route")
    add_record_option(parser)
    args = parser.parse_args()
    if args.num_envs < 1 or args.seconds <= 0:
        parser.error("--num-envs must be positive and --seconds above 0")
    rows = []
    for env_id in args.env or DEFAULT_IDS:
        before = anchor_steps_per_second(args.seconds / 2)
        measured = [(s, *routes(env_id, s, args.num_envs, args.seconds)) for s in (MuJoCoSettings(),
                                                                                  MuJoCoSettings.fast())]
        after = anchor_steps_per_second(args.seconds / 2)
        panda = None if before is None else (before + after) / 2
        for settings, k, rates in measured:
            for route, rate, apart in rates:
                rows.append([env_id, f"{settings.time_step * 1000:g}", str(k), route, str(args.num_envs),
                             f"{rate:,.0f}", f"{rate * k:,.0f}", f"{rate / panda:.2f}" if panda else "-",
                             f"{apart:.1e}"])
                print(" | ".join(rows[-1]), flush=True)
        print(f"  PandaReach-v3: {panda:,.0f} steps/s" if panda else "  (no panda-gym: no anchor)", flush=True)
    if args.record:
        record("mujoco_batch", f"MuJoCo alone, {args.num_envs} mechanisms at once", paragraph(__doc__, 1),
               ["env", "step (ms)", "physics steps per control step", "route", "N", "robot control steps/s",
                "physics steps/s", "x PandaReach-v3", f"joints apart after {CHECKED} periods (m or rad)"], rows,
               order=25, folder=args.record, source=engine_versions())


if __name__ == "__main__":
    main()
