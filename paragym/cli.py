"""The ``paragym`` command: ``paragym envs``, ``paragym demo ENV_ID`` and the rest (``paragym --help``).

Generic over the tasks: an env id's registry row (:mod:`paragym.registry`) and its task's bench
(:mod:`paragym.baselines.tasks`) say what each command does with it.
"""

from __future__ import annotations

import argparse
import os
import sqlite3
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym

import paragym
from paragym import registry
from paragym.baselines import RandomPolicy, ZeroPolicy
from paragym.baselines.tasks import bench_of
from paragym.rollout import frame_of, run_episode

__all__ = ["main"]


def _validate_episode(env_id: str, args: argparse.Namespace) -> int:
    """Run a policy's episode in dynamic fidelity and validate what it executed against what it commanded
    (:func:`paragym.validation.episode.validate_episode`); print the report, save Figs 8-9 and a JSON."""
    import json

    from paragym.baselines.policies import get_policy
    from paragym.validation.episode import validate_episode
    from paragym.validation.report import write_report

    name = args.policy or bench_of(env_id).reference
    spec = get_policy(env_id, name, args.models)
    env = gym.make(env_id, scenario=_scenario(env_id, args), fidelity="dynamic", engine=args.engine)
    try:
        print(f"{env_id}: {args.scenario} scenario, seed {args.seed}, policy {name} ({spec.kind}), dynamic fidelity "
              f"in {args.engine}")
        val = validate_episode(env, spec.factory(env, args.seed), seed=args.seed, sensor_seed=args.seed)
    finally:
        env.close()
    rep = val.report
    print(f"episode: {val.steps} steps, return {val.episode_return:.2f}, success {val.success}; the body "
          f"executed at most {val.position_error * 1000:.2f} mm from its command")
    if rep is None:
        print("FAIL: the episode ended before the sensors took enough samples to validate it")
        return 1
    print(rep.table())
    out = Path(args.out) / (env_id.split("/")[1] + f"_{args.scenario}_seed{args.seed}_{name}")
    return write_report(rep, out, f"{env_id.split('/')[1]}, {args.scenario}, {name}: "
                                  f"{'PASS' if rep.passed else 'FAIL'}",
                        {"env_id": env_id, "scenario": args.scenario, "seed": args.seed, "policy": name,
                         "producer": json.loads(spec.producer()), "engine": args.engine,
                         "position_error_m": val.position_error,
                         "success": val.success, "return": val.episode_return, "steps": val.steps})


def _scenario(env_id: str, args: argparse.Namespace) -> str:
    """The --scenario argument, or the env's paper case (:attr:`paragym.registry.EnvRow.paper_scenario`);
    kept in ``args``."""
    if args.scenario is None:
        args.scenario = registry.row(env_id).paper_scenario
    return args.scenario


def _cmd_policies(args: argparse.Namespace) -> int:
    from paragym.baselines.policies import policies_for

    env_id = paragym.check_env_id(args.env_id)
    for name, spec in policies_for(env_id, args.models).items():
        print(f"{name:24s} {spec.kind:10s} {spec.description}")
    return 0


def _cmd_envs(args: argparse.Namespace) -> int:
    for r in registry.rows():
        print(f"{r.id:40s} {r.summary} [max {r.max_episode_steps} steps]")
    return 0


def _cmd_plan(args: argparse.Namespace) -> int:
    env_id = paragym.check_env_id(args.env_id)
    plan = bench_of(env_id).plan
    if plan is None:
        raise ValueError(f"{env_id} has no offline planner (its task's bench names none)")
    env = gym.make(env_id, scenario=_scenario(env_id, args), render_mode="rgb_array")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = env_id.split("/")[1] + f"_plan_{args.scenario}_seed{args.seed}"
    try:
        return plan(env, args, out, stem)
    finally:
        env.close()


def _cmd_validate(args: argparse.Namespace) -> int:
    env_id = paragym.check_env_id(args.env_id)
    if bench_of(env_id).dynamics is None:
        raise ValueError(f"{env_id} has no dynamic fidelity to execute and validate in (its task's bench names "
                         f"no dynamics)")
    validate_plan = bench_of(env_id).validate_plan
    if args.engine not in paragym.registry.row(env_id).engines:
        raise ValueError(f"--engine {args.engine}: {env_id}'s dynamic fidelity runs in "
                         f"{', '.join(paragym.registry.row(env_id).engines)}")
    if args.policy is not None or validate_plan is None or args.engine != "pybullet":  # a policy's episode
        return _validate_episode(env_id, args)
    env = gym.make(env_id, scenario=_scenario(env_id, args))
    out = Path(args.out)
    stem = env_id.split("/")[1] + f"_{args.scenario}_seed{args.seed}"
    try:
        return validate_plan(env, args, out, stem)
    finally:
        env.close()


