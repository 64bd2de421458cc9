"""When a task counts as solved, and a check of it that can stop training (``benchmarks/time_to_solve.py``).

A task's bench states its targets (:attr:`paragym.baselines.tasks.Bench.solved`), each a
:class:`paragym.baselines.tasks.Target`: a figure (the success rate or one of the bench's metrics) whose mean over
the check's episodes is at least or at most a number, or which beats another policy's figure (times a factor)
episode by episode, the 95 % interval of the paired gap wholly on the better side. :class:`SolveCheck` plays a
policy on a fixed set of validation episodes (reset seeds ``EVAL_SEED + k``, those ``paragym train`` evaluates
on, apart from the leaderboard's test episodes) and says whether every target holds. :func:`stop_when_solved` is
the Stable-Baselines3 callback that checks a model as it learns, on its wall clock without the checks' own time,
and stops it when solved or out of time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from paragym.baselines.policies import LearnedPolicy, policies_for
from paragym.baselines.tasks import Target, bench_of
from paragym.baselines.training import EVAL_SEED
from paragym.registry import check_env_id
from paragym.rollout import run_episode

# Target: the benches' (tasks)
__all__ = ["SolveCheck", "SolvePoint", "Target", "stop_search_when_solved", "stop_when_solved"]


@dataclass
class SolvePoint:
    """One check: the training steps and seconds (without the checks) it came at, the figures and whether
    every target held."""

    timesteps: int
    seconds: float
    figures: dict[str, float]
    solved: bool


def _figures(env: Any, policy: Any, seeds: list[int], keys: set[str], metrics: Any) -> dict[str, np.ndarray]:
    """Each key's value on each episode of ``seeds`` (one array per key, in the order of the seeds)."""
    rows: dict[str, list[float]] = {k: [] for k in keys}
    for s in seeds:
        ep = run_episode(env, policy, seed=s)
        values = {"success": float(ep.success), "return": float(ep.episode_return), **metrics(ep)}
        for k in keys:
            rows[k].append(float(values[k]))
    return {k: np.array(v) for k, v in rows.items()}


@dataclass
class SolveCheck:
    """The targets of ``env_id``'s task (its bench's ``solved``, or ``targets``) checked on ``episodes``
    validation episodes (the env's defaults, or ``env_kwargs``: the dynamic fidelity's, say). The figures of the
    policies a target compares against are measured once, on the same episodes, and a policy is compared with them
    episode by episode (:meth:`paragym.baselines.tasks.Target.met`); ``bounds`` holds each target's value or that
    policy's mean times the factor, for the record."""

    env_id: str
    episodes: int = 20
    targets: tuple[Target, ...] = ()
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    bounds: list[float] = field(init=False)

    def __post_init__(self) -> None:
        import gymnasium as gym

        self.env_id = check_env_id(self.env_id)
        if not isinstance(self.episodes, int) or self.episodes < 1:
            raise ValueError(f"episodes must be a positive integer; got {self.episodes!r}")
        bench = bench_of(self.env_id)
        self.targets = tuple(self.targets) or tuple(t for t in bench.solved if t.applies(self.env_id))
        if not self.targets or not all(isinstance(t, Target) for t in self.targets):
            raise ValueError(f"targets must be Targets; {self.env_id}'s task states none (its bench's solved) "
                             f"and none were given")
        self._metrics = bench.metrics
        self.seeds = [EVAL_SEED + k for k in range(self.episodes)]
        self.env = gym.make(self.env_id, **self.env_kwargs)
        specs = policies_for(self.env_id)
        self.bounds, self._others = [], []
        for t in self.targets:
            if t.against is None:
                self.bounds.append(float(t.value))
                self._others.append(None)
                continue
            if t.against not in specs:
                raise ValueError(f"{self.env_id}: no policy {t.against!r} to compare against; have {sorted(specs)}")
            if self.episodes < 2:
                raise ValueError(f"episodes must be at least 2 to compare with {t.against!r} episode by episode; "
                                 f"got {self.episodes}")
            spec = specs[t.against]
            others = np.array([_figures(self.env, spec.factory(self.env, s), [s], {t.key}, self._metrics)[t.key][0]
                               for s in self.seeds])  # a policy per episode, built for its seed (the leaderboard's way)
            self._others.append(others)
            self.bounds.append(t.factor * float(others.mean()))

    def check(self, policy: Any) -> tuple[bool, dict[str, float]]:
        """Whether ``policy`` (``reset``/``act``) meets every target, and its figures (means over the episodes)."""
        figures = _figures(self.env, policy, self.seeds, {t.key for t in self.targets}, self._metrics)
        ok = all(t.met(figures[t.key], others) for t, others in zip(self.targets, self._others, strict=True))
        return ok, {k: float(v.mean()) for k, v in figures.items()}

    def describe(self) -> str:
        return "; ".join(f"{t.describe()} ({bound:.4g})" for t, bound in zip(self.targets, self.bounds, strict=True))

    def close(self) -> None:
        self.env.close()


def stop_when_solved(check: SolveCheck, every_seconds: float, budget_seconds: float,
                     points: list[SolvePoint]) -> Any:
    """An SB3 callback: every ``every_seconds`` of learning (the checks' own time left out) it checks the
    model's deterministic policy (:class:`~paragym.baselines.policies.LearnedPolicy`), appends a
    :class:`SolvePoint` to ``points``, and stops learning once solved or after ``budget_seconds``."""
    from stable_baselines3.common.callbacks import BaseCallback

    class StopWhenSolved(BaseCallback):
        def _on_training_start(self) -> None:
            self.learning, self.since = 0.0, time.perf_counter()
            self.next_check = every_seconds

        def _on_step(self) -> bool:
            now = time.perf_counter()
            self.learning += now - self.since
            self.since = now
            if self.learning < self.next_check and self.learning < budget_seconds:
                return True
            solved, figures = check.check(LearnedPolicy(self.model))
            points.append(SolvePoint(int(self.num_timesteps), self.learning, figures, solved))
            self.next_check = self.learning + every_seconds
            self.since = time.perf_counter()  # the check's time is not learning
            return not solved and self.learning < budget_seconds

    return StopWhenSolved()


def stop_search_when_solved(check: SolveCheck, every_seconds: float, points: list[SolvePoint]) -> Any:
    """:func:`stop_when_solved` for the linear search (:func:`paragym.baselines.cem.train_cem`'s ``stop``): every
    ``every_seconds`` of search it checks the search's mean policy, appends a :class:`SolvePoint` (its steps: the
    env steps the search has played) and stops the search once solved. The budget is the search's own."""
    due = [every_seconds]

    def stop(actor: Any, seconds: float, steps: int) -> bool:
        if seconds < due[0]:
            return False
        solved, figures = check.check(LearnedPolicy(actor=actor))
        points.append(SolvePoint(steps, seconds, figures, solved))
        due[0] = seconds + every_seconds
        return solved

    return stop
