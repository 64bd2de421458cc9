"""Load a Stable-Baselines3 model file without running any code from it.

SB3 keeps an algorithm's attributes in the zip's ``data`` entry as JSON;
what JSON cannot hold (the policy class, the spaces, schedules, buffers)
it stores as a cloudpickle payload under ``":serialized:"``, which
``Algorithm.load`` unpickles, and an unpickled payload can run any code.
:func:`safe_custom_objects` reads the JSON itself and supplies a
replacement for *every* serialized entry, built only from the readable
fields SB3 writes beside each payload (parsed as literals, never
evaluated): SB3's ``custom_objects`` then stand in for them, so nothing is
unpickled. The weights (``*.pth``) are read by SB3 with
``torch.load(weights_only=True)``: tensors only.

What the replacements are:

* ``observation_space``, ``action_space``: a ``Box`` from the readable
  shape, dtype and bounds (only ``Box`` spaces, which every paragym env
  has);
* ``policy_class``: the algorithm's ``MlpPolicy``;
* ``policy_kwargs`` (when it holds a class, such as ``activation_fn``):
  its entries as literals, activation functions from a fixed list of
  ``torch.nn`` modules;
* schedules (``lr_schedule``, ``clip_range``, ...): the constant read from
  their readable form, or 0 (they only matter for further training);
* ``train_freq`` (off-policy algorithms): one step (only training reads it);
* ``target_entropy`` (TQC keeps it as a numpy scalar): minus the action's
  dimension, the "auto" value (only training reads it);
* anything else (the last observations, episode buffers, buffer classes):
  ``None``, which SB3 treats as unset.

Resuming training from your *own* checkpoints (``paragym train`` after an
interruption) does unpickle them, as SB3 does: only resume from files you
made.
"""

from __future__ import annotations

import ast
import collections
import io
import json
import pickle
import re
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["read_weights", "readable_box", "readable_policy_kwargs", "safe_custom_objects"]

#: entries that hold a schedule (a function of the remaining progress), whatever SB3 version wrote them
SCHEDULES = ("lr_schedule", "learning_rate", "clip_range", "clip_range_vf", "exploration_schedule")
#: activation functions a policy_kwargs entry may name (torch.nn classes)
ACTIVATIONS = ("Tanh", "ReLU", "ELU", "LeakyReLU", "GELU", "SiLU", "Sigmoid", "Softplus", "Mish")


def _literal(text: Any, what: str) -> Any:
    if not isinstance(text, str):  # SB3 wrote it as JSON already
        return text
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError) as exc:
        raise ValueError(f"{what} is not a plain value ({text[:60]!r}); refusing to unpickle it") from exc


def _numbers(text: Any, dtype: np.dtype, size: int, what: str) -> np.ndarray:
    """A numpy array printed by ``str(array)`` (brackets, spaces, inf), read back."""
    text = str(text)
    if "..." in text:
        raise ValueError(f"{what} is printed in summary form; cannot rebuild it without unpickling")
    tokens = text.replace("[", " ").replace("]", " ").split()
    try:
        values = np.array([float(t) for t in tokens], dtype=dtype)
    except ValueError as exc:
        raise ValueError(f"{what} has a value that is not a number ({text[:60]!r})") from exc
    if values.size != size:
        raise ValueError(f"{what} has {values.size} values; its shape needs {size}")
    return values


def readable_box(entry: Any, what: str) -> Any:
    """A space of a model file's ``data`` entry, rebuilt as a ``Box`` from its readable fields (shape, dtype,
    bounds), never from its pickled payload."""
    from gymnasium import spaces

    if not isinstance(entry, dict):
        raise ValueError(f"{what} is not a space SB3 wrote")
    kind = entry.get(":type:", "")
    if not kind.endswith("spaces.box.Box'>"):
        raise ValueError(f"{what} is a {kind or 'space of unknown type'}; only Box spaces load without unpickling")
    shape = tuple(int(n) for n in _literal(entry["_shape"], f"{what} shape"))
    dtype = np.dtype(entry["dtype"])
    size = int(np.prod(shape))
    low = _numbers(entry["low"], dtype, size, f"{what} low").reshape(shape)
    high = _numbers(entry["high"], dtype, size, f"{what} high").reshape(shape)
    return spaces.Box(low, high, shape, dtype)


def _schedule(entry: dict[str, str]) -> Any:
    from stable_baselines3.common.utils import ConstantSchedule, FloatSchedule

    found = re.search(r"ConstantSchedule\(val=([-+0-9.eE]+)\)", entry.get("value_schedule", ""))
    return FloatSchedule(ConstantSchedule(float(found[1]) if found else 0.0))


def readable_policy_kwargs(entry: Any) -> dict[str, Any]:
    """A model's ``policy_kwargs`` from its readable form (a plain JSON object, or the fields SB3 writes beside
    the pickled payload): literals, and an activation function as its ``torch.nn`` class name."""
    if not isinstance(entry, dict):
        return {}
    out: dict[str, Any] = {}
    for key, text in entry.items():
        if key.startswith(":"):
            continue
        found = re.fullmatch(r"<class 'torch\.nn\.modules\.activation\.(\w+)'>", str(text))
        if found and found[1] in ACTIVATIONS:
            out[key] = found[1]
        elif found:
            raise ValueError(f"policy_kwargs[{key!r}] names activation {found[1]}, not one of {', '.join(ACTIVATIONS)}")
        else:
            out[key] = _literal(text, f"policy_kwargs[{key!r}]")
    return out


def _policy_kwargs(entry: dict[str, str]) -> dict[str, Any]:
    import torch.nn as nn

    out = readable_policy_kwargs(entry)
    if "activation_fn" in out:
        out["activation_fn"] = getattr(nn, out["activation_fn"])
    return out