def _cmd_export(args: argparse.Namespace) -> int:
    from paragym.envs.export import write

    env_id = paragym.check_env_id(args.env_id)
    if bench_of(env_id).dynamics is None:
        raise ValueError(f"{env_id} has no dynamic fidelity, so no simulated mechanism to export")
    out = args.out or "runs/export/"
    paths, gaps = write(env_id, args.format, out, overwrite=args.overwrite)
    print(f"wrote {', '.join(str(p) for p in paths)}")
    if gaps is None:
        print("not checked: install mujoco (pip install 'paragym[mujoco]') to load the file and compare it")
        return 0
    print(f"loaded in MuJoCo at reset(seed=0): every link frame within {gaps['frame_m']:.1e} m and "
          f"{gaps['frame_rad']:.1e} rad of the simulated tree; loops closed within {gaps['loop_m']:.1e} m")
    return 0 if max(gaps.values()) < 1e-9 else 1


def _cmd_demo(args: argparse.Namespace) -> int:
    from paragym.baselines.policies import get_policy

    env_id = paragym.check_env_id(args.env_id)
    env = gym.make(env_id, scenario=_scenario(env_id, args), render_mode="rgb_array")
    bench = bench_of(env_id)
    from paragym.plots import plot_episode

    best_name, plot = bench.demo, bench.plot_episode or plot_episode
    policy = {"best": lambda: get_policy(env_id, bench.reference).factory(env, args.seed),
              "random": lambda: RandomPolicy(env.action_space, args.seed),
              "zero": lambda: ZeroPolicy(env.action_space)}[args.policy]()
    name = best_name if args.policy == "best" else args.policy
    print(f"{env_id}: {args.scenario} scenario, seed {args.seed}, policy {name}")
    ep = run_episode(env, policy, seed=args.seed, frame_every=args.frame_every if args.gif else 0)
    if not ep.frames:  # the picture's first panel
        ep.frames.append(frame_of(env))
    env.close()
    out = Path(args.out)
    stem = env_id.split("/")[1] + f"_{args.scenario}_seed{args.seed}_{args.policy}"
    png = plot(ep, out / f"{stem}.png")
    end = ep.infos[-1]
    collision = f"  collision {end['collision']}" if "collision" in end else ""
    print(f"steps {len(ep.actions)}  return {ep.episode_return:.3f}  success {end.get('is_success')}{collision}  "
          f"reset+plan {ep.reset_seconds:.2f} s  steps {ep.step_seconds:.2f} s")
    print(f"wrote {png}")
    if args.gif:
        from PIL import Image

        gif = out / f"{stem}.gif"
        frames = [Image.fromarray(f) for f in ep.frames]
        frames[0].save(gif, save_all=True, append_images=frames[1:], duration=80, loop=0)
        print(f"wrote {gif} ({len(frames)} frames)")
    return 0 if args.policy != "best" or end.get("is_success") else 1


