"""The one protocol shared by reference planners and learned agents."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["PathFollowingPolicy", "PlanningError", "Policy"]


class PlanningError(RuntimeError):
    """A planner found no plan (at its resolution, within its budget); every planner raises this one."""


@runtime_checkable
class Policy(Protocol):
    """``reset(obs, info)`` at the start of an episode (plan here if needed),
    then ``act(obs, info) -> action`` each step. Policies see only what the
    env returns (``obs``, ``info``, including ``info["scenario"]`` at reset)."""

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None: ...

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray: ...


class PathFollowingPolicy:
    """Plans at ``reset`` with ``planner.plan(info["scenario"]) -> JointPath``
    and follows the path's waypoints in straight joint-space steps of at most
    ``max_joint_step`` rad per joint (the env's scale for an action of 1).
    ``info["alpha"]`` (the joint state, float64) is what it steers from.

    It moves on to the next waypoint once every joint is within
    :data:`ARRIVAL` x ``max_joint_step`` of the current one. Before paragym
    0.6.0 it waited until it was there to 1e-9 rad: in dynamic fidelity the
    encoders settle near a waypoint and never on it to the last bit, and the
    follower stood at the first waypoint it could not hit; in kinematic
    fidelity the float32 actions land within rounding (about 1e-8 rad) of a
    waypoint, and it spent 1-3 extra steps on that rounding in 30 of the 500
    RRT + GA episodes of the full leaderboard (whose returns rose by up to
    0.2; the success rates did not change)."""

    #: the share of a step within which a waypoint counts as reached (0.1 deg for the default 2 deg step)
    ARRIVAL = 0.05

    def __init__(self, planner: Any, max_joint_step: float) -> None:
        if not max_joint_step > 0:
            raise ValueError(f"max_joint_step must be > 0 rad; got {max_joint_step}")
        self.planner = planner
        self.max_joint_step = max_joint_step
        self.path: Any = None

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        self.path = self.planner.plan(info["scenario"])
        self._next = 1

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        if self.path is None:
            raise RuntimeError("call reset(obs, info) before act")
        alpha = info["alpha"]
        w = self.path.waypoints
        while self._next < len(w) - 1 and np.max(np.abs(w[self._next] - alpha)) < self.ARRIVAL * self.max_joint_step:
            self._next += 1
        delta = w[self._next] - alpha
        return (delta / max(self.max_joint_step, np.max(np.abs(delta)))).astype(np.float32)
