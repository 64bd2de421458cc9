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

import dataclasses
import hashlib
import inspect
import json
import re
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import paragym
from paragym.baselines.simple import RandomPolicy, ZeroPolicy
from paragym.baselines.training import check_env_id, env_name, load_model
from paragym.models import SHARED_WITH, shipped_models_dir, shipped_models_folder

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
        file's SHA-256). Two rows with different producers are never mixed."""
        f = self.factory
        code = f if inspect.isfunction(f) or inspect.ismethod(f) else type(f)
        params = self.params() if callable(self.params) else (self.params or {})
        return json.dumps({"policy": f"{code.__module__}.{code.__qualname__}", "params": params},
                          sort_keys=True, default=repr)


def init_defaults(cls: type, **overrides: Any) -> dict[str, Any]:
    """The keyword defaults of ``cls.__init__`` (dataclasses as dicts), with
    ``overrides``: a planner's parameters as its constructor sets them."""
    out: dict[str, Any] = {}
    for name, p in inspect.signature(cls.__init__).parameters.items():
        if name != "self" and p.default is not inspect.Parameter.empty:
            out[name] = p.default
    out.update(overrides)
    return {k: dataclasses.asdict(v) if dataclasses.is_dataclass(v) else v for k, v in out.items()}


_REGISTRY: dict[str, dict[str, PolicySpec]] = {env_id: {} for env_id in paragym.ENVIRONMENTS}


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
    if name in _REGISTRY[env_id] and not replace:
        raise ValueError(f"{env_id} already has a policy named {name!r} (replace=True overrides it)")
    spec = PolicySpec(env_id, name, factory, kind, description, params)
    _REGISTRY[env_id][name] = spec
    return spec


class LearnedPolicy:
    """A saved Stable-Baselines3 model acting deterministically.

    The deterministic action of an MLP policy is a few matrix products, so
    the layers are copied out once into numpy and evaluated there (about
    20 us a step against about 300 us through ``model.predict``); the result
    equals ``model.predict(obs, deterministic=True)`` to float32 rounding
    (tested). Networks of other shapes go through ``model.predict``."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.layers, self.squash = _numpy_actor(model)
        space = model.action_space
        self.low, self.high = space.low.astype(np.float64), space.high.astype(np.float64)

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        if self.layers is None:
            action, _ = self.model.predict(obs, deterministic=True)
            return action
        x = np.asarray(obs, np.float32).reshape(-1)
        for weight, bias, activation in self.layers:
            x = weight @ x + bias
            if activation is not None:
                x = activation(x)
        if self.squash:  # SAC/TD3: tanh-squashed to [-1, 1], then to the bounds
            x = self.low + 0.5 * (np.tanh(x) + 1.0) * (self.high - self.low)
        return np.clip(x, self.low, self.high).astype(np.float32)


def _numpy_actor(model: Any) -> tuple[list[tuple[np.ndarray, np.ndarray, Any]] | None, bool]:
    """The deterministic actor of ``model`` as (weight, bias, activation)
    layers in numpy and whether its output is tanh-squashed; (None, False)
    when the network is not a plain MLP on flat observations."""
    import torch.nn as nn

    acts = {nn.Tanh: np.tanh, nn.ReLU: lambda v: np.maximum(v, 0.0)}
    policy = model.policy
    if hasattr(policy, "mlp_extractor") and hasattr(policy, "action_net"):  # PPO/A2C
        if type(policy.features_extractor).__name__ != "FlattenExtractor" or getattr(policy, "squash_output", False):
            return None, False
        modules, squash = [*policy.mlp_extractor.policy_net, policy.action_net], False
    elif hasattr(policy, "actor") and hasattr(policy.actor, "mu"):  # SAC (latent_pi, mu) / TD3 (mu)
        actor = policy.actor
        if type(actor.features_extractor).__name__ != "FlattenExtractor" or getattr(actor, "use_sde", False):
            return None, False
        if hasattr(actor, "latent_pi"):
            modules = [*actor.latent_pi, actor.mu]
        else:  # TD3: mu ends in the Tanh that the squashing applies
            modules = [*actor.mu][:-1] if isinstance([*actor.mu][-1], nn.Tanh) else None
            if modules is None:
                return None, False
        squash = True
    else:
        return None, False
    layers: list[list[Any]] = []
    for m in modules:
        if isinstance(m, nn.Linear):
            layers.append([m.weight.detach().numpy().astype(np.float32), m.bias.detach().numpy().astype(np.float32),
                           None])
        elif type(m) in acts and layers and layers[-1][2] is None:
            layers[-1][2] = acts[type(m)]
        else:
            return None, False
    return [tuple(layer) for layer in layers], squash


@lru_cache(maxsize=256)
def file_sha256(path: str, mtime_ns: int, size: int) -> str:
    """The SHA-256 of a file (cached by path, modification time and size)."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _sha256(path: Path) -> str:
    st = path.stat()
    return file_sha256(str(path), st.st_mtime_ns, st.st_size)


