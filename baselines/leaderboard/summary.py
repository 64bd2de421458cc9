"""The leaderboard's summaries: one row per (env, policy), ranked."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from paragym import registry
from paragym.baselines.leaderboard.suite import EvalSuite
from paragym.baselines.stats import ahead, half_width, mean_ci, resolvable_drop, separable, wilson
from paragym.baselines.store import DynamicRow, EpisodeRow, ResultStore
from paragym.baselines.tasks import bench_of, dynamic_kwargs

__all__ = ["NoiseFloor", "Summary", "dynamic_summary", "mark_separable", "noise_floor", "rung_verdict", "summarise"]


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
    #: 95 % intervals (:mod:`paragym.baselines.stats`): the success rate's (Wilson), the mean return's and the
    #: primary metric's mean's (Student's t)
    success_ci: tuple[float, float] = (math.nan, math.nan)
    return_ci: tuple[float, float] = (math.nan, math.nan)
    primary_ci: tuple[float, float] = (math.nan, math.nan)
    #: whether its intervals set it apart from the leader's (:func:`mark_separable`; None for the leader)
    separable: bool | None = None
    #: the dynamic fidelity's episodes: episodes, success_rate, return_mean, metrics (means), kf (the verdict on
    #: the paper episode: passed, worst, position_error_mm); None when they were not run
    dynamic: dict[str, Any] | None = None
    #: the same of its dynamic episodes in MuJoCo (``engine="mujoco"``), where its task runs them
    dynamic_mujoco: dict[str, Any] | None = None

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
        key = bench_of(env).primary[0]
        wins = sum(bool(r.success) for r in rs)
        out.setdefault(env, []).append(Summary(
            env, policy, bench_of(env).kind_of(env, policy, rs[0].kind), "", len(rs),
            wins / len(rs), float(returns.mean()), float(returns.std()), metrics,
            float(np.mean([r.wall_seconds for r in rs])),
            store.validation(env, policy, rs[0].producer) if store is not None else None, producer=rs[0].producer,
            success_ci=wilson(wins, len(rs)), return_ci=mean_ci(returns),
            primary_ci=mean_ci(returns if key == "return" else [r.metrics.get(key, math.nan) for r in rs])))
    ordered = {r.id: out[r.id] for r in registry.rows() if r.id in out}
    for summaries in ordered.values():
        summaries.sort(key=Summary.sort_key)
        for i, s in enumerate(summaries, 1):
            s.rank = i
        mark_separable(summaries)
    return ordered


def mark_separable(summaries: list[Summary]) -> None:
    """Set each non-leader's :attr:`Summary.separable`: whether the leader
    (rank 1) is ahead of it beyond doubt: its success rate's interval lies
    above the other's, or, where the success rates cannot be told apart, its
    primary metric's interval lies beyond the other's on the better side (the
    ranking's next criterion). Otherwise the order of the two rests on chance
    as much as on the policies: a 3-episode lucky run and a 50-episode one are
    never separable on success."""
    if not summaries:
        return
    leader = summaries[0]
    leader.separable = None
    sign = bench_of(leader.env).primary[1]
    for s in summaries[1:]:
        ahead_on_success = ahead(leader.success_ci, s.success_ci, +1)
        ahead_on_primary = not separable(leader.success_ci, s.success_ci) and ahead(leader.primary_ci, s.primary_ci,
                                                                                      sign)
        s.separable = ahead_on_success or ahead_on_primary


@dataclass(frozen=True)
class NoiseFloor:
    """The smallest differences from the leader that one leaderboard table can resolve with its episodes: below
    these, "apart from #1" cannot say yes (:func:`noise_floor`)."""

    #: episodes per policy (the leader's)
    episodes: int
    #: the leader's success rate
    leader_success: float
    #: the least drop in success rate from the leader's that is apart from it (Wilson's intervals of the same
    #: number of episodes, :func:`paragym.baselines.stats.resolvable_drop`); None where none can be
    success_drop: float | None
    #: the ranking's next metric (its label in the table) and how far beyond the leader's mean a policy of equal
    #: success must lie to be apart: the leader's interval's half-width plus the median other row's (Student's
    #: t); None where no interval is known
    metric: str
    metric_gap: float | None

    def sentence(self) -> str:
        """The floor in words, as LEADERBOARD.md prints it under a table."""
        success = (f"a success rate at least {self.success_drop:.2f} below the leader's {self.leader_success:.2f}"
                   if self.success_drop is not None else
                   f"no success rate (the leader's {self.leader_success:.2f} is at its floor for "
                   f"{self.episodes} episodes)")
        metric = ("" if self.metric_gap is None else
                  f"; at equal success, a mean {self.metric} about {self.metric_gap:.3g} worse than the leader's")
        return (f"**Noise floor** ({self.episodes} episodes per policy): apart from #1 needs {success}{metric}. "
                f"Smaller differences are within chance here; `paragym leaderboard --episodes N` runs N episodes "
                f"per evaluation seed for a finer floor.")


def noise_floor(summaries: list[Summary]) -> NoiseFloor:
    """The noise floor of one env's ranked summaries (the leader first): on success, at the leader's rate and
    episode count; on the ranking's next metric, the leader's half-width plus the median half-width of the
    other rows (two means closer than their half-widths' sum have overlapping intervals, :func:`mark_separable`)."""
    leader = summaries[0]
    bench = bench_of(leader.env)
    key = bench.primary[0]
    others = [w for w in (half_width(s.primary_ci) for s in summaries[1:]) if math.isfinite(w)]
    own = half_width(leader.primary_ci)
    gap = own + float(np.median(others)) if others and math.isfinite(own) else None
    drop = resolvable_drop(round(leader.success_rate * leader.episodes), leader.episodes)
    return NoiseFloor(leader.episodes, leader.success_rate, drop, bench.label(key), gap)


def dynamic_summary(rows: list[DynamicRow], suite: EvalSuite) -> dict[str, Any] | None:
    """One policy's dynamic episodes in a few numbers (None when it has none)."""
    if not rows:
        return None
    paper = next((r for r in rows if r.scenario == suite.dynamic[0][0] and r.seed == suite.dynamic[0][1]), None)
    kwargs = dynamic_kwargs(rows[0].env, rows[0].engine)
    d = kwargs["dynamics"]
    if "engine" in kwargs:  # MuJoCo: its own step and servos, the bench's masses and force limits
        m = kwargs["engine"]
        settings = (f"`{type(d).__name__}`'s masses and force limits, `{type(m).__name__}`: a "
                    f"{m.time_step * 1e3:g} ms step, the exported loops and servos")
    else:
        settings = (f"`{type(d).__name__}`: a {d.time_step * 1e3:g} ms step, {d.solver_iterations} solver "
                    "iterations" + (f", the {d.layout} layout" if getattr(d, "layout", "tree") != "tree" else ""))
    wins = sum(bool(r.success) for r in rows)
    return {"episodes": len(rows), "success_rate": wins / len(rows), "success_ci": wilson(wins, len(rows)),
            "return_mean": float(np.mean([r.episode_return for r in rows])),
            "metrics": {k: float(np.mean([r.metrics[k] for r in rows])) for k in rows[0].metrics},
            "kf": None if paper is None else {"passed": paper.kf_passed, **paper.kf},
            "settings": settings}


def rung_verdict(methods: dict[str, dict[str, dict[str, str]]], env_id: str) -> str:
    """Whether a rung is hard. ``methods``: one task's rows of the rungs, method -> rung id -> its
    ``leaderboard.csv`` row (a method is a row's role: "reference", a floor's name, a learning algorithm's).
    "hard" when the reference's 95 % interval lies above every other ranked method's, floors and learners
    alike; else "sanity:" and the methods whose interval reaches the reference's (a rung that a cheap method
    or a learner solves as well measures nothing beyond that); "-" where the reference has no row."""
    ref = methods.get("reference", {}).get(env_id)
    if ref is None:
        return "-"
    low = float(ref["success_ci_low"])
    close = [m for m, rows in methods.items()
             if m != "reference" and env_id in rows and float(rows[env_id]["success_ci_high"]) >= low]
    return "hard" if not close else "sanity: " + ", ".join(close)