def _cmd_train(args: argparse.Namespace) -> int:
    if args.engine != "pybullet" and args.fidelity != "dynamic":
        raise ValueError("--engine is the dynamic fidelity's: give --fidelity dynamic too")
    from paragym.baselines.config import ALGOS

    if args.fidelity != "kinematic" and str(args.algo).lower() not in ALGOS:
        raise ValueError(f"--fidelity dynamic trains {', '.join(ALGOS)} under physics; got {args.algo!r}")
    if args.seeds != 1 or args.sweep or args.ray or args.ray_storage:
        return _train_runs(args)
    if args.algo == "cem":  # a search of linear policies: no PyTorch, no SB3
        from paragym.baselines.cem import CemSettings, train_cem

        if args.timesteps is not None:
            raise ValueError("--timesteps does not apply to cem: it searches for --budget seconds")
        found = train_cem(args.env_id, seed=args.seed, settings=CemSettings(budget_seconds=args.budget,
                                                                                generations=args.generations),
                          models_dir=args.models, force=args.force, echo=None if args.no_progress else print)
        meta = found.meta
        print(f"CEM seed {meta['seed']} on {meta['env_id']}: {meta['generations']} generations, "
              f"{meta['episodes_played']:,} episodes in {meta['train_seconds']:.0f} s; the mean's last generation "
              f"{meta['curve']['mean_success'][-1]:.0%} success")
        if found.model is not None:
            print(f"wrote {found.model} and {found.model.with_suffix('.json').name}")
        return 0
    from paragym.baselines.training import LOADABLE, check_algo, train

    algo = check_algo(args.algo, LOADABLE)
    if algo in ("bc", "dagger") and args.timesteps is not None:
        raise ValueError(f"--timesteps does not apply to {algo}: it learns from "
                         + ("a dataset for a number of epochs" if algo == "bc" else "a number of iterations of "
                            "expert-labelled episodes") + f"; set them in paragym.yml's {algo} section")
    if algo == "bc":  # behaviour cloning of the reference's demonstrations
        from paragym.baselines.bc import train_bc

        res = train_bc(args.env_id, seed=args.seed, models_dir=args.models, threads=args.threads, force=args.force)
        meta = res.meta
        print(f"BC seed {meta['seed']} on {meta['env_id']}: {meta['dataset_steps']:,} steps of "
              f"{meta['dataset_episodes']} episodes ({meta['dataset_id']}, sha256 {meta['dataset_sha256'][:12]}), "
              f"{meta['bc']['epochs']} epochs in "
              f"{meta['train_seconds']:.0f} s; best held-out loss at epoch {meta['best_epoch']}")
        print(f"wrote {res.files.model}, {res.files.meta.name}, {res.files.curve_png.name}")
        return 0
    if algo == "dagger":  # imitation of a feedback expert in the learner's own states
        from paragym.baselines.dagger import train_dagger

        res = train_dagger(args.env_id, seed=args.seed, models_dir=args.models, threads=args.threads,
                           force=args.force, echo=None if args.no_progress else print)
        meta, curve = res.meta, res.meta["curve"]
        print(f"DAgger seed {meta['seed']} on {meta['env_id']}: {len(curve['iteration'])} iterations, "
              f"{meta['pairs']:,} pairs labelled by {meta['expert']} in {meta['train_seconds']:.0f} s; last "
              f"evaluation {curve['eval_success'][-1]:.0%} success")
        print(f"wrote {res.files.model}, {res.files.meta.name}, {res.files.curve_png.name}")
        return 0
    try:
        res = train(args.env_id, args.algo, seed=args.seed, timesteps=args.timesteps, models_dir=args.models,
                    progress_bar=not args.no_progress, threads=args.threads, force=args.force,
                    vectorized=args.vectorized, n_envs=args.n_envs, fidelity=args.fidelity, engine=args.engine)
    except KeyboardInterrupt:
        raise KeyboardInterrupt(f"interrupted: the last checkpoint under {args.models} is kept; run the same "
                                f"command again to resume from it") from None
    meta = res.meta
    if res.skipped:
        print(f"{res.files.model} is already trained for {meta['timesteps']:,} steps (--force retrains)")
        return 0
    curve = meta["curve"]
    last = (f"last evaluation {curve['eval_mean_return'][-1]:.3f} +- {curve['eval_std_return'][-1]:.3f}"
            if curve["eval_mean_return"] else "no evaluation yet")
    resumed = f", resumed at {res.resumed_from:,}" if res.resumed_from else ""
    why = ("PPO learns in whole rollouts" if meta["algo"] == "ppo" else
           f"its {meta['hyperparams']['n_envs']} envs step together")
    whole = f" ({meta['num_timesteps']:,} done: {why})" if meta["num_timesteps"] > meta["timesteps"] else ""
    start = meta["hyperparams"].get("init_from")
    if isinstance(start, dict):
        print(f"started from {start['file']} (sha256 {start['sha256'][:12]})")
    print(f"{meta['algo'].upper()} seed {meta['seed']} on {meta['env_id']}: {meta['timesteps']:,} steps{whole} in "
          f"{meta['train_seconds']:.0f} s{resumed}; {last}")
    print(f"wrote {res.files.model} ({meta['model_bytes'] / 1024:.0f} KiB, {meta['parameters']['policy']:,} "
          f"parameters), {res.files.meta.name}, {res.files.curve_png.name}")
    return 0


