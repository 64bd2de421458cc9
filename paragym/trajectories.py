"""Joint-space paths shared by planners, policies and pictures (SI units: rad)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["JointPath"]


@dataclass(frozen=True)
class JointPath:
    """A piecewise-linear path through joint space.

    Attributes:
        waypoints: (K, n) configurations, rad.
        via_indices: indices into ``waypoints`` of the task points passed, in
            order (the first is the start).
    """

    waypoints: np.ndarray
    via_indices: tuple[int, ...]

    @property
    def length(self) -> float:
        """Sum of the Euclidean joint distances between consecutive waypoints
        (rad): the sum of d(Xi_i, Xi_i+1) in paper 000's fitness (eq 3)."""
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())

    def densify(self, max_step: float) -> np.ndarray:
        """Configurations along the path no more than ``max_step`` rad apart
        (for dense collision checks), all segments at once."""
        w = self.waypoints
        seg = np.diff(w, axis=0)
        counts = np.maximum(1, np.ceil(np.linalg.norm(seg, axis=1) / max_step).astype(int))
        starts = np.repeat(np.arange(len(seg)), counts)
        frac = np.concatenate([np.arange(c) / c for c in counts])
        return np.vstack([w[starts] + frac[:, None] * seg[starts], w[-1:]])
