"""A saved policy's deterministic action without PyTorch, the same bits on every CPU.

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

The forward pass is one compiled kernel (:func:`k_forward`) in a fixed
order, not BLAS: OpenBLAS picks its kernels per CPU, and its float32
products of the same weights differ in the last bits between CPUs, which
an episode then carries into its returns. Each dot product is
summed in float64 in index order (a product of two float32 is exact in
float64), the bias added, and the sum rounded to float32, as the layer's
float32 output; tanh is :func:`k_tanh`, written here in plain arithmetic,
because libm's and numpy's tanh are CPU-dependent too. Numba compiles
without fast-math, so no sum is reordered or contracted into an FMA on any
target. The actions equal PyTorch's to float32 rounding (tested), and
equal themselves on every CPU (``tests/test_cpu_independence.py``).

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
import math
import re
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

__all__ = ["ACTIVATIONS", "MlpActor", "actor_from_file", "actor_from_model", "actor_from_weights", "k_forward",
           "k_tanh"]

#: the activations the kernel computes, by their torch.nn class name, as the kernel's codes
ACTIVATIONS: dict[str, int] = {"Tanh": 1, "ReLU": 2}

#: (weight (out, in), bias (out,), activation name or None) in float32
Layer = tuple[np.ndarray, np.ndarray, str | None]

_LN2_HI = 6.93147180369123816490e-01  # ln 2 in two parts (fdlibm's): k * _LN2_HI is exact for |k| < 2**11
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00


@njit(cache=True)
def _expm1_pos(y: float) -> float:
    """exp(y) - 1 for 0 <= y <= 64, in +, *, / only (no libm): a Taylor series below 0.5, else
    2**k * exp(r) - 1 with r = y - k ln 2 (|r| <= ln 2 / 2) and exp(r) by its Taylor series to r**15.
    Relative error about 1e-16; the same bits on every IEEE-754 machine."""
    if y < 0.5:
        term, total = y, y
        for n in range(2, 19):
            term = term * y / n
            total += term
        return total
    k = math.floor(y * _INV_LN2 + 0.5)
    r = (y - k * _LN2_HI) - k * _LN2_LO
    term, total = 1.0, 1.0
    for n in range(1, 16):
        term = term * r / n
        total += term
    scale = 1.0
    for _ in range(int(k)):
        scale *= 2.0
    return total * scale - 1.0


@njit(cache=True)
def k_tanh(x: float) -> float:
    """tanh(x) in float64 from :func:`_expm1_pos` (``tanh(abs(x)) = e / (e + 2)`` with ``e = exp(2 abs(x)) - 1``):
    within 1e-15 of libm's, and the same bits on every CPU; 1 with the sign of x from ``abs(x) = 20`` on, where
    tanh rounds to 1."""
    a = abs(x)
    if a >= 20.0:
        t = 1.0
    elif a == 0.0:
        return x
    else:
        e = _expm1_pos(2.0 * a)
        t = e / (e + 2.0)
    return t if x > 0 else -t


@njit(cache=True)
def k_forward(obs, weights, biases, shapes, activations, squash, low, high, out):
    """The actor's deterministic action for one observation ``obs`` (float32) into ``out`` (float32).
    ``weights``: every layer's weights, transposed ((in, out), row-major) and concatenated, as float64 (each a
    float32 value); ``biases``: the biases, concatenated (float32); ``shapes`` (L, 2): each layer's (out, in);
    ``activations`` (L,): 0 none, 1 tanh, 2 ReLU. Each output is the float64 sum over the inputs in index
    order, plus the bias, rounded to float32 (the loop runs over the outputs inside the inputs, so that it
    vectorises across outputs without reordering any one sum); then, if ``squash``,
    low + (tanh(x) + 1) / 2 * (high - low) in float64; the action clipped to [low, high]."""
    width = 0
    for i in range(shapes.shape[0]):
        width = max(width, shapes[i, 0], shapes[i, 1])
    x = np.zeros(width, np.float64)
    acc = np.zeros(width, np.float64)
    for j in range(obs.shape[0]):
        x[j] = np.float64(obs[j])
    w_at, b_at = 0, 0
    for layer in range(shapes.shape[0]):
        n_out, n_in = shapes[layer, 0], shapes[layer, 1]
        code = activations[layer]
        for i in range(n_out):
            acc[i] = 0.0
        for j in range(n_in):
            xj = x[j]
            row = w_at + j * n_out
            for i in range(n_out):
                acc[i] += weights[row + i] * xj
        for i in range(n_out):
            v = np.float32(acc[i] + np.float64(biases[b_at + i]))
            if code == 1:
                v = np.float32(k_tanh(np.float64(v)))
            elif code == 2 and v < 0:
                v = np.float32(0.0)
            x[i] = np.float64(v)
        w_at += n_out * n_in
        b_at += n_out
    for i in range(out.shape[0]):
        v = x[i]
        if squash:
            v = low[i] + 0.5 * (k_tanh(v) + 1.0) * (high[i] - low[i])
        out[i] = np.float32(min(max(v, low[i]), high[i]))


@dataclass(frozen=True)
class MlpActor:
    """An actor as (weight, bias, activation name) layers in float32, whether its output is tanh-squashed
    to the bounds, and the action bounds; :meth:`act` runs :func:`k_forward`."""

    layers: tuple[Layer, ...]
    squash: bool
    low: np.ndarray
    high: np.ndarray
    _packed: tuple[np.ndarray, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        packed = (np.concatenate([w.T.reshape(-1) for w, _, _ in self.layers]).astype(np.float64),
                  np.concatenate([b for _, b, _ in self.layers]).astype(np.float32),
                  np.array([w.shape for w, _, _ in self.layers], np.int64),
                  np.array([ACTIVATIONS.get(a, 0) if a else 0 for _, _, a in self.layers], np.int64))
        object.__setattr__(self, "_packed", packed)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The deterministic action for one observation, clipped to the bounds (float32)."""
        x = np.ascontiguousarray(obs, np.float32).reshape(-1)
        out = np.empty(self.low.shape[0], np.float32)
        k_forward(x, *self._packed, self.squash, self.low, self.high, out)
        return out


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
    function = activation or default
    if hidden is None or function not in ACTIVATIONS:
        return None
    layers: list[Layer] = [(np.ascontiguousarray(weights[f"{prefix}.{i}.weight"], np.float32),
                            np.ascontiguousarray(weights[f"{prefix}.{i}.bias"], np.float32), function)
                           for i in hidden]
    layers.append((np.ascontiguousarray(weights[last[0]], np.float32),
                   np.ascontiguousarray(weights[last[1]], np.float32), None))
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
