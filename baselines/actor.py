"""A saved policy's deterministic action in numpy, without PyTorch.

The deterministic action of a Stable-Baselines3 MLP policy is a few matrix
products: the actor's linear layers with their activation between, then,
for SAC, TD3 and TQC, the tanh squashing to the action bounds. This module
builds that actor from the policy's weights, read either from a model file
(:func:`actor_from_file`: the weights by
:func:`paragym.baselines.safe_load.read_weights`, tensors only, and the
spaces and keyword arguments from the file's readable fields: PyTorch is
not imported) or from a model in memory (:func:`actor_from_model`). Both go
through :func:`actor_from_weights`, so the leaderboard's actions are the
same whichever way the model came.

The actor covers the policies SB3 builds for flat ``Box`` observations:
``ActorCriticPolicy`` (PPO, A2C, and paragym's BC and DAgger, whose
``mlp_extractor.policy_net`` layers and ``action_net`` make the mean
action), SAC's and TQC's ``actor.latent_pi`` and ``actor.mu``, and TD3's
``actor.mu`` (whose final tanh is the squashing). Anything else (state-dependent
exploration, a custom features extractor, squashed Gaussian outputs) gives
None: such a model acts through SB3's ``predict``.
"""

from __future__ import annotations

import json
import re
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["MlpActor", "actor_from_file", "actor_from_model", "actor_from_weights"]

#: activations (by their torch.nn class name) as numpy functions
ACTIVATIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "Tanh": np.tanh,
    "ReLU": lambda v: np.maximum(v, np.float32(0.0)),
}

Layer = tuple[np.ndarray, np.ndarray, Callable[[np.ndarray], np.ndarray] | None]


@dataclass(frozen=True)
class MlpActor:
    """An actor as (weight, bias, activation) layers in float32, whether its
    output is tanh-squashed to the bounds, and the action bounds."""

    layers: tuple[Layer, ...]
    squash: bool
    low: np.ndarray
    high: np.ndarray

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The deterministic action for one observation, clipped to the bounds (float32)."""
        x = np.asarray(obs, np.float32).reshape(-1)
        for weight, bias, activation in self.layers:
            x = weight @ x + bias
            if activation is not None:
                x = activation(x)
        if self.squash:  # SAC/TD3/TQC: tanh-squashed to [-1, 1], then to the bounds
            x = self.low + 0.5 * (np.tanh(x) + 1.0) * (self.high - self.low)
        return np.clip(x, self.low, self.high).astype(np.float32)


def _linear_chain(weights: Mapping[str, np.ndarray], prefix: str) -> list[int] | None:
    """The indices of the linear layers of the ``nn.Sequential`` whose weights are named ``<prefix>.<i>.weight``,
    in order, when every gap between two of them holds exactly one module (the activation)."""
    found = sorted(int(m[1]) for k in weights if (m := re.fullmatch(re.escape(prefix) + r"\.(\d+)\.weight", k)))
    if any(b - a != 2 for a, b in zip(found, found[1:], strict=False)):
        return None
    return found


def actor_from_weights(weights: Mapping[str, np.ndarray], activation: str | None, low: np.ndarray,
                       high: np.ndarray) -> MlpActor | None:
    """The actor of a policy from its state dict (``weights``, numpy arrays by SB3's names), the name of its
    activation (``activation``, a ``torch.nn`` class name; None: SB3's default, Tanh for actor-critic
    policies, ReLU for SAC/TD3/TQC) and the action bounds; None when the policy is not one this module covers."""
    if "action_net.weight" in weights:  # ActorCriticPolicy: policy_net's layers, then action_net
        hidden, prefix, squash, default = _linear_chain(weights, "mlp_extractor.policy_net"), \
            "mlp_extractor.policy_net", False, "Tanh"
        last = ("action_net.weight", "action_net.bias")
    elif "actor.mu.weight" in weights:  # SAC, TQC: latent_pi's layers, then mu; squashed
        hidden, prefix, squash, default = _linear_chain(weights, "actor.latent_pi"), "actor.latent_pi", True, "ReLU"
        last = ("actor.mu.weight", "actor.mu.bias")
    elif "actor.mu.0.weight" in weights:  # TD3: mu ends in the tanh that the squashing applies
        chain = _linear_chain(weights, "actor.mu")
        if not chain:
            return None
        hidden, prefix, squash, default = chain[:-1], "actor.mu", True, "ReLU"
        last = (f"actor.mu.{chain[-1]}.weight", f"actor.mu.{chain[-1]}.bias")
    else:
        return None
    function = ACTIVATIONS.get(activation or default)
    if hidden is None or function is None:
        return None
    layers: list[Layer] = [(np.asarray(weights[f"{prefix}.{i}.weight"], np.float32),
                            np.asarray(weights[f"{prefix}.{i}.bias"], np.float32), function) for i in hidden]
    layers.append((np.asarray(weights[last[0]], np.float32), np.asarray(weights[last[1]], np.float32), None))
    return MlpActor(tuple(layers), squash, np.asarray(low, np.float64), np.asarray(high, np.float64))


def actor_from_model(model: Any) -> MlpActor | None:
    """The actor of an SB3 model in memory (:func:`actor_from_weights`)."""
    policy = model.policy
    extractor = getattr(policy, "features_extractor", None) or getattr(getattr(policy, "actor", None),
                                                                         "features_extractor", None)
    squashed_gaussian = getattr(policy, "squash_output", False) and hasattr(policy, "action_net")
    if type(extractor).__name__ != "FlattenExtractor" or getattr(policy, "use_sde", False) or squashed_gaussian:
        return None
    activation = getattr(policy, "activation_fn", None) or getattr(policy, "net_args", {}).get("activation_fn")
    weights = {k: v.detach().cpu().numpy() for k, v in policy.state_dict().items()}
    space = model.action_space
    return actor_from_weights(weights, getattr(activation, "__name__", None), space.low, space.high)


def actor_from_file(path: str | Path) -> tuple[MlpActor | None, Any]:
    """The actor of the SB3 model file at ``path``, without PyTorch, and the file's observation space (a
    ``Box``); (None, space) when the policy is not one this module covers. Nothing in the file is unpickled
    (:mod:`paragym.baselines.safe_load`); a damaged or unsafe file raises a ValueError naming it."""
    from paragym.baselines.safe_load import read_weights, readable_box, readable_policy_kwargs

    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data").decode())
        observation = readable_box(data["observation_space"], "observation_space")
        action = readable_box(data["action_space"], "action_space")
        kwargs = readable_policy_kwargs(data.get("policy_kwargs", {}))
    except (OSError, KeyError, TypeError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        raise ValueError(f"cannot read model {path}: {type(exc).__name__}: {exc}") from exc
    if len(observation.shape) != 1 or kwargs.get("use_sde") or kwargs.get("squash_output") or \
            "features_extractor_class" in kwargs:
        return None, observation
    return actor_from_weights(read_weights(path), kwargs.get("activation_fn"), action.low, action.high), observation
