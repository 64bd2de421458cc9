"""What the leaderboard evaluates: the suites, the episodes' seeds and the dynamic episodes' settings."""

from __future__ import annotations

import json
from dataclasses import dataclass, replace

from paragym import registry
from paragym.baselines.policies import PolicySpec
from paragym.baselines.tasks import bench_of, dynamic_kwargs

__all__ = ["FULL", "QUICK", "EvalSuite", "dynamic_engines", "dynamic_producer", "episode_seed"]


@dataclass(frozen=True)
class EvalSuite:
    """Which episodes are evaluated: ``episodes`` per evaluation seed, and
    ``dynamic``: the episodes each policy also runs in the dynamic fidelity,
    as (scenario, reset seed), "paper" being each env's paper case
    (:data:`PAPER_SCENARIO`); ``dynamic_all``: whether every policy of every
    id runs them (the quick suite runs them on each task's newest id only,
    and there leaves out the floors and the learned seeds other than 0, to
    stay near two minutes from a fresh clone)."""

    name: str
    seeds: tuple[int, ...]
    episodes: int
    dynamic: tuple[tuple[str, int], ...] = ()
    dynamic_all: bool = True  # every policy runs the dynamic episodes (else: newest ids, no floors, seed 0 only)

    def runs_dynamic_on(self, env_id: str) -> bool:
        """Whether this suite runs dynamic episodes on ``env_id`` (if its task has a dynamic fidelity)."""
        return bool(self.dynamic) and (self.dynamic_all or env_id in registry.newest())

    def runs_dynamic(self, spec: PolicySpec) -> bool:
        """Whether ``spec`` runs the dynamic episodes in this suite."""
        if self.dynamic_all:
            return True
        return self.runs_dynamic_on(spec.env_id) and spec.kind != "floor" and not (
            spec.kind == "learned" and not spec.name.endswith("seed0"))

    def keys(self) -> list[tuple[int, int]]:
        return [(s, k) for s in self.seeds for k in range(self.episodes)]

    @property
    def smoke(self) -> bool:
        """Whether its tables rest on fewer episodes per policy than the full suite's (a smoke test)."""
        return len(self.keys()) < len(FULL.keys())

    def with_episodes(self, episodes: int) -> EvalSuite:
        """This suite with ``episodes`` per evaluation seed (a ValueError unless a positive integer): more buy a
        finer noise floor; the episodes of the shorter suite are its first ones, so a database keeps them."""
        if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
            raise ValueError(f"episodes must be a positive integer; got {episodes!r}")
        return replace(self, episodes=episodes)

    def options(self) -> str:
        """The ``paragym leaderboard`` options that run this suite."""
        base = QUICK if self.name == "quick" else FULL
        return (" --quick" if self.name == "quick" else "") + (
            f" --episodes {self.episodes}" if self.episodes != base.episodes else "")


FULL = EvalSuite("full", (0, 1, 2, 3, 4), 10, (("paper", 0), ("random", 200_001), ("random", 200_002)))
QUICK = EvalSuite("quick", (0,), 3, (("paper", 0),), dynamic_all=False)

def dynamic_producer(spec: PolicySpec, engine: str = "pybullet") -> str:
    """What makes a dynamic row: the policy's producer, the physics settings it ran under (None: the task
    has no dynamic fidelity, and no dynamic row) and what the KF's recorder measures
    (:data:`paragym.validation.episode.RECORDER`); in MuJoCo also the engine and its settings (a PyBullet row's
    producer names no engine, as before MuJoCo came)."""
    from paragym.validation.episode import RECORDER

    settings = bench_of(spec.env_id).dynamics
    made = {**json.loads(spec.producer()), "dynamics": None if settings is None else repr(settings()),
            "recorder": RECORDER}
    if engine != "pybullet":
        made["engine"] = repr(dynamic_kwargs(spec.env_id, engine)["engine"])
    return json.dumps(made, sort_keys=True)


def dynamic_engines(env_id: str) -> tuple[str, ...]:
    """The engines the leaderboard runs ``env_id``'s dynamic episodes in: its task's (:attr:`paragym.registry.
    EnvRow.engines`), MuJoCo's only where ``mujoco`` is installed (the ``mujoco`` extra)."""
    import importlib.util

    have = importlib.util.find_spec("mujoco") is not None
    return tuple(e for e in registry.row(env_id).engines if e == "pybullet" or have)


def engine_of_job(kind: str) -> str | None:
    """The engine of a dynamic job's kind ("dynamic": PyBullet's, "dynamic@<engine>"), None for another kind."""
    head, _, engine = kind.partition("@")
    return (engine or "pybullet") if head == "dynamic" else None


def dynamic_job(engine: str) -> str:
    """The kind of a dynamic job in ``engine`` (:func:`engine_of_job`)."""
    return "dynamic" if engine == "pybullet" else f"dynamic@{engine}"


def episode_seed(seed: int, episode: int) -> int:
    """The env's reset seed (and the policy's seed) of episode ``episode`` of evaluation seed ``seed``."""
    return 100_000 + 1_000 * seed + episode

