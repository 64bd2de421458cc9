"""DAgger: imitation of an expert in the states the learner visits (``paragym train ENV --algo dagger``).

Behaviour cloning (:mod:`paragym.baselines.bc`) learns from the expert's own
episodes; once the clone drifts off them it meets states no demonstration
covered, and its errors compound (Ross, Gordon and Bagnell, "A reduction of
imitation learning and structured prediction to no-regret online learning",
AISTATS 2011). DAgger asks the expert what it would do in the states the
learner itself reaches, and trains on all the pairs so far:

1. iteration 0: the expert acts for ``episodes`` episodes (this is BC's data);
2. iteration i >= 1: the current policy acts, sampling from its Gaussian (the
   paper's beta_i = 0 for i >= 1), and the expert labels every state visited;
3. after each iteration, the policy is fitted to the aggregate by maximum
   likelihood (:func:`paragym.baselines.bc.fit_policy`, ``epochs`` passes,
   the optimiser carried on from the previous iteration).

The expert must answer in any state, so it is a feedback policy, named in
``paragym.yml``'s ``dagger`` section: for the CaPaMan, ``grid-field``
(:class:`paragym.planners.grid_path.GridFieldPolicy`), the shortest free path
on Theta from wherever the cranks are. Episodes it cannot plan are skipped.

Episodes are seeded 300000 + 10000 x seed + k, apart from the leaderboard's
(100000 + ...), the training evaluations' (10000 + k) and the
demonstrations' (200000 + k). After every iteration the deterministic policy
is evaluated on ``eval_episodes`` episodes seeded 10000 + k; the model saved
is the last iteration's (no pick by evaluation). It is a PPO ``MlpPolicy``
saved as ``dagger_seed<N>.zip`` with its JSON (settings, the curve per
iteration) and a picture of the curve; the leaderboard ranks it as
``dagger-seed<N>``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import paragym.baselines.training as training
from paragym import check_env_id, plots
from paragym.baselines.bc import fit_policy, imitation_run, save_imitation
from paragym.baselines.training import EVAL_SEED, USER_MODELS, TrainResult
from paragym.planners.base import PlanningError

__all__ = ["DAGGER_DEFAULTS", "ROLLOUT_SEED", "Rollout", "fit_dagger", "rollout",
           "train_dagger"]

#: the settings of a DAgger run (``paragym.yml``'s ``dagger`` section overrides them per env)
DAGGER_DEFAULTS: dict[str, Any] = {"expert": None, "iterations": 12, "episodes": 60, "epochs": 10,
                                   "batch_size": 256, "learning_rate": 1e-3, "net_arch": [256, 256],
                                   "log_std_init": -1.0, "eval_episodes": 10}
#: rollout episode k of training seed s is reset with seed ROLLOUT_SEED + 10000 s + k
ROLLOUT_SEED = 300_000


@dataclass
class Rollout:
    """One episode: the observations visited, the expert's action at each
    (the labels), the actions taken, and the success."""

    observations: list[np.ndarray]
    labels: list[np.ndarray]
    actions: list[np.ndarray]
    success: bool


def rollout(env: Any, expert: Any, model: Any, reset_seed: int, expert_acts: bool) -> Rollout | None:
    """One episode from ``reset_seed``, driven by the expert or by ``model``
    (sampling from its Gaussian), labelled by the expert; None if the expert
    cannot plan it."""
    obs, info = env.reset(seed=reset_seed)
    try:
        expert.reset(obs, info)
    except PlanningError:
        return None
    low, high = env.action_space.low, env.action_space.high
    run, done = Rollout([], [], [], False), False
    while not done:
        label = np.clip(expert.act(obs, info), low, high).astype(np.float32)
        action = label if expert_acts else model.predict(obs, deterministic=False)[0]
        run.observations.append(np.array(obs, np.float32))
        run.labels.append(label)
        run.actions.append(np.array(action, np.float32))
        obs, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    run.success = bool(info.get("is_success", False))
    return run


def _evaluate(env: Any, model: Any, episodes: int) -> tuple[float, float]:
    """Success rate and mean return of the deterministic policy on seeds EVAL_SEED + k, as the
    leaderboard plays it (:class:`paragym.baselines.policies.LearnedPolicy`, this round's weights)."""
    from paragym.baselines.policies import LearnedPolicy
    from paragym.rollout import run_episode

    policy = LearnedPolicy(model)
    runs = [run_episode(env, policy, EVAL_SEED + k) for k in range(episodes)]
    return float(np.mean([r.success for r in runs])), float(np.mean([r.episode_return for r in runs]))


def fit_dagger(env_id: str, seed: int, settings: dict[str, Any], threads: int = 1,
               echo: Any = None) -> tuple[Any, dict[str, Any]]:
    """The DAgger-trained PPO model and its metadata (module docstring)."""
    import gymnasium as gym
    import torch
    from stable_baselines3 import PPO

    from paragym.baselines.policies import get_policy

    env_id = check_env_id(env_id)
    hp = {**DAGGER_DEFAULTS, **settings}
    if not hp["expert"]:
        raise ValueError(f"DAgger needs a feedback expert for {env_id}: set `expert` in paragym.yml's dagger "
                         f"section (a policy name of `paragym policies {env_id}`)")
    for key in ("iterations", "episodes", "epochs", "eval_episodes"):
        if not (isinstance(hp[key], int) and hp[key] >= 1):
            raise ValueError(f"dagger setting {key} must be an integer >= 1; got {hp[key]!r}")
    torch.manual_seed(seed)
    torch.set_num_threads(int(threads))
    env = gym.make(env_id)
    expert_spec = get_policy(env_id, hp["expert"])
    expert = expert_spec.factory(env, seed)
    model = PPO("MlpPolicy", env, seed=seed, device="cpu",
                policy_kwargs={"net_arch": list(hp["net_arch"]), "log_std_init": float(hp["log_std_init"])})
    optimiser = torch.optim.Adam(model.policy.parameters(), lr=float(hp["learning_rate"]))
    rng = np.random.default_rng(seed)
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    curve: dict[str, list[float]] = {"iteration": [], "pairs": [], "rollout_success": [], "eval_success": [],
                                     "eval_mean_return": [], "seconds": []}
    skipped, k, t0 = [], 0, time.perf_counter()
    for it in range(int(hp["iterations"])):
        done_episodes, succ = 0, []
        while done_episodes < int(hp["episodes"]):
            reset_seed = ROLLOUT_SEED + 10_000 * seed + k
            k += 1
            run = rollout(env, expert, model, reset_seed, it == 0)
            if run is None:
                skipped.append(reset_seed)
                continue
            xs += run.observations
            ys += run.labels
            succ.append(run.success)
            done_episodes += 1
        x, y = np.stack(xs), np.stack(ys)
        fit_policy(model.policy, x, y, x[:0], y[:0], hp, rng, optimiser)
        success, mean_return = _evaluate(env, model, int(hp["eval_episodes"]))
        for key, value in (("iteration", it), ("pairs", len(xs)), ("rollout_success", float(np.mean(succ))),
                           ("eval_success", success), ("eval_mean_return", mean_return),
                           ("seconds", time.perf_counter() - t0)):
            curve[key].append(value)
        if echo is not None:
            echo(f"iteration {it}: {len(xs):,} pairs; {'expert' if it == 0 else 'policy'} rollouts succeed "
                 f"{np.mean(succ):.0%}; evaluation {success:.0%}, return {mean_return:.2f}")
    env.close()
    meta = {"expert": hp["expert"], "expert_producer": expert_spec.producer(), "dagger": hp,
            "pairs": len(xs), "episodes": k - len(skipped),
            "skipped_seeds": skipped, "train_seconds": time.perf_counter() - t0, "curve": curve}
    return model, meta


def train_dagger(env_id: str, seed: int = 0, models_dir: str | Path = USER_MODELS, threads: int = 1,
                 force: bool = False, overrides: dict[str, Any] | None = None, echo: Any = None) -> TrainResult:
    """DAgger (module docstring) on ``env_id`` with the settings of
    ``paragym.yml``'s ``dagger`` section and ``overrides``, saved where
    :func:`paragym.baselines.training.train` saves; an existing model is
    replaced only with ``force``."""
    env_id = check_env_id(env_id)
    settings, files = imitation_run(env_id, "dagger", seed, models_dir, force, overrides)
    model, meta = fit_dagger(env_id, seed, settings, threads, echo)
    meta = save_imitation(files, env_id, "dagger", seed, threads, model, meta)
    plots.plot_imitation_curve("dagger", meta["curve"], files.curve_png,
                               f"DAgger seed {seed} on {training.env_name(env_id)}, expert {meta['expert']}")
    return TrainResult(files, model, meta)
