"""Behaviour cloning from the reference's demonstrations (``paragym train ENV --algo bc``).

The ``imitation`` library pins gymnasium 0.29 and Stable-Baselines3 2.2,
older than paragym's, so this is SB3 policy pretraining, written out: an SB3
PPO ``MlpPolicy`` (the PPO baselines' network) fitted to the actions of a
Minari dataset (:func:`paragym.baselines.demos.record_demos`) by maximum
likelihood (the Gaussian's log-probability of the expert's action, clipped
to the action space), with Adam over mini-batches. A tenth of the episodes
is held out; the epoch with the lowest held-out loss is kept.

The model is saved as a PPO file named ``bc_seed<N>.zip`` (it loads as any
PPO model, without unpickling; a PPO run could start from it), with its JSON
(the dataset, its size, the settings, the loss per epoch) and a picture of
the loss curve, where ``paragym train`` writes. The leaderboard ranks it as
the learned policy ``bc-seed<N>``.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

import paragym.baselines.training as training
from paragym import check_env_id, plots
from paragym.baselines.demos import dataset_id_for, reference_name
from paragym.baselines.training import USER_MODELS, TrainResult

__all__ = ["BC_DEFAULTS", "fit_bc", "fit_policy", "imitation_run", "load_demonstrations", "save_imitation", "train_bc"]

#: the settings of a BC run (``paragym.yml``'s ``bc`` section overrides them per env)
BC_DEFAULTS: dict[str, Any] = {"epochs": 60, "batch_size": 256, "learning_rate": 1e-3, "net_arch": [64, 64],
                               "log_std_init": -1.0, "holdout": 0.1}


def load_demonstrations(dataset_id: str, env_id: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any]:
    """The observations (M, obs), actions (M, act) and episode index (M,) of
    every step of the Minari dataset ``dataset_id``, and the dataset; a
    ValueError says how to record a missing one."""
    import minari

    if dataset_id not in minari.list_local_datasets():
        policy = dataset_id.rsplit("/", 1)[-1].rsplit("-v", 1)[0]  # paragym/<env>/<policy>-v0: whose episodes
        raise ValueError(f"no Minari dataset {dataset_id}: record it first with "
                         f"`paragym demos {env_id} --episodes 200 --policy {policy}`")
    data = minari.load_dataset(dataset_id)
    obs, act, index = [], [], []
    for k, ep in enumerate(data.iterate_episodes()):
        obs.append(np.asarray(ep.observations)[:-1])
        act.append(np.asarray(ep.actions))
        index.append(np.full(len(ep.actions), k))
    return np.concatenate(obs), np.concatenate(act), np.concatenate(index), data


def fit_bc(env_id: str, dataset_id: str, seed: int, settings: dict[str, Any], threads: int = 1,
           progress_bar: bool = False) -> tuple[Any, dict[str, Any]]:
    """The cloned PPO model and its metadata (module docstring)."""
    import gymnasium as gym
    import torch
    from stable_baselines3 import PPO

    env_id = check_env_id(env_id)
    hp = {**BC_DEFAULTS, **settings}
    obs, act, index, data = load_demonstrations(dataset_id, env_id)
    env = gym.make(env_id)
    low, high = env.action_space.low, env.action_space.high
    act = np.clip(act, low, high)
    torch.manual_seed(seed)
    torch.set_num_threads(int(threads))
    model = PPO("MlpPolicy", env, seed=seed, device="cpu",
                policy_kwargs={"net_arch": list(hp["net_arch"]), "log_std_init": float(hp["log_std_init"])})
    env.close()
    rng = np.random.default_rng(seed)
    episodes = rng.permutation(int(index.max()) + 1)
    held = set(episodes[:max(1, int(round(hp["holdout"] * len(episodes))))].tolist()) if len(episodes) > 1 else set()
    test = np.isin(index, list(held))
    t0 = time.perf_counter()
    curve = fit_policy(model.policy, obs[~test], act[~test], obs[test], act[test], hp, rng)
    seconds = time.perf_counter() - t0
    digest = hashlib.sha256(np.ascontiguousarray(obs, np.float64).tobytes())
    digest.update(np.ascontiguousarray(act, np.float64).tobytes())
    meta = {"dataset_id": dataset_id, "dataset_sha256": digest.hexdigest(),  # of what was learned: obs and actions
            "dataset_episodes": int(data.total_episodes), "dataset_steps": int(len(obs)),
            "holdout_episodes": sorted(int(e) for e in held), "bc": hp, "train_seconds": seconds,
            "best_epoch": int(np.argmin(curve["holdout_loss"]) + 1), "curve": curve}
    return model, meta


def fit_policy(policy: Any, x: np.ndarray, y: np.ndarray, x_held: np.ndarray, y_held: np.ndarray,
               hp: dict[str, Any], rng: np.random.Generator, optimiser: Any = None) -> dict[str, list[float]]:
    """Fit the SB3 ``policy`` to the actions ``y`` at observations ``x`` by
    maximum likelihood (module docstring), ``hp["epochs"]`` passes of Adam
    over mini-batches of ``hp["batch_size"]``; keep the weights of the epoch
    with the lowest loss on the held-out pairs (on the training pairs if there
    are none). Returns the loss per epoch."""
    import torch

    x_t, y_t = torch.as_tensor(x, dtype=torch.float32), torch.as_tensor(y, dtype=torch.float32)
    xh, yh = torch.as_tensor(x_held, dtype=torch.float32), torch.as_tensor(y_held, dtype=torch.float32)
    optimiser = optimiser or torch.optim.Adam(policy.parameters(), lr=float(hp["learning_rate"]))

    def loss_of(xb: torch.Tensor, yb: torch.Tensor) -> torch.Tensor:
        return -policy.get_distribution(xb).log_prob(yb).mean()

    curve: dict[str, list[float]] = {"epoch": [], "train_loss": [], "holdout_loss": []}
    best, best_state = np.inf, None
    batch = int(hp["batch_size"])
    for epoch in range(int(hp["epochs"])):
        policy.set_training_mode(True)
        order = torch.as_tensor(rng.permutation(len(x_t)))
        total = 0.0
        for start in range(0, len(x_t), batch):
            idx = order[start:start + batch]
            loss = loss_of(x_t[idx], y_t[idx])
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += float(loss.detach()) * len(idx)
        policy.set_training_mode(False)
        with torch.no_grad():
            held_loss = float(loss_of(xh, yh)) if len(xh) else total / len(x_t)
        curve["epoch"].append(epoch + 1)
        curve["train_loss"].append(total / len(x_t))
        curve["holdout_loss"].append(held_loss)
        if held_loss < best:
            best, best_state = held_loss, {k: v.clone() for k, v in policy.state_dict().items()}
    if best_state is not None:
        policy.load_state_dict(best_state)
    return curve


def train_bc(env_id: str, seed: int = 0, models_dir: str | Path = USER_MODELS, threads: int = 1, force: bool = False,
             overrides: dict[str, Any] | None = None) -> TrainResult:
    """Behaviour cloning (module docstring) of ``env_id``'s reference from its
    Minari dataset (``dataset_id`` in ``overrides`` to use another), with the
    settings of ``paragym.yml``'s ``bc`` section and ``overrides``, saved
    where :func:`paragym.baselines.training.train` saves; an existing model
    is replaced only with ``force``."""
    env_id = check_env_id(env_id)
    settings, files = imitation_run(env_id, "bc", seed, models_dir, force, overrides)
    dataset_id = settings.pop("dataset_id", None) or dataset_id_for(env_id, reference_name(env_id))
    model, meta = fit_bc(env_id, dataset_id, seed, settings, threads)
    meta = save_imitation(files, env_id, "bc", seed, threads, model, meta)
    plots.plot_imitation_curve("bc", meta["curve"], files.curve_png,
                               f"BC seed {seed} on {training.env_name(env_id)} from {dataset_id} "
                               f"({meta['dataset_episodes']} episodes)")
    return TrainResult(files, model, meta)


def imitation_run(env_id: str, algo: str, seed: int, models_dir: str | Path, force: bool,
                  overrides: dict[str, Any] | None) -> tuple[dict[str, Any], training.RunFiles]:
    """The settings of an imitation run (``paragym.yml``'s ``algo`` section
    for ``env_id``, then ``overrides``) and its files; a ValueError if its
    model exists and not ``force``."""
    table = training.hyperparams_table("paragym.yml").get(algo) or {}
    settings = {**(table.get(env_id) or {}), **(overrides or {})}
    files = training.run_files(env_id, algo, seed, training.writable_models_dir(models_dir))
    if files.model.exists() and not force:
        raise ValueError(f"{files.model} exists; --force retrains it over that file, or choose another --models "
                         f"folder or --seed")
    return settings, files


def save_imitation(files: training.RunFiles, env_id: str, algo: str, seed: int, threads: int, model: Any,
                   meta: dict[str, Any]) -> dict[str, Any]:
    """Save an imitation run's model and its JSON (``meta`` with the run's
    identity, versions, machine and size); returns the JSON's content."""
    meta = {"env_id": env_id, "algo": algo, "seed": seed, **meta, "versions": training.versions(),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, torch threads {threads}",
            "parameters": training.count_parameters(model)}
    files.model.parent.mkdir(parents=True, exist_ok=True)
    model.save(files.model)
    meta["model_bytes"] = files.model.stat().st_size
    training.write_atomic(files.meta, json.dumps(meta, indent=1))
    return meta
