"""The one protocol shared by reference planners and learned agents."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["Policy"]


@runtime_checkable
class Policy(Protocol):
    """``reset(obs, info)`` at the start of an episode (plan here if needed),
    then ``act(obs, info) -> action`` each step. Policies see only what the
    env returns (``obs``, ``info``, including ``info["scenario"]`` at reset)."""

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None: ...

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray: ...
