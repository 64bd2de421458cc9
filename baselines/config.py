"""The hyper-parameters of a training run: rl-baselines3-zoo's ``hyperparams/<algo>.yml`` keyed by env id, and
paragym's own keys (``hyperparams/paragym.yml``), read and checked (:mod:`paragym.baselines.training`)."""

from __future__ import annotations

from importlib import resources
from typing import Any

import yaml

from paragym import check_env_id

__all__ = ["ALGOS", "OWN_KEYS", "PARAGYM_KEYS", "check_algo", "hyperparams_table",
           "load_hyperparams", "reward_normalization"]

ALGOS = ("ppo", "sac", "td3", "tqc")  # tqc: sb3-contrib's Truncated Quantile Critics


#: keys that paragym consumes (rl-zoo's and paragym.yml's); all others go to the SB3 algorithm
PARAGYM_KEYS = ("n_envs", "n_timesteps", "vec_env", "env_kwargs", "eval_freq", "n_eval_episodes", "init_from",
                "noise_type", "noise_std", "checkpoint_freq", "normalize")


#: paragym.yml's keys, which rl-zoo does not know
OWN_KEYS = ("vec_env", "eval_freq", "n_eval_episodes", "checkpoint_freq", "init_from")


def check_algo(algo: str, known: tuple[str, ...] = ALGOS) -> str:
    """``algo`` lower-cased, or a ValueError naming the ``known`` algorithms."""
    if isinstance(algo, str) and algo.lower() in ("bc", "dagger") and algo.lower() not in known:
        raise ValueError(f"{algo.lower()} learns from an expert's demonstrations, not from rewards: paragym train "
                         f"ENV --algo {algo.lower()} (paragym.baselines.{algo.lower()})")
    if not isinstance(algo, str) or algo.lower() not in known:
        raise ValueError(f"unknown algorithm {algo!r}; known: {', '.join(known)}")
    return algo.lower()


def hyperparams_table(name: str) -> dict[str, Any]:
    """The table of ``hyperparams/<name>`` (a yml shipped with the package), keyed by env id."""
    return yaml.safe_load(resources.files("paragym.baselines").joinpath("hyperparams", name).read_text())


def load_hyperparams(algo: str, env_id: str) -> dict[str, Any]:
    """The hyper-parameters of ``algo`` for ``env_id``: rl-zoo's from the
    packaged ``hyperparams/<algo>.yml`` and paragym's own from
    ``hyperparams/paragym.yml`` (a copy; the caller may change it)."""
    algo, env_id = check_algo(algo), check_env_id(env_id)
    table = hyperparams_table(f"{algo}.yml")
    if env_id not in table:
        raise ValueError(f"hyperparams/{algo}.yml has no entry for {env_id}")
    own = (hyperparams_table("paragym.yml").get(algo) or {}).get(env_id) or {}
    clash = sorted(set(own) & set(table[env_id]))
    if clash or set(own) - set(OWN_KEYS):
        raise ValueError(f"hyperparams/paragym.yml: {algo} {env_id} may hold only {', '.join(OWN_KEYS)}")
    return {"vec_env": "dummy", **dict(table[env_id]), **own}


def reward_normalization(hp: dict[str, Any]) -> dict[str, Any] | None:
    """rl-zoo's ``normalize`` entry as VecNormalize's keyword arguments (None:
    no normalisation). rl-zoo writes it as a Python literal in a string, which
    is read here with :func:`ast.literal_eval` (never evaluated). paragym
    scales only the rewards: a normalised observation would make a saved
    policy depend on the statistics, so ``norm_obs`` must be False."""
    import ast

    value = hp.get("normalize", False)
    if isinstance(value, str):
        try:
            value = ast.literal_eval(value)
        except (ValueError, SyntaxError) as exc:
            raise ValueError(f"normalize must be a bool or a dict literal; got {value!r}") from exc
    if value is False or value is None:
        return None
    kwargs = {"norm_obs": True, "norm_reward": True} if value is True else dict(value)
    if not isinstance(value, bool | dict) or kwargs.get("norm_obs", True):
        raise ValueError(f"normalize must leave the observations alone (norm_obs: False); got {hp['normalize']!r}")
    return kwargs


def _read_config(env_id: str, algo: str, timesteps: int | None, overrides: dict[str, Any] | None,
                 n_envs: int | None) -> tuple[dict[str, Any], int]:
    """The run's hyperparameters (the yml's, with ``overrides`` and ``n_envs``) and its total timesteps."""
    hp = {**load_hyperparams(algo, env_id), **(overrides or {})}
    total = int(hp["n_timesteps"] if timesteps is None else timesteps)
    if total <= 0:
        raise ValueError(f"timesteps must be positive; got {timesteps!r}")
    if n_envs is not None:
        if not isinstance(n_envs, int) or n_envs < 1:
            raise ValueError(f"n_envs must be a positive integer; got {n_envs!r}")
        hp["n_envs"] = n_envs
    hp["n_envs"] = int(hp["n_envs"])
    return hp, total