#: the storages a weights file may hold, by their torch class name
_STORAGES = {"FloatStorage": np.dtype("<f4"), "DoubleStorage": np.dtype("<f8"), "HalfStorage": np.dtype("<f2"),
             "LongStorage": np.dtype("<i8"), "IntStorage": np.dtype("<i4"), "BoolStorage": np.dtype("?")}


def _rebuild_tensor(storage: np.ndarray, offset: int, size: tuple[int, ...], stride: tuple[int, ...],
                    *_: Any) -> np.ndarray:
    """torch._utils._rebuild_tensor_v2, in numpy: a copy of the strided view of ``storage`` (elements)."""
    if len(size) != len(stride) or offset < 0 or any(n < 0 for n in size) or any(s < 0 for s in stride):
        raise ValueError("a tensor in the weights has a negative offset, size or stride, or a stride per axis wrong")
    end = offset + sum((n - 1) * s for n, s in zip(size, stride, strict=True)) + 1 if all(size) else offset
    if end > storage.size:
        raise ValueError("a tensor in the weights reaches past its storage")
    item = storage.itemsize
    return np.lib.stride_tricks.as_strided(storage[offset:], shape=tuple(size),
                                           strides=tuple(s * item for s in stride)).copy()


class _WeightsUnpickler(pickle.Unpickler):
    """Unpickles a ``torch.save``'d state dict into numpy arrays, building nothing else: an ordered dict, tensors
    (:func:`_rebuild_tensor`) and storages read from the archive; any other class is refused."""

    def __init__(self, archive: zipfile.ZipFile, prefix: str, data: bytes) -> None:
        super().__init__(io.BytesIO(data))
        self.archive, self.prefix = archive, prefix

    def find_class(self, module: str, name: str) -> Any:
        if (module, name) == ("collections", "OrderedDict"):
            return collections.OrderedDict
        if (module, name) == ("torch._utils", "_rebuild_tensor_v2"):
            return _rebuild_tensor
        if module == "torch" and name in _STORAGES:
            return _STORAGES[name]
        raise ValueError(f"the weights name {module}.{name}, which is not a tensor; refusing to unpickle it")

    def persistent_load(self, pid: Any) -> np.ndarray:
        if not (isinstance(pid, tuple) and len(pid) == 5 and pid[0] == "storage" and isinstance(pid[1], np.dtype)):
            raise ValueError(f"the weights refer to {str(pid)[:60]}, which is not a storage")
        _, dtype, key, _, count = pid
        raw = self.archive.read(f"{self.prefix}/data/{key}")
        return np.frombuffer(raw, dtype=dtype, count=int(count))


def read_weights(path: str | Path) -> dict[str, np.ndarray]:
    """The policy's weights in the SB3 model file at ``path`` (its ``policy.pth``, a ``torch.save`` archive) as
    numpy arrays by name, without PyTorch: the archive's pickle may only build an ordered dict of tensors."""
    try:
        with zipfile.ZipFile(path) as outer:
            inner = zipfile.ZipFile(io.BytesIO(outer.read("policy.pth")))
        pickles = [n for n in inner.namelist() if n.endswith("/data.pkl")]
        if len(pickles) != 1:
            raise ValueError("its policy.pth is not a torch archive")
        prefix = pickles[0][: -len("/data.pkl")]
        order = f"{prefix}/byteorder"  # torch writes it; files without one are little-endian
        if order in inner.namelist() and inner.read(order).decode().strip() != "little":
            raise ValueError("its weights are big-endian")
        weights = _WeightsUnpickler(inner, prefix, inner.read(pickles[0])).load()
    except (OSError, KeyError, zipfile.BadZipFile, pickle.UnpicklingError, EOFError) as exc:
        raise ValueError(f"cannot read the weights of {path}: {type(exc).__name__}: {exc}") from exc
    except ValueError as exc:
        raise ValueError(f"cannot read the weights of {path}: {exc}") from exc
    if not isinstance(weights, dict) or not all(isinstance(v, np.ndarray) for v in weights.values()):
        raise ValueError(f"cannot read the weights of {path}: its policy.pth is not a state dict of tensors")
    return dict(weights)


def safe_custom_objects(path: str | Path, algorithm: type) -> dict[str, Any]:
    """Replacements for every cloudpickled entry of the model file at
    ``path`` (see the module docstring), to pass as SB3's ``custom_objects``.
    A ValueError says which entry cannot be rebuilt without unpickling."""
    with zipfile.ZipFile(path) as archive:
        data = json.loads(archive.read("data").decode())
    if not isinstance(data, dict):
        raise ValueError(f"{path}: its 'data' entry is not a JSON object")
    out: dict[str, Any] = {}
    for key, entry in data.items():
        if not (isinstance(entry, dict) and ":serialized:" in entry):
            continue
        readable = {k: v for k, v in entry.items() if k != ":serialized:"}
        if key in ("observation_space", "action_space"):
            out[key] = readable_box(entry, key)
        elif key == "policy_class":
            out[key] = algorithm.policy_aliases["MlpPolicy"]
        elif key == "policy_kwargs":
            out[key] = _policy_kwargs(readable)
        elif key == "train_freq":  # a (frequency, unit) named tuple with no readable form; only training reads it
            out[key] = (1, "step")
        elif key == "target_entropy":  # TQC keeps a numpy scalar; only training reads it: its "auto" value
            action = data.get("action_space")
            shape = readable_box(action, "action_space").shape if isinstance(action, dict) else (1,)
            out[key] = -float(np.prod(shape))
        elif "Schedule" in readable.get(":type:", "") or key in SCHEDULES:
            out[key] = _schedule(readable)
        else:
            out[key] = None
    return out