def _train_runs(args: argparse.Namespace) -> int:
    """``paragym train --seeds/--sweep/--ray``: several runs, here or as Ray Tune trials."""
    from paragym.baselines.trials import plan_runs, read_sweep, run_all

    if args.ray_storage and not args.ray:
        raise ValueError("--ray-storage is Ray Tune's: give --ray too")
    runs = plan_runs(args.seed, args.seeds, args.models, read_sweep(args.sweep) if args.sweep else None)
    where = f"as Ray Tune trials on {args.ray}" if args.ray else "here, one after the other"
    print(f"{len(runs)} {args.algo.upper()} runs on {args.env_id}, {where}")
    outcomes = run_all(args.env_id, args.algo, runs, timesteps=args.timesteps, threads=args.threads,
                       force=args.force, vectorized=args.vectorized, n_envs=args.n_envs, ray_address=args.ray,
                       storage=args.ray_storage, fidelity=args.fidelity, engine=args.engine)
    for out in outcomes:
        if out.skipped:
            print(f"{out.files.model} is already trained for {out.meta.get('timesteps', 0):,} steps (--force "
                  f"retrains)")
    print(f"{sum(not o.skipped for o in outcomes)} trained, {sum(o.skipped for o in outcomes)} trained before; "
          f"rank them: paragym leaderboard --models {args.models}"
          + (" (a sweep's point: --models <its folder>)" if args.sweep else ""))
    return 0


def _cmd_demos(args: argparse.Namespace) -> int:
    from paragym.baselines.demos import record_demos

    data = record_demos(args.env_id, args.episodes, policy=args.policy, dataset_id=args.dataset_id,
                        force=args.force, progress=not args.no_progress)
    meta = data.storage.metadata
    print(f"{data.total_episodes} episodes, {data.total_steps:,} steps of {meta.get('algorithm_name')}")
    print(f"wrote Minari dataset {meta['dataset_id']} (ref_min_score {meta['ref_min_score']:.3f}, ref_max_score "
          f"{meta['ref_max_score']:.3f}); load it with minari.load_dataset({meta['dataset_id']!r})")
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from paragym.baselines.report import write_report

    page = write_report(args.out, None if args.no_db else args.db, models_dirs=args.models,
                        progress=not args.no_progress)
    print(f"wrote {page} and its pictures in {page.parent}")
    return 0


def _cmd_leaderboard(args: argparse.Namespace) -> int:
    import signal

    from paragym.baselines.leaderboard import FULL, QUICK, run_leaderboard

    asked = []

    def stop(signum: int, frame: Any) -> None:  # SIGTERM stops as Ctrl-C does: workers ended, rows kept
        asked.append(signum)
        raise KeyboardInterrupt

    def still_asked(row: Any) -> None:
        """A stop whose KeyboardInterrupt got lost on the way (a signal while numba compiles may be) still
        stops the run, at the next stored episode."""
        if asked:
            raise KeyboardInterrupt

    for text in args.agent or []:
        _register_agent(text, args.env)
    before = signal.signal(signal.SIGTERM, stop), signal.signal(signal.SIGINT, stop)
    try:
        suite = QUICK if args.quick else FULL
        args.db = args.db if args.db is not None else str(Path(args.out) / "paragym.sqlite")
        run = run_leaderboard(db=args.db, suite=suite if args.episodes is None else suite.with_episodes(args.episodes),
                              env_ids=args.env,
                              policies=args.policy, models_dir=args.models,
                              executor="workers" if args.workers > 1 and args.executor == "local" else args.executor,
                              workers=args.workers, ray_address=args.ray_address, out=args.out,
                              markdown_path=args.markdown, validate=not args.no_validation,
                              progress=not args.no_progress, on_row=still_asked, command=_command(args.argv),
                              resume_from=args.resume_from)
    finally:  # the caller's handlers again (a test or a notebook that called main)
        signal.signal(signal.SIGTERM, before[0])
        signal.signal(signal.SIGINT, before[1])
    print(f"\n{run.new_episodes} episodes run, {run.skipped_episodes} taken from {args.db}; in dynamic fidelity "
          f"{run.new_dynamic} run, {run.skipped_dynamic} taken; {run.seconds:.0f} s")
    print("wrote " + ", ".join(str(p) for p in run.files))
    return 0


