"""A derivative-free search of a linear policy: the cross-entropy method (CEM), as a built-in learner.

A reviewer's first check of a new benchmark's hard task is a cheap one: a constant action, a rule read from the
observation, a few minutes of black-box search over linear policies (Mania, Guy and Recht, "Simple random search
provides a competitive approach to reinforcement learning", 2018). A rung that such a search solves is not hard,
whatever PPO does on it; this module makes the search a learner the leaderboard ranks beside PPO and BC.

The policy is ``a = clip(W obs + b)`` to the action space's bounds (W (actions, observations), b (actions,), float32),
acted through :class:`paragym.baselines.actor.MlpActor` as a one-layer network: the same bits on every CPU, no
PyTorch. The search keeps a Gaussian over (W, b), diagonal, starting at zero with standard deviation
``init_std / sqrt(observations)`` for W and ``init_std`` for b. Each generation:

1. draws ``population - 1`` candidates from it; candidate 0 is its mean (so the curve is the mean's);
2. plays every candidate on the same ``episodes`` episodes (reset seeds of the generation, disjoint from the
   leaderboard's 100000 and up) in one native vector env of ``population * episodes`` robots, each robot's first
   episode counted;
3. ranks the candidates by successes, then by mean return, and refits the Gaussian to the best ``elite`` share
   (mean and standard deviation), adding ``noise`` to the deviation so the search does not collapse.

It stops after ``budget_seconds`` of wall time or ``generations`` generations, whichever comes first, and the
policy is the last mean. Files, beside the other learners' under ``models/<env>/``: ``cem_seed<N>.npz`` (the
arrays ``W``, ``b``, ``low``, ``high``; read with ``allow_pickle=False``, so loading runs no code) and
``cem_seed<N>.json`` (the settings, the curve, the time taken).
"""

from __future__ import annotations

import json
import math
import os
import platform
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from paragym import __version__
from paragym.baselines.actor import MlpActor
from paragym.baselines.run_files import writable_models_dir
from paragym.baselines.training import check_env_id, env_name
from paragym.rollout import first_episodes

__all__ = ["CemResult", "CemSettings", "linear_actor", "read_linear", "train_cem"]

#: the first reset seed of training seed 0's generations; seed N's start N * SEED_STRIDE later (the leaderboard
#: plays 100000 + k, k below 100000)
FIRST_SEED = 1_000_000
SEED_STRIDE = 10_000_000


