"""The leaderboard's summaries: one row per (env, policy), ranked."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym import registry
from paragym.baselines.leaderboard.suite import EvalSuite, dynamic_kwargs
from paragym.baselines.store import DynamicRow, EpisodeRow, ResultStore
from paragym.baselines.tasks import bench_of

__all__ = ["Summary", "dynamic_summary", "summarise"]


@dataclass
class Summary:
    """One (env, policy) row of the leaderboard."""

    env: str
    policy: str
    kind: str
    description: str
    episodes: int
    success_rate: float
    return_mean: float
    return_std: float
    metrics: dict[str, float]
    wall_seconds: float
    validation: dict[str, Any] | None = None
    rank: int = 0
    producer: str = ""
    #: the dynamic fidelity's episodes: episodes, success_rate, return_mean, metrics (means), kf (the verdict on
    #: the paper episode: passed, worst, position_error_mm); None when they were not run
    dynamic: dict[str, Any] | None = None

    def sort_key(self) -> tuple[float, float, float, str]:
        """Success rate, then the env's primary metric, then the return (all best first)."""
        key, sign = bench_of(self.env).primary
        value = self.return_mean if key == "return" else self.metrics.get(key, math.nan)
        value = -math.inf if not np.isfinite(value) else sign * value
        return (-self.success_rate, -value, -self.return_mean, self.policy)


def summarise(rows: Iterable[EpisodeRow], store: ResultStore | None = None) -> dict[str, list[Summary]]:
    """The ranked summaries, per env (in registration order). The rows of one
    (env, policy) must come from one producer (the caller filters them)."""
    groups: dict[tuple[str, str], list[EpisodeRow]] = {}
    for row in rows:
        groups.setdefault((row.env, row.policy), []).append(row)
    out: dict[str, list[Summary]] = {}
    for (env, policy), rs in groups.items():
        returns = np.array([r.episode_return for r in rs])
        keys = rs[0].metrics.keys()
        metrics = {k: float(np.mean([r.metrics[k] for r in rs])) for k in keys}
        out.setdefault(env, []).append(Summary(
            env, policy, rs[0].kind, "", len(rs),
            float(np.mean([r.success for r in rs])), float(returns.mean()), float(returns.std()), metrics,
            float(np.mean([r.wall_seconds for r in rs])),
            store.validation(env, policy, rs[0].producer) if store is not None else None, producer=rs[0].producer))
    ordered = {r.id: out[r.id] for r in registry.rows() if r.id in out}
    for summaries in ordered.values():
        summaries.sort(key=Summary.sort_key)
        for i, s in enumerate(summaries, 1):
            s.rank = i
    return ordered



def dynamic_summary(rows: list[DynamicRow], suite: EvalSuite) -> dict[str, Any] | None:
    """One policy's dynamic episodes in a few numbers (None when it has none)."""
    if not rows:
        return None
    paper = next((r for r in rows if r.scenario == suite.dynamic[0][0] and r.seed == suite.dynamic[0][1]), None)
    d = dynamic_kwargs(rows[0].env)["dynamics"]
    settings = (f"`{type(d).__name__}`: a {d.time_step * 1e3:g} ms step, {d.solver_iterations} solver iterations"
                + (f", the {d.layout} layout" if getattr(d, "layout", "tree") != "tree" else ""))
    return {"episodes": len(rows), "success_rate": float(np.mean([r.success for r in rows])),
            "return_mean": float(np.mean([r.episode_return for r in rows])),
            "metrics": {k: float(np.mean([r.metrics[k] for r in rows])) for k in rows[0].metrics},
            "kf": None if paper is None else {"passed": paper.kf_passed, **paper.kf},
            "settings": settings}