def _command(argv: Sequence[str]) -> str:
    """The command as typed, for the results file (the agents' files by name only: no folder of this machine)."""
    import shlex

    shown = [Path(a).name if a.endswith(".py") or ".py:" in a else a for a in argv]
    return "paragym " + shlex.join(shown)


def _cmd_verify(args: argparse.Namespace) -> int:
    from paragym.baselines.leaderboard.results import describe, verify

    for text in args.agent or []:
        _register_agent(text, None, default_envs=_file_envs(args.results))
    sample = None if args.sample == "all" else int(args.sample)
    if sample is not None and sample < 1:
        raise ValueError(f"--sample must be a positive number or 'all'; got {args.sample!r}")
    result = verify(args.results, sample, args.dynamic, args.seed, args.models)
    print(describe(result))
    return 0 if result.ok else 1


def _file_envs(path: str) -> list[str]:
    from paragym.baselines.leaderboard.results import read_results

    return sorted({p["env"] for p in read_results(path)["policies"]})


def _register_agent(text: str, env_ids: list[str] | None, default_envs: list[str] | None = None) -> None:
    """``--agent [NAME=]FILE.py:ATTR`` (or ``module:attr``): register it for the envs of ``--env``, else for the
    ids its ``env_ids`` attribute names."""
    from paragym.baselines.agents import AgentFile, identity, load_agent
    from paragym.baselines.policies import register_policy

    name, factory = load_agent(text)
    envs = env_ids or getattr(factory.target if isinstance(factory, AgentFile) else factory, "env_ids", None) or \
        default_envs
    if not envs:
        raise ValueError(f"--agent {text!r}: name the envs it plays with --env (or give {name} an env_ids "
                         f"attribute listing them)")
    made = identity(factory)
    where = made["policy"]
    for env_id in [envs] if isinstance(envs, str) else envs:
        register_policy(env_id, name, factory, "user",
                        f"your agent {where} (source sha256 {made.get('source_sha256', '?')[:12]})")


