"""Train Stable-Baselines3 agents on the paragym envs (``paragym train``).

The run is here; its parts are in modules of their own: the hyper-parameters
(:mod:`paragym.baselines.config`), the run's files (:mod:`paragym.baselines.run_files`) and loading a model
(:mod:`paragym.baselines.loading`).

Hyper-parameters come from ``hyperparams/<algo>.yml`` keyed by env id, in
rl-baselines3-zoo's format (``python -m rl_zoo3.train ... -conf
hyperparams/ppo.yml`` reads the same files), and paragym's own keys from
``hyperparams/paragym.yml``. A run writes, under ``<models_dir>/<env name>/``
(default ``runs/models``; never the shipped models, which are read-only
package data):

* ``<algo>_seed<N>.zip``: the final model (SB3's format: weights, optimiser
  state, hyper-parameters);
* ``<algo>_seed<N>.json``: the run's config, versions, wall time, network
  size and its training curve (periodic evaluations on fixed seeds, and the
  return of every training episode);
* ``<algo>_seed<N>.png``: the curve as a picture;
* ``checkpoints/<algo>_seed<N>/`` while it runs: the latest model (and replay
  buffer for SAC/TD3) and the curve so far, written atomically every
  ``checkpoint_freq`` steps. A run started again with the same arguments
  resumes from there (the env's random streams restart, so a resumed run is
  a continuation, not a bit-identical replay); the folder goes when the run
  completes. Resuming loads the checkpoint with SB3's own ``load``, which
  unpickles it: resume only from checkpoints you made. (Evaluating a model,
  :func:`load_model`, unpickles nothing.)

A finished model is never overwritten without ``force``: the same command
again says it is done, another ``timesteps`` is refused.

Everything runs on the CPU; ``threads`` (default 1) caps torch's threads so
that two runs share a 2-core machine without contention.
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

from paragym import check_env_id, registry

# the names the training's parts had when they were all here: one module each now, imported for training's
# callers as before
from paragym.baselines.config import (  # noqa: F401
    ALGOS,
    OWN_KEYS,
    PARAGYM_KEYS,
    _read_config,
    check_algo,
    hyperparams_table,
    load_hyperparams,
    reward_normalization,
)
from paragym.baselines.loading import LOADABLE, _algorithm, load_model, model_algorithm  # noqa: F401
from paragym.baselines.run_files import (  # noqa: F401
    USER_MODELS,
    RunFiles,
    TrainResult,
    _finished_run,
    _save_run,
    count_parameters,
    env_name,
    fidelity_dir,
    run_files,
    versions,
    writable_models_dir,
    write_atomic,
)
from paragym.models import shipped_models_dir, shipped_models_folder

__all__ = ["ALGOS", "EVAL_SEED", "RunFiles", "TrainResult", "load_hyperparams", "run_files", "train"]

#: the evaluation env during training is seeded from here (the leaderboard uses other seeds)
EVAL_SEED = 10_000


def _make_vec(env_id: str, n_envs: int, seed: int, vec_env: str, env_kwargs: dict[str, Any]) -> Any:
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    if vec_env not in ("dummy", "subproc"):
        raise ValueError(f"vec_env must be 'dummy', 'subproc' or 'native'; got {vec_env!r}")
    cls = SubprocVecEnv if vec_env == "subproc" and n_envs > 1 else DummyVecEnv
    return make_vec_env(env_id, n_envs=n_envs, seed=seed, vec_env_cls=cls, env_kwargs=env_kwargs)


def _make_callbacks(hp: dict[str, Any], eval_env: Any, n_envs: int, ckpt: Path, curve: dict[str, list],
                    off_policy: bool) -> list[Any]:
    """An EvalCallback that records each evaluation in ``curve``, a callback
    that records training episodes and writes the checkpoint."""
    from stable_baselines3.common.callbacks import BaseCallback, EvalCallback

    done_before = curve["eval_seconds"][-1] if curve["eval_seconds"] else 0.0  # a resumed run's wall time so far
    start = time.perf_counter()

    class RecordEvaluation(BaseCallback):
        def _on_step(self) -> bool:
            parent = self.parent
            curve["eval_timesteps"].append(int(self.num_timesteps))
            curve["eval_seconds"].append(done_before + time.perf_counter() - start)  # wall-clock of learning
            last = np.asarray(parent.evaluations_results[-1], float)
            curve["eval_mean_return"].append(float(last.mean()))
            curve["eval_std_return"].append(float(last.std()))
            succ = parent.evaluations_successes[-1] if parent.evaluations_successes else []
            curve["eval_success_rate"].append(float(np.mean(succ)) if len(succ) else None)
            return True

    class RecordAndCheckpoint(BaseCallback):
        def __init__(self, every: int) -> None:
            super().__init__()
            self.every, self.last_saved = every, 0

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", ()):
                if "episode" in info:
                    curve["train_timesteps"].append(int(self.num_timesteps))
                    curve["train_return"].append(float(info["episode"]["r"]))
            if self.num_timesteps - self.last_saved >= self.every:
                self.save()
            return True

        def save(self) -> None:
            ckpt.mkdir(parents=True, exist_ok=True)
            self.model.save(ckpt / "latest.tmp.zip")
            if off_policy:
                self.model.save_replay_buffer(ckpt / "replay_buffer.tmp.pkl")
                os.replace(ckpt / "replay_buffer.tmp.pkl", ckpt / "replay_buffer.pkl")
            os.replace(ckpt / "latest.tmp.zip", ckpt / "latest.zip")
            venv = self.model.get_env()
            if hasattr(venv, "ret_rms"):  # VecNormalize: its running return statistics
                venv.save(str(ckpt / "vecnormalize.pkl"))
            write_atomic(ckpt / "curve.json", json.dumps({"num_timesteps": int(self.num_timesteps), **curve}))
            self.last_saved = self.num_timesteps

    eval_cb = EvalCallback(eval_env, n_eval_episodes=int(hp["n_eval_episodes"]),
                           eval_freq=max(1, int(hp["eval_freq"]) // n_envs), deterministic=True, verbose=0,
                           log_path=str(ckpt), callback_after_eval=RecordEvaluation())
    return [eval_cb, RecordAndCheckpoint(int(hp.get("checkpoint_freq", hp["eval_freq"])))]


def train(env_id: str, algo: str, seed: int = 0, timesteps: int | None = None, models_dir: str | Path = USER_MODELS,
          progress_bar: bool = True, threads: int = 1, force: bool = False, verbose: int = 0,
          hyperparams: dict[str, Any] | None = None, callbacks: list[Any] | None = None,
          vectorized: bool = False, n_envs: int | None = None, fidelity: str = "kinematic",
          engine: str = "pybullet") -> TrainResult:
    """Train ``algo`` on ``env_id`` with ``seed`` for ``timesteps`` env steps
    (default: the yml's ``n_timesteps``) and save the model, its JSON and its
    curve under ``models_dir`` (default ``runs/models``; the shipped models'
    folder is refused). A finished run with the same timesteps is returned
    as it is (``skipped``) and one with other timesteps is refused, unless
    ``force``; an interrupted one resumes from its checkpoint. ``hyperparams`` override the yml's entries; ``callbacks``
    (SB3 callbacks) run beside paragym's own. ``vectorized`` trains on the
    env's native vector env (:func:`paragym.baselines.sb3_vec.as_sb3_vecenv`)
    instead of one env per copy (also when paragym.yml says ``vec_env:
    native``); ``n_envs`` overrides the yml's number of copies (robots).
    ``fidelity="dynamic"`` trains under physics in ``engine`` ("pybullet" or "mujoco") at the leaderboard's
    settings (:func:`paragym.baselines.tasks.dynamic_kwargs`), one env per copy in processes of
    their own (at most the machine's cores unless ``n_envs`` says), evaluated there too, and writes under
    ``models_dir/dynamic-<engine>/`` (:func:`~paragym.baselines.run_files.fidelity_dir`).

    The steps, as rl-baselines3-zoo's ExperimentManager takes them: read the
    config (:func:`_read_config`), check what is on disk
    (:func:`_finished_run`), make the envs (:func:`_make_envs`), build or
    resume the model (:func:`_build_model`), learn (:func:`_learn`), save
    (:func:`_save_run`)."""
    import torch

    env_id, algo = check_env_id(env_id), check_algo(algo)
    if not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer; got {seed!r}")
    folder = fidelity_dir(writable_models_dir(models_dir), fidelity, engine)
    hp, total = _read_config(env_id, algo, timesteps, hyperparams, n_envs)
    # MuJoCo's dynamics on a native vector env (MuJoCo alone, every robot stepped at once), else one env per process
    native_dynamic = fidelity == "dynamic" and engine == "mujoco" and "dynamic" in registry.row(
        env_id).vector_fidelities
    if fidelity == "dynamic" and n_envs is None and not native_dynamic:  # one env per process, as many as cores
        hp["n_envs"] = min(hp["n_envs"], os.cpu_count() or 1)
    vectorized = bool(vectorized) or (hp.get("vec_env") == "native" and fidelity == "kinematic") or native_dynamic
    if vectorized and fidelity == "dynamic" and not native_dynamic:
        raise ValueError(f"{env_id} has no native vector env in the dynamic fidelity of {engine}: train it without "
                         "--vectorized (one env per process)")
    files = run_files(env_id, algo, seed, folder)
    done = _finished_run(files, algo, total, force)
    if done is not None:
        return done
    torch.set_num_threads(int(threads))
    env, eval_env = _make_envs(env_id, hp, int(seed), vectorized, files, force, fidelity, engine)
    model, curve, resumed_from = _build_model(algo, hp, env, int(seed), verbose, files, force)
    own = _make_callbacks(hp, eval_env, int(hp["n_envs"]), files.checkpoints, curve, algo != "ppo")
    learned, seconds = _learn(model, algo, int(hp["n_envs"]), total - resumed_from, resumed_from == 0,
                              own + list(callbacks or []), progress_bar)
    env.close()
    eval_env.close()
    meta = {
        "env_id": env_id, "algo": algo, "seed": int(seed), "timesteps": total, "resumed_from": resumed_from,
        "num_timesteps": int(model.num_timesteps),
        "vectorized": bool(vectorized), "fidelity": fidelity, "engine": engine if fidelity == "dynamic" else None,
        "hyperparams": hp, "train_seconds": seconds, "steps_per_second": learned / seconds if seconds else None,
        "parameters": count_parameters(model),
        "versions": versions(), "machine": f"{platform.machine()}, {os.cpu_count()} cores, torch threads {threads}",
        "curve": curve,
    }
    _save_run(files, model, meta, f"{algo.upper()} seed {seed} on {env_name(env_id)}: {total:,} steps, "
                                   f"{seconds / 60:.1f} min")
    return TrainResult(files, model, meta, resumed_from=resumed_from)


def _make_envs(env_id: str, hp: dict[str, Any], seed: int, vectorized: bool, files: RunFiles,
               force: bool, fidelity: str = "kinematic", engine: str = "pybullet") -> tuple[Any, Any]:
    """The training env (``n_envs`` copies, or the native vector env) and the
    evaluation env (one robot, wrapped as the training env is), with reward
    normalisation for learning only when the yml asks for it; in the dynamic fidelity the native vector env
    (MuJoCo alone) where ``vectorized``, else each copy in a process of its own."""
    n_envs, env_kwargs = hp["n_envs"], dict(hp.get("env_kwargs") or {})
    vec_env = hp.get("vec_env", "dummy")
    if fidelity == "dynamic":
        from paragym.baselines.tasks import dynamic_kwargs

        env_kwargs.update(dynamic_kwargs(env_id, engine))
        vec_env = "subproc"
    if vectorized:
        from stable_baselines3.common.vec_env import VecMonitor

        import paragym.baselines.sb3_vec as sb3_vec

        if registry.row(env_id).vector_entry_point is None:
            raise ValueError(f"{env_id} has no native vector env yet; train without --vectorized")
        env = VecMonitor(sb3_vec.as_sb3_vecenv(env_id, n_envs, **env_kwargs))
        env.seed(seed)
        # evaluated on one robot of the native env, wrapped as the training env is (SB3 syncs the two wrapper chains)
        eval_env = VecMonitor(sb3_vec.as_sb3_vecenv(env_id, 1, **env_kwargs))
        eval_env.seed(EVAL_SEED)
    else:
        env = _make_vec(env_id, n_envs, seed, vec_env, env_kwargs)
        eval_env = _make_vec(env_id, 1, EVAL_SEED, "dummy", env_kwargs)
    normalize = reward_normalization(hp)
    if normalize is not None:  # scale the rewards for learning only: the policy sees raw observations
        from stable_baselines3.common.vec_env import VecNormalize

        stats = files.checkpoints / "vecnormalize.pkl"
        env = (VecNormalize.load(str(stats), env) if stats.exists() and not force else
               VecNormalize(env, **{"gamma": float(hp.get("gamma", 0.99)), **normalize}))
        # the same wrapper, inert, on the evaluation env (EvalCallback syncs the two): raw returns
        eval_env = VecNormalize(eval_env, training=False, norm_obs=False, norm_reward=False)
    return env, eval_env


def console_logger(verbose: int = 0) -> Any:
    """An SB3 logger that prints (``verbose`` >= 1) and writes no file. SB3's default makes an empty
    ``SB3-<date>`` folder in the temp dir at every ``learn``; give models this one (``model.set_logger``)."""
    import sys

    from stable_baselines3.common.logger import HumanOutputFormat, Logger

    return Logger(folder=None, output_formats=[HumanOutputFormat(sys.stdout)] if verbose >= 1 else [])


def _build_model(algo: str, hp: dict[str, Any], env: Any, seed: int, verbose: int, files: RunFiles,
                 force: bool) -> tuple[Any, dict[str, list], int]:
    """The model (resumed from its checkpoint, with its replay buffer and its
    curve so far, unless ``force``), the curve and the timesteps it resumed from."""
    model, curve, start = _model_and_curve(algo, hp, env, seed, verbose, files, force)
    model.set_logger(console_logger(verbose))
    return model, curve, start


def _model_and_curve(algo: str, hp: dict[str, Any], env: Any, seed: int, verbose: int, files: RunFiles,
                     force: bool) -> tuple[Any, dict[str, list], int]:
    curve: dict[str, list] = {k: [] for k in ("eval_timesteps", "eval_seconds", "eval_mean_return", "eval_std_return",
                                              "eval_success_rate", "train_timesteps", "train_return")}
    cls, latest = _algorithm(algo), files.checkpoints / "latest.zip"
    if latest.exists() and (files.checkpoints / "curve.json").exists() and not force:
        model = cls.load(latest, env=env, device="cpu")
        if algo in ("sac", "td3", "tqc") and (files.checkpoints / "replay_buffer.pkl").exists():
            model.load_replay_buffer(files.checkpoints / "replay_buffer.pkl")
        saved = json.loads((files.checkpoints / "curve.json").read_text())
        for key in curve:
            curve[key] = list(saved.get(key, []))
        start = files.checkpoints / "init_from.json"
        if hp.get("init_from") and start.is_file():  # what the first start of this run began from
            hp["init_from"] = json.loads(start.read_text())
        return model, curve, int(model.num_timesteps)
    kwargs = {k: v for k, v in hp.items() if k not in PARAGYM_KEYS and k != "policy"}
    if "noise_type" in hp or algo == "td3":  # rl-zoo's keys; only its Gaussian noise here
        from stable_baselines3.common.noise import NormalActionNoise

        if hp.get("noise_type", "normal") != "normal":
            raise ValueError(f"noise_type must be 'normal'; got {hp['noise_type']!r}")
        dim = env.action_space.shape[0]
        kwargs["action_noise"] = NormalActionNoise(np.zeros(dim), float(hp.get("noise_std", 0.1)) * np.ones(dim))
    model = cls(hp["policy"], env, seed=seed, device="cpu", verbose=verbose, **kwargs)
    if hp.get("init_from"):
        hp["init_from"] = _initialise_from(model, algo, hp["init_from"], files)
        files.checkpoints.mkdir(parents=True, exist_ok=True)
        write_atomic(files.checkpoints / "init_from.json", json.dumps(hp["init_from"]))
    return model, curve, 0


def _initialise_from(model: Any, algo: str, source: str | dict[str, Any], files: RunFiles) -> dict[str, Any]:
    """Start ``model``'s policy from a behaviour-cloned one (paragym.yml's
    ``init_from: bc``): the ``bc_seed<N>.zip`` of this run's models folder if
    there is one, else the shipped one; its weights but not its action noise
    (log_std stays the yml's). PPO only: the cloned policy is a PPO policy.
    Returns what it started from (``kind``, ``file``, ``sha256``), for the
    model's JSON, and says it on the console."""
    if isinstance(source, dict):  # resumed: the record of the first start
        return source
    if source != "bc" or algo != "ppo":
        raise ValueError(f"init_from must be 'bc' and the algorithm PPO; got {source!r} for {algo}")
    seed = files.model.stem.rsplit("seed", 1)[1]
    own = files.model.parent / f"bc_seed{seed}.zip"
    shipped = shipped_models_folder(f"paragym/{files.model.parent.name}") / "bc_seed0.zip"
    path = own if own.is_file() else shipped
    if not path.is_file():
        raise ValueError(f"init_from: bc needs a cloned policy ({own} or {shipped}): paragym train "
                         f"{files.model.parent.name} --algo bc")
    cloned = load_model(path, "bc").policy.state_dict()
    state = model.policy.state_dict()
    state.update({k: v for k, v in cloned.items() if k != "log_std"})
    model.policy.load_state_dict(state)
    from paragym.baselines.agents import sha256_of_file

    shown = f"shipped: {path.relative_to(shipped_models_dir().parent)}" if path == shipped else str(path)
    made = {"kind": "bc", "file": shown, "sha256": sha256_of_file(path)}
    print(f"PPO starts from the behaviour clone {shown} (sha256 {made['sha256'][:12]}; paragym.yml's init_from)")
    return made


def _learn(model: Any, algo: str, n_envs: int, remaining: int, fresh: bool, callbacks: list[Any],
           progress_bar: bool) -> tuple[int, float]:
    """Learn the ``remaining`` timesteps (PPO in whole rollouts of n_steps x
    n_envs: what it will do); returns the timesteps asked for and the seconds."""
    import warnings

    # the evaluation env is plain on purpose (raw returns, one robot); SB3 warns when the types differ
    warnings.filterwarnings("ignore", message="Training and eval env are not of the same type")
    remaining = max(0, remaining)
    if algo == "ppo":
        rollout = int(model.n_steps) * n_envs
        remaining = -(-remaining // rollout) * rollout
    t0 = time.perf_counter()
    if remaining:
        model.learn(remaining, callback=callbacks, progress_bar=progress_bar, reset_num_timesteps=fresh)
    return remaining, time.perf_counter() - t0


