"""Every policy the leaderboard knows, by env: one registration each.

A policy is registered with :func:`register_policy` as a name and a factory
``factory(env, seed) -> policy``, where ``policy`` has ``reset(obs, info)``
and ``act(obs, info) -> action`` (:class:`paragym.planners.base.Policy`) and
``seed`` seeds whatever randomness it has. The leaderboard builds a fresh
policy for every episode, so that an episode's result depends only on its
own seeds, never on which worker ran it or what it ran before.

Built in, per env: the paper's method (``kind="reference"``), the paper's
other cases where they differ from the trivial policies (``"paper case"``),
other planners of ours (``"other"``), the shipped Stable-Baselines3 models
(package data, :func:`shipped_models_dir`; named ``ppo-seed0`` and so on,
``"learned"``) and the floor every agent must beat, uniformly random and
zero actions (``"floor"``). A zero action *is* one of the paper's cases in
three envs; its description says which. Models you trained yourself join
only when you name their folder (``models_dir``, ``--models``), listed
apart from the shipped ones as ``user-ppo-seed0`` and so on.

Every policy has a producer (:meth:`PolicySpec.producer`): what exactly
makes its actions, recorded with every leaderboard row: the model file's
SHA-256 for a learned policy, the planner's parameters for a planner.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml

from paragym.baselines.actor import MlpActor, actor_from_file, actor_from_model
from paragym.baselines.agents import identity, sha256_of_file
from paragym.baselines.cem import read_linear
from paragym.baselines.tasks import bench_of, init_defaults, random_factory
from paragym.baselines.training import check_env_id, env_name, load_model
from paragym.models import shared_with, shipped_models_dir, shipped_models_folder

__all__ = ["KINDS", "LearnedPolicy", "PolicySpec", "get_policy", "init_defaults", "policies_for", "register_policy",
           "shipped_models_dir"]

KINDS = ("reference", "paper case", "other", "learned", "floor", "user")


@dataclass(frozen=True)
class PolicySpec:
    """A named way to act in one env: ``factory(env, seed) -> policy``."""

    env_id: str
    name: str
    factory: Callable[[gym.Env, int], Any]
    kind: str = "user"
    description: str = ""
    #: what defines the policy beyond its code: a dict, or a function that returns it (called when needed)
    params: dict[str, Any] | Callable[[], dict[str, Any]] | None = None

    def producer(self) -> str:
        """What makes this policy's actions, as canonical JSON: the factory's
        qualified name and the parameters (for a learned policy, the model
        file's SHA-256), and for an agent from outside paragym the SHA-256 of
        the source that defines it (:func:`paragym.baselines.agents.identity`).
        Two rows with different producers are never mixed."""
        params = self.params() if callable(self.params) else (self.params or {})
        return json.dumps(identity(self.factory, params), sort_keys=True, default=repr)


#: env id -> the policies registered in this process (:func:`register_policy`), beside the built-in ones
_REGISTRY: dict[str, dict[str, PolicySpec]] = {}


def _built_in(env_id: str) -> dict[str, PolicySpec]:
    """The task's built-in policies that play ``env_id`` (its bench, :mod:`paragym.baselines.tasks`), and the
    uniformly random floor every task has."""
    found = {p.name: PolicySpec(env_id, p.name, p.factory, p.kind, p.description, p.params)
             for p in bench_of(env_id).policies if p.plays(env_id)}
    found["random"] = PolicySpec(env_id, "random", random_factory, "floor", "uniform random actions")
    return found


def register_policy(env_id: str, name: str, factory: Callable[[gym.Env, int], Any], kind: str = "user",
                    description: str = "", replace: bool = False,
                    params: dict[str, Any] | Callable[[], dict[str, Any]] | None = None) -> PolicySpec:
    """Add a policy to ``env_id``'s leaderboard. ``name`` is its row label
    (letters, digits, ``-_.()+`` and spaces); an existing name needs ``replace``.
    ``params``: what defines the policy beyond its code (recorded with its
    rows; a change of them re-runs its episodes)."""
    env_id = check_env_id(env_id)
    if not isinstance(name, str) or not re.fullmatch(r"[\w\-.()+ ]{1,60}", name):
        raise ValueError(f"policy name must be 1-60 letters, digits, spaces or -_.()+; got {name!r}")
    if not callable(factory):
        raise ValueError(f"factory for {name!r} must be callable as factory(env, seed)")
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}; got {kind!r}")
    if (name in _REGISTRY.get(env_id, {}) or name in _built_in(env_id)) and not replace:
        raise ValueError(f"{env_id} already has a policy named {name!r} (replace=True overrides it)")
    spec = PolicySpec(env_id, name, factory, kind, description, params)
    _REGISTRY.setdefault(env_id, {})[name] = spec
    return spec


class LearnedPolicy:
    """A Stable-Baselines3 policy acting deterministically: a model in memory
    (``model``), or the actor read from a model file (``actor``:
    :func:`paragym.baselines.actor.actor_from_file`, without PyTorch).

    The deterministic action of an MLP policy is a few matrix products, so
    it is evaluated in a compiled kernel (:class:`paragym.baselines.actor.MlpActor`,
    without PyTorch's per-call overhead of ``model.predict``); the
    result equals ``model.predict(obs, deterministic=True)`` to float32
    rounding (tested). Networks of other shapes go through ``model.predict``."""

    def __init__(self, model: Any = None, actor: MlpActor | None = None) -> None:
        if model is None and actor is None:
            raise ValueError("a learned policy needs a model or an actor")
        self.model = model
        self.actor = actor if actor is not None else actor_from_model(model)

    @property
    def layers(self) -> tuple[Any, ...] | None:
        """The numpy actor's layers; None when the policy acts through ``model.predict``."""
        return None if self.actor is None else self.actor.layers

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        if self.actor is None:
            action, _ = self.model.predict(obs, deterministic=True)
            return action
        return self.actor.act(obs)


@lru_cache(maxsize=256)
def file_sha256(path: str, mtime_ns: int, size: int) -> str:
    """The SHA-256 of a file (cached by path, modification time and size)."""
    return sha256_of_file(path)


def _sha256(path: Path) -> str:
    st = path.stat()
    return file_sha256(str(path), st.st_mtime_ns, st.st_size)


@lru_cache(maxsize=64)
def _cached_model(path: str, sha256: str) -> Any:
    return load_model(path)


@lru_cache(maxsize=64)
def _cached_actor(path: str, sha256: str) -> tuple[MlpActor | None, Any]:
    return actor_from_file(path)


@lru_cache(maxsize=64)
def _cached_linear(path: str, sha256: str) -> MlpActor:
    return read_linear(path)


@dataclass(frozen=True)
class _LearnedFactory:
    """Loads the model once per process (picklable, for worker pools and Ray),
    and only the file whose SHA-256 the leaderboard recorded."""

    path: str
    sha256: str

    def __call__(self, env: gym.Env, seed: int) -> LearnedPolicy:
        p = Path(self.path)
        if not p.is_file() or _sha256(p) != self.sha256:
            raise ValueError(f"model {p} changed (or went) since the leaderboard listed it: its episodes would not "
                             f"be the model's recorded in their rows (SHA-256 {self.sha256[:12]}); run again")
        if p.suffix == ".npz":  # a linear policy of paragym.baselines.cem: arrays only
            actor = _cached_linear(str(p), self.sha256)
            if actor.layers[0][0].shape[1:] != env.observation_space.shape:
                raise ValueError(f"model {p} expects observations of shape {actor.layers[0][0].shape[1:]}, "
                                 f"the env gives {env.observation_space.shape}")
            return LearnedPolicy(actor=actor)
        actor, observation = _cached_actor(str(p), self.sha256)  # an MLP acts in numpy: PyTorch is not loaded
        policy = LearnedPolicy(actor=actor) if actor is not None else LearnedPolicy(_cached_model(str(p), self.sha256))
        if actor is None:
            observation = policy.model.observation_space
        if observation.shape != env.observation_space.shape:
            raise ValueError(f"model {p} expects observations of shape {observation.shape}, "
                             f"the env gives {env.observation_space.shape}")
        return policy


def _learned(env_id: str, models_dir: Path | None, prefix: str, origin: str) -> dict[str, PolicySpec]:
    """The models of ``env_id`` in ``models_dir`` (None: the shipped ones, named in descriptions by their path in
    the package, ``models/<env>/<file>``, the same on every machine; yours by the path you gave)."""
    folder = shipped_models_folder(env_id) if models_dir is None else models_dir / env_name(env_id)
    if origin == "shipped" and shared_with(env_id):
        origin += f" (trained on {shared_with(env_id)}, whose episodes this id's default mode runs bit for bit)"
    found = {}
    for path in sorted([*folder.glob("*_seed*.zip"), *folder.glob("cem_seed*.npz")]):
        m = re.fullmatch(r"(ppo|sac|td3|tqc|bc|dagger)_seed(\d+)" if path.suffix == ".zip" else r"(cem)_seed(\d+)",
                         path.stem)
        if m:
            name = f"{prefix}{m[1]}-seed{m[2]}"
            sha = _sha256(path)
            shown = path.relative_to(shipped_models_dir().parent) if models_dir is None else path
            found[name] = PolicySpec(env_id, name, _LearnedFactory(str(path), sha), "learned",
                                     f"{_what_trained(path, m[1])}, training seed {m[2]}, {origin}: {shown}",
                                     {"model_sha256": sha})
    return found


class _ZooLoader(yaml.SafeLoader):
    """YAML's safe loader, and rl-zoo's ordered mappings (``!!python/object/apply:collections.OrderedDict``,
    which it writes in config.yml and args.yml) read as plain lists of pairs: no Python object is built."""


_ZooLoader.add_constructor("tag:yaml.org,2002:python/object/apply:collections.OrderedDict",
                           lambda loader, node: dict(loader.construct_sequence(node, deep=True)[0]))


def zoo_config(run: Path, name: str) -> dict[str, Any]:
    """The hyper-parameters rl-zoo saved for the run in folder ``run`` (``<run>/<env>/config.yml``; {} when it
    has none)."""
    path = run / name / "config.yml"
    if not path.is_file():
        return {}
    try:
        found = yaml.load(path.read_text(), Loader=_ZooLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise ValueError(f"cannot read rl-zoo's {path}: {exc}") from exc
    return dict(found) if isinstance(found, (dict, list)) else {}


def _zoo_learned(env_id: str, folder: Path) -> dict[str, PolicySpec]:
    """The models rl-baselines3-zoo trained on ``env_id`` in its log folder ``folder`` (``<algo>/<env>_<run>/
    <env>.zip``, the env id with "/" as "-"), named ``user-<algo>-zoo<run>``. A run whose observations were
    normalised cannot be replayed from its model alone (the statistics are a pickle, which paragym does not
    load): it is refused with a message."""
    name = env_id.replace("/", "-")
    found = {}
    for path in sorted(folder.glob(f"*/{name}_*/{name}.zip")):
        run, algo = path.parent, path.parent.parent.name.lower()
        m = re.fullmatch(re.escape(name) + r"_(\d+)", run.name)
        if not m or algo not in ("ppo", "sac", "td3", "tqc"):
            continue
        config = zoo_config(run, name)
        normalize = str(config.get("normalize", ""))
        if "norm_obs': True" in normalize or normalize == "True" or config.get("normalize") is True:
            raise ValueError(f"{path}: rl-zoo normalised its observations (normalize: {config['normalize']}); "
                             f"its policy needs the statistics in vecnormalize.pkl, a pickle paragym does not load. "
                             f"Train with normalize: \"{{'norm_obs': False, 'norm_reward': True}}\" (the shipped "
                             f"hyper-parameters)")
        sha = _sha256(path)
        label = f"user-{algo}-zoo{m[1]}"
        found[label] = PolicySpec(env_id, label, _LearnedFactory(str(path), sha), "learned",
                                  f"{algo.upper()} trained by rl-baselines3-zoo (run {m[1]}), trained by you: {path}",
                                  {"model_sha256": sha})
    return found


def _what_trained(path: Path, algo: str) -> str:
    """How a model was made, from its JSON beside it (when there is one): the
    dataset a clone learned from, the clone a PPO run started from."""
    meta = path.with_suffix(".json")
    try:
        info = json.loads(meta.read_text()) if meta.is_file() else {}
    except (OSError, ValueError):
        info = {}
    if algo == "bc":
        sha = f", data sha256 {info['dataset_sha256'][:12]}" if info.get("dataset_sha256") else ""
        return f"behaviour cloning of {info.get('dataset_id', 'a Minari dataset')}{sha} (a PPO policy)"
    if algo == "dagger":
        return f"DAgger with the expert {info.get('expert', '(unknown)')} (a PPO policy)"
    if algo == "cem":
        done = (f", {info['generations']} generations in {info['train_seconds']:.0f} s"
                if "generations" in info and "train_seconds" in info else "")
        return f"a linear policy by the cross-entropy method (paragym.baselines.cem{done})"
    what = "TQC (sb3-contrib)" if algo == "tqc" else f"{algo.upper()} (Stable-Baselines3)"
    start = (info.get("hyperparams") or {}).get("init_from")
    if isinstance(start, dict):
        what += f" started from the behaviour clone {start['file']} (sha256 {start['sha256'][:12]})"
    elif start == "bc":  # a model trained before paragym 0.9.0 recorded which clone
        what += " started from a behaviour clone (which file was not recorded)"
    return what


def policies_for(env_id: str, models_dir: str | Path | None = None) -> dict[str, PolicySpec]:
    """Every policy of ``env_id``: the registered ones, the shipped models and,
    when ``models_dir`` is given, your own models under it: ``paragym
    train``'s (named ``user-<algo>-seed<N>``, and ``user-dynamic-<engine>-<algo>-seed<N>`` for those trained in the
    dynamic fidelity, under its ``dynamic-<engine>/``) and rl-baselines3-zoo's runs
    when it is a zoo log folder (``user-<algo>-zoo<run>``), in table order. A ``models_dir`` that does not
    exist is an error, not an empty list."""
    env_id = check_env_id(env_id)
    learned = _learned(env_id, None, "", "shipped")
    if models_dir is not None:
        folder = Path(models_dir)
        if not folder.is_dir():
            raise ValueError(f"models folder {folder} does not exist (models you trained: paragym train writes them "
                             f"to runs/models by default)")
        if folder.resolve() != shipped_models_dir().resolve():
            learned.update(_learned(env_id, folder, "user-", "trained by you"))
            learned.update(_zoo_learned(env_id, folder))
            for engine in ("pybullet", "mujoco"):  # paragym train --fidelity dynamic's runs (run_files.fidelity_dir)
                if (folder / f"dynamic-{engine}").is_dir():
                    learned.update(_learned(env_id, folder / f"dynamic-{engine}", f"user-dynamic-{engine}-",
                                            f"trained by you under {engine}'s dynamics"))
    specs = {**_built_in(env_id), **_REGISTRY.get(env_id, {}), **learned}
    return dict(sorted(specs.items(), key=lambda kv: (KINDS.index(kv[1].kind), kv[0])))


def get_policy(env_id: str, name: str, models_dir: str | Path | None = None) -> PolicySpec:
    """The policy ``name`` of ``env_id``, or a ValueError listing them."""
    specs = policies_for(env_id, models_dir)
    if name not in specs:
        raise ValueError(f"unknown policy {name!r} for {env_id}; known: {', '.join(specs)}")
    return specs[name]