SCENARIO_HELP = ("the env's paper case by default, or another of its scenarios: 'random' and the task's own "
                 "(each id's page in the docs; for the mobile tripod, whose paper has three, the default is 'push')")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``paragym`` command."""
    parser = argparse.ArgumentParser(prog="paragym", description=paragym.__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"paragym {paragym.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("envs", help="list the registered environments")
    p.set_defaults(func=_cmd_envs)
    p = sub.add_parser("policies", help="list an environment's policies: references, floors, shipped models "
                                        "(and yours, with --models), by the names the other commands take")
    p.add_argument("env_id", help="e.g. HybridSingularityFree-v2")
    p.add_argument("--models", default=None, help="folder of your own models (listed as user-<algo>-seed<N>)")
    p.set_defaults(func=_cmd_policies)
    p = sub.add_parser("demo", help="run one episode with the best available policy and save a picture")
    p.add_argument("env_id", help="e.g. paragym/CaPaManCollisionFree-v0 (the 'paragym/' may be omitted)")
    p.add_argument("--scenario", default=None, help=SCENARIO_HELP)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--policy", choices=("best", "random", "zero"), default="best")
    p.add_argument("--out", default="runs/demo", help="folder for the PNG (and GIF)")
    p.add_argument("--gif", action="store_true", help="also write an animated GIF of the episode")
    p.add_argument("--frame-every", type=int, default=4, help="GIF: keep a frame every N steps")
    p.set_defaults(func=_cmd_demo)
    task_own = ("after the env id, the options of its task's own (its bench's `options`, e.g. --dt SECONDS); one "
                "the task does not take is refused, naming those it does")
    p = sub.add_parser("plan", help="run the reference planner offline; print its figures and save pictures",
                       epilog=task_own)
    p.add_argument("env_id", help="e.g. CaPaManCollisionFree-v0")
    p.add_argument("--scenario", default=None, help=SCENARIO_HELP)
    p.add_argument("--seed", type=int, default=0, help="scenario (random) and planner seed")
    p.add_argument("--out", default="runs/plan", help="folder for the PNG and the JSON")
    p.set_defaults(func=_cmd_plan)
    p = sub.add_parser("validate", help="execute in the dynamic simulation and validate with the accelerometer "
                                        "array and the Kalman filter: a policy's episode (--policy), or the "
                                        "reference plan where the task's bench has one; print the report, save "
                                        "Figs 8-9", epilog=task_own)
    p.add_argument("env_id", help="e.g. CaPaManCollisionFree-v0")
    p.add_argument("--scenario", default=None, help=SCENARIO_HELP)
    p.add_argument("--seed", type=int, default=0, help="scenario, planner and sensor-noise seed")
    p.add_argument("--policy", default=None,
                   help="validate this policy's episode (a name of `paragym policies ENV`: the reference, a shipped "
                        "model, user-<algo>-seed<N> with --models); without it, the reference plan where the task "
                        "has one (the CaPaMan, the hybrid), else the reference policy's episode")
    p.add_argument("--models", default=None, help="folder of your own models (for --policy user-...)")
    p.add_argument("--engine", default="pybullet", choices=("pybullet", "mujoco"),
                   help="the dynamic fidelity's physics engine (MuJoCo: with the mujoco extra); in MuJoCo the "
                        "policy's episode is validated (the reference's without --policy)")
    p.add_argument("--out", default="runs/validate", help="folder for the pictures and the JSON report")
    p.set_defaults(func=_cmd_validate)
    p = sub.add_parser("export", help="write an env's mechanism as a model file: MJCF (MuJoCo) with its loop "
                                      "closures and motors, or URDF with a loop-closure sidecar (JSON)")
    p.add_argument("env_id", help="e.g. HybridSingularityFree-v2")
    p.add_argument("--format", choices=("mjcf", "urdf"), default="mjcf", help="the model format (default mjcf)")
    p.add_argument("--out", default=None, help="the file to write, or a folder to write <env name>.xml or .urdf "
                                               "in (default runs/export/)")
    p.add_argument("--overwrite", action="store_true", help="replace files that exist (refused without it)")
    p.set_defaults(func=_cmd_export)
    p = sub.add_parser("train", help="train a Stable-Baselines3 agent (needs the 'rl' extra); resumable")
    p.add_argument("env_id", help="e.g. CaPaManCollisionFree-v0")
    p.add_argument("--algo", default="ppo", help="ppo, sac, td3 or tqc (hyper-parameters: baselines/hyperparams/); "
                                                 "bc: behaviour cloning of the dataset `paragym demos` records; "
                                                 "dagger: DAgger with the expert of paragym.yml's dagger section; "
                                                 "cem: a cross-entropy search of linear policies (no PyTorch)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--timesteps", type=int, default=None, help="env steps (default: the yml's n_timesteps)")
    p.add_argument("--models", default="runs/models",
                   help="folder for the trained model (default: %(default)s; the shipped models are read-only)")
    p.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    p.add_argument("--force", action="store_true", help="retrain even if the model exists; ignore checkpoints")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--vectorized", action="store_true",
                   help="train on the env's native vector env (N robots per numpy call)")
    p.add_argument("--n-envs", type=int, default=None, help="copies (robots) to train on (default: the yml's)")
    p.add_argument("--fidelity", choices=("kinematic", "dynamic"), default="kinematic",
                   help="dynamic: train under physics at the leaderboard's settings (in MuJoCo on the native dynamic "
                        "vector env where the task has one, else one env per process), the runs under "
                        "--models/dynamic-<engine>/ (default %(default)s)")
    p.add_argument("--engine", choices=("pybullet", "mujoco"), default="pybullet",
                   help="the dynamic fidelity's engine (default %(default)s)")
    p.add_argument("--seeds", type=int, default=1, metavar="N",
                   help="train seeds --seed .. --seed + N - 1 (default 1), one run each")
    p.add_argument("--sweep", default=None, metavar="FILE.yml",
                   help="a hyper-parameter sweep: YAML of names to lists of values, their grid trained with every "
                        "seed, each point's runs under --models/<point>/ (the training guide)")
    p.add_argument("--ray", default=None, metavar="ADDRESS",
                   help="run each seed and sweep point as a Ray Tune trial: 'local' starts a local Ray, else a "
                        "cluster's address (needs the 'ray' extra; the cluster guide)")
    p.add_argument("--ray-storage", default=None, metavar="DIR|URI",
                   help="Ray Tune's storage, which every node reaches (default: a temporary folder here, for a "
                        "local Ray or one node)")
    p.add_argument("--budget", type=float, default=300.0, help="cem: seconds of search (default %(default)s)")
    p.add_argument("--generations", type=int, default=1000,
                   help="cem: at most this many generations (default %(default)s); a model's JSON says how many it "
                        "ran: that number with --budget inf makes the same model on any machine")
    p.set_defaults(func=_cmd_train)
    p = sub.add_parser("demos", help="record a policy's episodes (default: the reference) as a Minari dataset "
                                     "(needs the 'demos' extra)")
    p.add_argument("env_id", help="e.g. MobileTripodOdometry-v1")
    p.add_argument("--episodes", type=int, default=200, help="episodes to record (default %(default)s)")
    p.add_argument("--policy", default=None, help="a leaderboard policy name (default: the env's reference)")
    p.add_argument("--dataset-id", default=None, help="Minari's id (default paragym/<env>/<policy>-v0)")
    p.add_argument("--force", action="store_true", help="replace a dataset paragym wrote before")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_demos)
    p = sub.add_parser("report", help="learning curves with bootstrap CIs and rliable's aggregate scores, as PNG and "
                                      "markdown (needs the 'report' extra)")
    p.add_argument("--db", default="results/paragym.sqlite",
                   help="the leaderboard's database (default: %(default)s)")
    p.add_argument("--no-db", action="store_true", help="learning curves only")
    p.add_argument("--models", action="append", default=[],
                   help="a folder of your trained models to include beside the shipped ones (repeatable)")
    p.add_argument("--out", default="results/report",
                   help="folder for REPORT.md and its PNGs (default: %(default)s; the repository's committed report "
                        "is in report/, written only when you name it)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_report)
    p = sub.add_parser("verify", help="re-run a sample of a results file's episodes (results.json.gz, written by "
                                      "paragym leaderboard) and say whether they reproduce; exit code 1 if not")
    p.add_argument("results", help="a results file (results.json or results.json.gz)")
    p.add_argument("--sample", default="20", help="episodes to re-run, or 'all' (default %(default)s)")
    p.add_argument("--dynamic", type=int, default=0, help="dynamic-fidelity episodes to re-run too (default 0)")
    p.add_argument("--seed", type=int, default=0, help="which episodes the sample draws (default 0)")
    p.add_argument("--models", default=None, help="the folder of the models the file ranks as user-...")
    p.add_argument("--agent", action="append", metavar="[NAME=]FILE.py:FACTORY",
                   help="an outside agent the file ranks, as given to paragym leaderboard --agent (repeatable)")
    p.set_defaults(func=_cmd_verify)
    p = sub.add_parser("leaderboard", help="evaluate every env x every policy on fixed seeds; resumable; writes "
                                           "LEADERBOARD.md, a CSV and a PNG per env")
    p.add_argument("--quick", action="store_true",
                   help="1 seed x 3 episodes instead of 5 x 10, and the paper case in dynamic fidelity on each task's "
                        "newest id for the references and learned seed 0 instead of 3 episodes for every policy "
                        "(a smoke run: its tables say so)")
    p.add_argument("--episodes", type=int, default=None, metavar="N",
                   help="episodes per evaluation seed (full suite: 10 x 5 seeds; quick: 3 x 1): more give a finer "
                        "noise floor, the smallest difference from #1 a table can tell apart")
    p.add_argument("--db", default=None, help="SQLite results file (default: paragym.sqlite in --out)")
    p.add_argument("--resume-from", default=None, metavar="RESULTS.json.gz",
                   help="first put a results file's episodes into --db (the committed leaderboard/results.json.gz: "
                        "a fresh checkout runs only what it lacks); its digest is checked, and a row is reused only "
                        "where its policy's producer is unchanged")
    p.add_argument("--out", default="results", help="folder for the reports (default %(default)s)")
    p.add_argument("--markdown", default=None, help="where LEADERBOARD.md goes (default: in --out)")
    p.add_argument("--env", action="append", help="only this env (repeatable)")
    p.add_argument("--policy", action="append", help="only this policy name (repeatable)")
    p.add_argument("--models", default=None,
                   help="also rank the models you trained in this folder: paragym train's (as user-<algo>-seed<N>, "
                        "user-dynamic-<engine>-<algo>-seed<N> for --fidelity dynamic's) "
                        "or rl-baselines3-zoo's log folder (as user-<algo>-zoo<run>); the shipped models always "
                        "take part")
    p.add_argument("--agent", action="append", metavar="[NAME=]FILE.py:FACTORY",
                   help="rank your agent: a factory(env, seed) in a Python file (or module:attr) whose policy has "
                        "reset(obs, info) and act(obs, info); it plays the --env ids (or those its env_ids "
                        "attribute lists); named FACTORY unless NAME= is given (repeatable)")
    p.add_argument("--executor", choices=("local", "workers", "ray"), default="local")
    p.add_argument("--workers", type=int, default=min(4, os.cpu_count() or 1),
                   help="processes (a local pool; 1: in this process) or Ray CPUs (default: the cores, at most 4)")
    p.add_argument("--ray-address", default=None, help="a Ray cluster's address (default: start a local Ray)")
    p.add_argument("--no-validation", action="store_true", help="skip the KF validation of the reference plans")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_leaderboard)
    for command in sub.choices.values():  # each value's name in the usage and the help, where not set above
        for action in command._actions:
            if action.metavar is None and action.choices is None and action.dest in METAVARS:
                action.metavar = "FILE|DIR/" if (command.prog, action.dest) == ("paragym export", "out") \
                    else METAVARS[action.dest]
    return parser


#: the name of each option's value in the usage and the help
METAVARS = {"env_id": "ENV_ID", "results": "RESULTS_FILE", "scenario": "NAME", "seed": "N", "out": "DIR",
            "models": "DIR", "policy": "NAME", "frame_every": "N", "timesteps": "T", "threads": "N", "n_envs": "N",
            "budget": "S", "generations": "G", "episodes": "N", "dataset_id": "ID", "db": "FILE", "sample": "N|all",
            "dynamic": "N", "markdown": "FILE", "env": "ID", "workers": "N", "ray_address": "ADDR", "algo": "ALGO"}


#: the commands that take a task's own options (:attr:`paragym.baselines.tasks.Bench.options`)
TASK_OPTIONS = ("plan", "validate")


def synopsis(width: int = 116) -> str:
    """Every command's usage, one after another, as argparse writes it at ``width`` characters (without
    ``-h``): the CLI guide's synopsis, so that the guide lists every command and option the parser takes."""
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    lines = []
    for name, command in commands.items():
        formatter = argparse.HelpFormatter(f"paragym {name}", width=width)
        actions = [a for a in command._actions if not isinstance(a, argparse._HelpAction)]
        formatter.add_usage(None, actions, [], prefix="")
        usage = formatter.format_help().rstrip("\n")
        lines.append(usage + (" [the task's own options]" if name in TASK_OPTIONS else ""))
    return "\n".join(lines)