@lru_cache(maxsize=64)
def _cached_model(path: str, sha256: str) -> Any:
    return load_model(path)


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
        model = _cached_model(str(p), self.sha256)
        if model.observation_space.shape != env.observation_space.shape:
            raise ValueError(f"model {p} expects observations of shape {model.observation_space.shape}, "
                             f"the env gives {env.observation_space.shape}")
        return LearnedPolicy(model)


def _learned(env_id: str, models_dir: Path, prefix: str, origin: str) -> dict[str, PolicySpec]:
    folder = shipped_models_folder(env_id) if origin == "shipped" else models_dir / env_name(env_id)
    if origin == "shipped" and env_id in SHARED_WITH:
        origin += f" (trained on {SHARED_WITH[env_id]}, whose episodes this id's default mode runs bit for bit)"
    found = {}
    for path in sorted(folder.glob("*_seed*.zip")):
        m = re.fullmatch(r"(ppo|sac|td3|tqc|bc|dagger)_seed(\d+)", path.stem)
        if m:
            name = f"{prefix}{m[1]}-seed{m[2]}"
            sha = _sha256(path)
            found[name] = PolicySpec(env_id, name, _LearnedFactory(str(path), sha), "learned",
                                     f"{_what_trained(path, m[1])}, training seed {m[2]}, {origin}: {path}",
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
        return f"behaviour cloning of {info.get('dataset_id', 'a Minari dataset')} (a PPO policy)"
    if algo == "dagger":
        return f"DAgger with the expert {info.get('expert', '(unknown)')} (a PPO policy)"
    what = "TQC (sb3-contrib)" if algo == "tqc" else f"{algo.upper()} (Stable-Baselines3)"
    if (info.get("hyperparams") or {}).get("init_from") == "bc":
        what += " started from its seed's behaviour clone"
    return what


def policies_for(env_id: str, models_dir: str | Path | None = None) -> dict[str, PolicySpec]:
    """Every policy of ``env_id``: the registered ones, the shipped models and,
    when ``models_dir`` is given, your own models under it (named
    ``user-<algo>-seed<N>``), in table order. A ``models_dir`` that does not
    exist is an error, not an empty list."""
    env_id = check_env_id(env_id)
    learned = _learned(env_id, shipped_models_dir(), "", "shipped")
    if models_dir is not None:
        folder = Path(models_dir)
        if not folder.is_dir():
            raise ValueError(f"models folder {folder} does not exist (models you trained: paragym train writes them "
                             f"to runs/models by default)")
        if folder.resolve() != shipped_models_dir().resolve():
            learned.update(_learned(env_id, folder, "user-", "trained by you"))
    specs = {**_REGISTRY[env_id], **learned}
    return dict(sorted(specs.items(), key=lambda kv: (KINDS.index(kv[1].kind), kv[0])))


def get_policy(env_id: str, name: str, models_dir: str | Path | None = None) -> PolicySpec:
    """The policy ``name`` of ``env_id``, or a ValueError listing them."""
    specs = policies_for(env_id, models_dir)
    if name not in specs:
        raise ValueError(f"unknown policy {name!r} for {env_id}; known: {', '.join(specs)}")
    return specs[name]


# --- built-in policies -------------------------------------------------------------------------------------------

def _random(env: gym.Env, seed: int) -> RandomPolicy:
    return RandomPolicy(env.action_space, seed)


def _zero(env: gym.Env, seed: int) -> ZeroPolicy:
    return ZeroPolicy(env.action_space)


def _rrt_ga(env: gym.Env, seed: int) -> Any:
    from paragym.planners import RrtGaPlanner, RrtGaPolicy

    return RrtGaPolicy(max_joint_step=env.unwrapped.max_joint_step, planner=RrtGaPlanner(seed=seed))


def _grid_path(env: gym.Env, seed: int) -> Any:
    from paragym.planners import GridPathPolicy

    return GridPathPolicy(max_joint_step=env.unwrapped.max_joint_step)


def _grid_field(env: gym.Env, seed: int) -> Any:
    from paragym.planners import GridFieldPolicy

    return GridFieldPolicy(max_joint_step=env.unwrapped.max_joint_step)


def _grid_field_params() -> dict[str, Any]:
    from paragym.planners import GridFieldPolicy
    from paragym.planners.grid_path import GridPathPlanner

    return {"policy": init_defaults(GridFieldPolicy, planner=None), "planner": init_defaults(GridPathPlanner)}


def _polynomial_detour(env: gym.Env, seed: int) -> Any:
    from paragym.planners.polynomial_detour import PolynomialDetourPolicy

    return PolynomialDetourPolicy()


def _polynomial_detour_margin(env: gym.Env, seed: int) -> Any:
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner, PolynomialDetourPolicy

    u = env.unwrapped
    return PolynomialDetourPolicy(PolynomialDetourPlanner(u.geometry, j_bar=u.j_bar, stroke_margin=STROKE_MARGIN))


def _polynomial_detour_margin_params() -> dict[str, Any]:
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner

    return {"planner": {**init_defaults(PolynomialDetourPlanner, geometry=None), "stroke_margin": STROKE_MARGIN,
                        "j_bar": "the env's"}}


#: HybridSingularityFree-v2's reference plans its strokes this far (m) inside their limits, where it can: a
#: simulated actuator chasing a stroke planned at its limit overshoots it by up to 0.5 mm
STROKE_MARGIN = 0.001


def _gradient(env: gym.Env, seed: int) -> Any:
    from paragym.planners.nullspace_gradient import GradientPolicy

    return GradientPolicy(geometry=env.unwrapped.geometry)


class FixedTablePolicy:
    """Paper 003's case (a) in the env's null-space action: the null-space rate
    that cancels the least-norm motion of the table (rho1), so the table
    stays where the env put it. The paper's case (a) picks, offline, the
    table position with the lowest mean kappa over the whole task; the env
    starts at the optimum for the first point instead, and a policy cannot
    move the start, so this is case (a) from the env's start."""

    def __init__(self, env: gym.Env) -> None:
        self.geometry = env.unwrapped.geometry
        self.max_null_rate = env.unwrapped.max_null_rate

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        self.task = info["scenario"]

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        from paragym.mechanisms import orthoglide as og

        k = min(info["step"], len(self.task.t) - 1)
        r1 = float(info["rho"][0])
        px, py = self.task.points[k]
        j, _, n = og.jacobian_at(r1, px, py, self.geometry)
        rate = og.least_norm(j, self.task.velocities[k])[0]
        if abs(n[0, 0]) < 1e-9:
            return np.zeros(1, np.float32)
        return np.array([np.clip(-rate[0] / (self.max_null_rate * n[0, 0]), -1.0, 1.0)], np.float32)


def _fixed_table(env: gym.Env, seed: int) -> FixedTablePolicy:
    if env.unwrapped.action_mode != "null_space":
        raise ValueError("the fixed-table policy acts in the env's null_space action mode")
    return FixedTablePolicy(env)


@dataclass(frozen=True)
class _Estimator:
    """An estimator of :mod:`paragym.planners.encoder_correction` as a policy factory."""

    kind: str

    def __call__(self, env: gym.Env, seed: int) -> Any:
        from paragym.planners import encoder_correction as ec

        return ec.EstimatorPolicy(getattr(ec, self.kind), max_correction=env.unwrapped.max_correction,
                                  geometry=env.unwrapped.geometry)


_encoder_correction = _Estimator("EncoderCorrection")


def _encoder_trust(env: gym.Env, seed: int) -> Any:
    from paragym.planners.encoder_correction import EncoderTrustPolicy

    return EncoderTrustPolicy()


def _encoder_trust_params() -> dict[str, Any]:
    from paragym.planners.encoder_correction import EncoderTrustPolicy

    return {"policy": init_defaults(EncoderTrustPolicy)}
_ukf_fusion = _Estimator("FusionEstimator")

def _rrt_ga_params() -> dict[str, Any]:
    from paragym.planners import RrtGaPlanner, RrtGaPolicy
    from paragym.planners.rrt_ga import RrtGaSettings

    return {"policy": {**init_defaults(RrtGaPolicy, planner=None), "arrival": RrtGaPolicy.ARRIVAL},
            "planner": init_defaults(RrtGaPlanner, settings=RrtGaSettings(), seed="the episode's seed")}


def _grid_path_params() -> dict[str, Any]:
    from paragym.planners import GridPathPolicy
    from paragym.planners.grid_path import GridPathPlanner

    return {"policy": {**init_defaults(GridPathPolicy, planner=None), "arrival": GridPathPolicy.ARRIVAL},
            "planner": init_defaults(GridPathPlanner)}


def _polynomial_detour_params() -> dict[str, Any]:
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner

    return {"planner": init_defaults(PolynomialDetourPlanner)}


def _gradient_params() -> dict[str, Any]:
    from paragym.planners.nullspace_gradient import GradientPolicy

    return {"policy": init_defaults(GradientPolicy)}


def _estimator_params(kind: str) -> Callable[[], dict[str, Any]]:
    def params() -> dict[str, Any]:
        from paragym.planners import encoder_correction as ec

        return {"estimator": kind, "estimator_params": init_defaults(getattr(ec, kind)),
                "policy": init_defaults(ec.EstimatorPolicy, estimator=kind)}
    return params


_BUILT_IN: tuple[tuple[str, str, Callable[[gym.Env, int], Any], str, str, Any], ...] = (
    ("paragym/CaPaManCollisionFree-v0", "rrt-ga", _rrt_ga, "reference",
     "RRT + GA on the joint matrix Theta (paper 000, eqs 1-5), followed at 2 deg per step", _rrt_ga_params),
    ("paragym/CaPaManCollisionFree-v0", "grid-dijkstra", _grid_path, "other",
     "shortest path on the free cells of Theta (Dijkstra); no GA, no clearance term", _grid_path_params),
    ("paragym/CaPaManCollisionFree-v0", "zero", _zero, "floor", "stand still at T.P.1", None),
    ("paragym/HybridSingularityFree-v0", "polynomial-detour", _polynomial_detour, "reference",
     "7th-degree path + serial optimisation of Delta + detour via-poses (paper 002)", _polynomial_detour_params),
    ("paragym/HybridSingularityFree-v0", "zero", _zero, "floor",
     "= nominal only: the unplanned 7th-degree path at Delta = 0.5 (paper 002's starting point)", None),
    ("paragym/Orthoglide2PRRKappa-v0", "gradient-c", _gradient, "reference",
     "null-space gradient of kappa (paper 003, case c, eqs 9-10)", _gradient_params),
    ("paragym/Orthoglide2PRRKappa-v0", "fixed-table-a", _fixed_table, "paper case",
     "case (a): the table held still (at the env's start; see FixedTablePolicy)", None),
    ("paragym/Orthoglide2PRRKappa-v0", "zero", _zero, "floor",
     "= least norm, case (b): rho_dot = J^+ t_dot (paper 003, eq 5 with z = 0)", None),
    ("paragym/MobileTripodOdometry-v0", "encoder-correction", _encoder_correction, "reference",
     "redundant leg encoders correct the odometry (paper 004, eqs 1-5, circle intersection)",
     _estimator_params("EncoderCorrection")),
    ("paragym/MobileTripodOdometry-v0", "ukf-fusion", _ukf_fusion, "other",
     "unscented Kalman filter fusing odometry and encoders (filterpy); not in the paper",
     _estimator_params("FusionEstimator")),
    ("paragym/MobileTripodOdometry-v0", "zero", _zero, "floor",
     "= odometry only: no correction (paper 004's uncorrected estimate)", None),
    ("paragym/CaPaManCollisionFree-v1", "grid-field", _grid_field, "other",
     "grid-dijkstra's shortest free paths on Theta, followed from wherever the cranks are (DAgger's expert)",
     _grid_field_params),
    ("paragym/HybridSingularityFree-v2", "polynomial-detour", _polynomial_detour_margin, "reference",
     "7th-degree path, serial optimisation of Delta, detour via poses (paper 002), strokes planned 1 mm inside "
     "their limits where the path allows", _polynomial_detour_margin_params),
    # v1 of the tripod acts through trust in the paper's correction: the reference is its test of the faulty unit
    ("paragym/MobileTripodOdometry-v1", "encoder-correction", _encoder_trust, "reference",
     "redundant leg encoders correct the odometry (paper 004, eqs 1-5, circle intersection), through v1's action",
     _encoder_trust_params),
    ("paragym/MobileTripodOdometry-v2", "encoder-correction", _encoder_trust, "reference",
     "redundant leg encoders correct the odometry (paper 004, eqs 1-5, circle intersection), through v1's action",
     _encoder_trust_params),
)
#: v1 id -> (v0 id, the v0 policies that play v1 unchanged: the CaPaMan's and the hybrid's v1 keep v0's action)
_SAME_IN_V1 = {
    "paragym/CaPaManCollisionFree-v1": ("paragym/CaPaManCollisionFree-v0", ("rrt-ga", "grid-dijkstra", "zero")),
    "paragym/MobileTripodOdometry-v1": ("paragym/MobileTripodOdometry-v0", ("zero",)),
    "paragym/HybridSingularityFree-v1": ("paragym/HybridSingularityFree-v0", ("polynomial-detour", "zero")),
    "paragym/Orthoglide2PRRKappa-v1": ("paragym/Orthoglide2PRRKappa-v0", ("gradient-c", "fixed-table-a", "zero")),
    "paragym/HybridSingularityFree-v2": ("paragym/HybridSingularityFree-v0", ("zero",)),
    "paragym/MobileTripodOdometry-v2": ("paragym/MobileTripodOdometry-v0", ("zero",)),
}
_BUILT_IN += tuple((new, *row[1:]) for new, (old, names) in _SAME_IN_V1.items()
                   for row in _BUILT_IN if row[0] == old and row[1] in names)

for _env_id, _name, _factory, _kind, _doc, _params in _BUILT_IN:
    register_policy(_env_id, _name, _factory, _kind, _doc, params=_params)
for _env_id in paragym.ENVIRONMENTS:
    register_policy(_env_id, "random", _random, "floor", "uniform random actions")