@dataclass(frozen=True)
class CemSettings:
    """The search's settings (module docstring).

    Attributes:
        population: candidates per generation, the mean among them (at least 4).
        episodes: episodes each candidate plays per generation, the same for all (at least 1).
        elite: the share of the candidates the Gaussian is refitted to (0 < elite <= 1; at least 2 candidates).
        init_std: the starting deviation of b, and of W times sqrt(observations): wide enough that some candidates
            saturate the actions (a feedback gain of several action ranges per unit of observation).
        noise: added to the refitted deviation, in the same units as init_std.
        budget_seconds: wall time the search may take (s; inf: the generations alone decide).
        generations: the most generations.
    """

    population: int = 32
    episodes: int = 8
    elite: float = 0.25
    init_std: float = 2.0
    noise: float = 0.02
    budget_seconds: float = 300.0
    generations: int = 1000

    def __post_init__(self) -> None:
        for name, low in (("population", 4), ("episodes", 1), ("generations", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ValueError(f"{name} must be a whole number >= {low}; got {value!r}")
        if not (0 < self.elite <= 1 and round(self.elite * self.population) >= 2):
            raise ValueError(f"elite must lie in (0, 1] and keep at least 2 of the {self.population} candidates; "
                             f"got {self.elite!r}")
        for name in ("init_std", "noise"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0; got {value!r}")
        if not (isinstance(self.budget_seconds, int | float) and self.budget_seconds > 0):  # inf: generations alone
            raise ValueError(f"budget_seconds must be a number of seconds > 0 (inf: no limit); got "
                             f"{self.budget_seconds!r}")


@dataclass(frozen=True)
class CemResult:
    """What :func:`train_cem` made: the policy's arrays, its files (None where none were written) and the
    record written beside them."""

    W: np.ndarray
    b: np.ndarray
    model: Path | None
    meta: dict[str, Any]


def linear_actor(W: np.ndarray, b: np.ndarray, low: np.ndarray, high: np.ndarray) -> MlpActor:
    """The linear policy ``clip(W obs + b, low, high)`` as a one-layer :class:`MlpActor` (float32)."""
    return MlpActor(((np.asarray(W, np.float32), np.asarray(b, np.float32), None),), False,
                    np.asarray(low, np.float64), np.asarray(high, np.float64))


def read_linear(path: str | Path) -> MlpActor:
    """The actor of a ``cem_seed<N>.npz`` file (arrays only: ``allow_pickle=False``)."""
    with np.load(Path(path), allow_pickle=False) as data:
        missing = {"W", "b", "low", "high"} - set(data.files)
        if missing:
            raise ValueError(f"{path} is not a linear policy: it lacks {', '.join(sorted(missing))}")
        W, b, low, high = data["W"], data["b"], data["low"], data["high"]
    if W.ndim != 2 or b.shape != (W.shape[0],) or low.shape != b.shape or high.shape != b.shape:
        raise ValueError(f"{path}: W {W.shape}, b {b.shape}, low {low.shape}, high {high.shape} do not fit together")
    return linear_actor(W, b, low, high)


def _play(vec: Any, params: np.ndarray, seeds: list[int], n_obs: int, low: np.ndarray, high: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, int]:
    """Successes and returns (R,) of each robot's first episode, robot r acting with ``params[r]``
    ((actions, observations + 1): W beside b), reset with ``seeds[r]``; and the steps those episodes took."""
    W, b = params[:, :, :n_obs].astype(np.float32), params[:, :, n_obs].astype(np.float32)

    def act(obs: np.ndarray) -> np.ndarray:
        return np.clip(np.einsum("rao,ro->ra", W, obs.astype(np.float32)) + b, low, high).astype(np.float32)

    rewards, length, success = first_episodes(vec, act, seeds)
    returns = np.cumsum(rewards, axis=0)[-1]  # step by step, as the search has always summed them
    return success, returns, int(length.sum())


def train_cem(env_id: str, seed: int = 0, settings: CemSettings | None = None, models_dir: str | Path | None = None,
              force: bool = False, echo: Any = None, stop: Callable[[MlpActor, float, int], bool] | None = None
              ) -> CemResult:
    """Search a linear policy for ``env_id`` (module docstring) with training seed ``seed``; with ``models_dir``
    (never the shipped models' folder), write ``<models_dir>/<Name>-vN/cem_seed<seed>.npz`` and its ``.json`` (an
    existing file is kept unless ``force``). ``echo``: called with a line per generation (None: silent)."""
    env_id = check_env_id(env_id)
    settings = settings or CemSettings()
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be a whole number >= 0; got {seed!r}")
    model = None
    if models_dir is not None:
        folder = Path(writable_models_dir(models_dir)) / env_name(env_id)
        model = folder / f"cem_seed{seed}.npz"
        if model.exists() and not force:
            raise FileExistsError(f"{model} exists: force=True (--force) replaces it")
    p, e = settings.population, settings.episodes
    vec = gym.make_vec(env_id, num_envs=p * e, vectorization_mode="vector_entry_point")
    n_obs = int(np.prod(vec.single_observation_space.shape))
    n_act = int(np.prod(vec.single_action_space.shape))
    low = vec.single_action_space.low.astype(np.float32)
    high = vec.single_action_space.high.astype(np.float32)
    rng = np.random.default_rng(seed)
    mean = np.zeros((n_act, n_obs + 1))
    std = np.full_like(mean, settings.init_std)
    std[:, :n_obs] /= math.sqrt(n_obs)
    floor = np.full_like(mean, settings.noise)
    floor[:, :n_obs] /= math.sqrt(n_obs)
    keep = int(round(settings.elite * p))
    curve: dict[str, list[float]] = {"generation": [], "seconds": [], "mean_success": [], "mean_return": [],
                                     "best_success": []}
    start = time.perf_counter()
    generation, steps, outside, stopped = 0, 0, 0.0, False
    while (generation < settings.generations and not stopped
           and time.perf_counter() - start - outside < settings.budget_seconds):
        candidates = mean + std * rng.standard_normal((p, n_act, n_obs + 1))
        candidates[0] = mean
        first = FIRST_SEED + seed * SEED_STRIDE + generation * e
        seeds = [first + k % e for k in range(p * e)]  # robot c * e + k: candidate c on episode k
        success, returns, played = _play(vec, np.repeat(candidates, e, axis=0), seeds, n_obs, low, high)
        steps += played
        wins = success.reshape(p, e).sum(axis=1)
        mean_return = returns.reshape(p, e).mean(axis=1)
        order = np.lexsort((-mean_return, -wins))  # most successes first, then the highest mean return
        elite = candidates[order[:keep]]
        curve["generation"].append(generation)
        curve["seconds"].append(time.perf_counter() - start - outside)
        curve["mean_success"].append(float(wins[0] / e))
        curve["mean_return"].append(float(mean_return[0]))
        curve["best_success"].append(float(wins[order[0]] / e))
        if echo is not None:
            echo(f"generation {generation}: mean {wins[0]}/{e} successes, return {mean_return[0]:.2f}; best "
                 f"{wins[order[0]]}/{e}, {mean_return[order[0]]:.2f}; "
                 f"{curve['seconds'][-1]:.0f} s")
        mean, std = elite.mean(axis=0), elite.std(axis=0) + floor
        generation += 1
        if stop is not None:
            before = time.perf_counter()
            searched = before - start - outside
            stopped = bool(stop(linear_actor(mean[:, :n_obs], mean[:, n_obs], low, high), searched, steps))
            outside += time.perf_counter() - before
    vec.close()
    W, b = mean[:, :n_obs].astype(np.float32), mean[:, n_obs].astype(np.float32)
    meta = {"env_id": env_id, "algo": "cem", "seed": seed, "settings": asdict(settings), "generations": generation,
            "episodes_played": generation * p * e, "steps_played": steps,
            "train_seconds": time.perf_counter() - start - outside, "stopped": stopped,
            "parameters": {"policy": int(W.size + b.size)}, "first_reset_seed": FIRST_SEED + seed * SEED_STRIDE,
            "versions": {"paragym": __version__, "numpy": np.__version__, "gymnasium": gym.__version__,
                         "python": platform.python_version()},
            "machine": f"{platform.machine()}, {os.cpu_count()} cores", "curve": curve}
    if model is not None:
        model.parent.mkdir(parents=True, exist_ok=True)
        np.savez(model, W=W, b=b, low=low.astype(np.float64), high=high.astype(np.float64))
        model.with_suffix(".json").write_text(json.dumps(meta, indent=1) + "\n")
    return CemResult(W, b, model, meta)