def _task_options(parser: argparse.ArgumentParser, args: argparse.Namespace, extra: list[str]) -> None:
    """Read the options of the env's task (its bench's ``options``) from what the command's own parser left,
    into ``args``; anything else left is argparse's error, as it would have been."""
    if args.command not in TASK_OPTIONS:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    env_id = paragym.check_env_id(args.env_id)
    own = argparse.ArgumentParser(prog=f"paragym {args.command} {args.env_id}", add_help=False)
    for option in bench_of(env_id).options:
        if args.command in option.commands:
            own.add_argument(option.flag, type=option.type, default=option.default_for(args.command),
                             help=option.help)
    left = own.parse_known_args(extra, namespace=args)[1]
    if left:
        offered = ", ".join(o.option_strings[0] for o in own._actions) or "none"
        raise ValueError(f"{env_id} does not take {' '.join(left)} (its task's options for {args.command}: "
                         f"{offered})")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``paragym`` console script."""
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if extra or args.command in TASK_OPTIONS:
            _task_options(parser, args, extra)
        return args.func(args)
    except KeyboardInterrupt as exc:  # one line, no traceback: what was kept and how to go on
        print(f"\nparagym: {exc}" if str(exc) else "\nparagym: interrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError, FileExistsError) as exc:  # bad input (a file of yours named): plainly, no traceback
        print(f"paragym: error: {exc}", file=sys.stderr)
        return 2
    except (RuntimeError, OSError) as exc:  # a planner that found no path, a GUI without display, a full disk
        print(f"paragym: failed: {exc}", file=sys.stderr)
        return 1
    except sqlite3.Error as exc:  # the results file went bad during the run
        print(f"paragym: failed: the results database: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
