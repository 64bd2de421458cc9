"""The registry of paragym's env ids: one row per id, the one place that says what an id is.

Everything keyed by env id elsewhere is derived from these rows: Gymnasium's registration
(:mod:`paragym`), the paper's case that the CLI's commands and the leaderboard's dynamic episodes
run, which earlier id a later version is measured like, and whose shipped models a later version
plays. A row names its task (:attr:`EnvRow.task`); the outer layers look tasks up by that name,
never by matching an id's text.

This module is the bottom layer: it imports nothing of paragym, so that any layer may read it.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ROWS", "RUNG_NAMES", "EnvRow", "add", "check_env_id", "first_version", "ladder", "ladder_of", "ladders",
           "newest", "row", "rows", "rows_of", "task_of"]


@dataclass(frozen=True)
class EnvRow:
    """One env id.

    Attributes:
        id: the Gymnasium id, ``paragym/<Name>-v<N>``.
        entry_point: the single env's class (``module:Class``).
        vector_entry_point: the native vector env's class, or None.
        max_episode_steps: the TimeLimit Gymnasium wraps the env in.
        task: the task the id belongs to: its scenarios, metrics and policies are the task's.
        paper_scenario: the ``scenario`` argument of the paper's case.
        scenarios: every named ``scenario`` argument; None (paragym's own rows): the task's own list,
            ``Task.scenario_names`` (:attr:`scenario_names` reads it).
        summary: one line of what the id is.
        models_from: the id whose shipped models this one plays: a later version whose default mode
            runs that id's episodes bit for bit where its rules do not end them sooner (tested); None:
            its own (``models/<Name>-v<N>/``).
        bench: the module of the task's bench (``paragym.baselines.tasks``): what the CLI and the
            leaderboard know of the task; None: ``paragym.baselines.tasks.<task>``.
        rung: the id's rung on its task's difficulty ladder (0 the easiest, :func:`ladder_of`), an id of its
            own with its own version line and leaderboard table; None: a version of the task itself
            (:func:`rows_of`, :func:`newest`). A ladder has versions as a task has: the rungs ``-v1`` of a
            task are a ladder of their own (:func:`ladders`).
        kinematic_as: the id whose kinematic fidelity this one is, bit for bit, in its spaces and every
            scenario: a later version (or ladder) that changed its dynamic fidelity alone (tested). A test of the
            kinematic fidelity alone runs on that id for both; None: a kinematic fidelity of its own.
    """

    id: str
    entry_point: str
    vector_entry_point: str | None
    max_episode_steps: int
    task: str
    paper_scenario: str
    scenarios: tuple[str, ...] | None
    summary: str
    models_from: str | None = None
    bench: str | None = None
    rung: int | None = None
    kinematic_as: str | None = None

    @property
    def bench_module(self) -> str:
        """The module that defines the task's ``BENCH``."""
        return self.bench or f"paragym.baselines.tasks.{self.task}"

    @property
    def scenario_names(self) -> tuple[str, ...]:
        """Every named ``scenario`` argument: the row's, else its task's (read from the env class that
        :attr:`entry_point` names, imported by name as Gymnasium imports it)."""
        if self.scenarios is not None:
            return self.scenarios
        import importlib

        module, cls = self.entry_point.split(":")
        return tuple(getattr(importlib.import_module(module), cls).task.scenario_names)

    @property
    def engines(self) -> tuple[str, ...]:
        """The physics engines of the id's dynamic fidelity (its task's ``engines``: the ``engine`` argument),
        the default first."""
        import importlib

        module, cls = self.entry_point.split(":")
        return tuple(getattr(importlib.import_module(module), cls).task.engines)

    @property
    def vector_fidelities(self) -> tuple[str, ...]:
        """The fidelities of the id's native vector env (its task's ``vector_fidelities``; the dynamic one in
        MuJoCo alone); empty without a native vector env."""
        if self.vector_entry_point is None:
            return ()
        import importlib

        module, cls = self.entry_point.split(":")
        return tuple(getattr(importlib.import_module(module), cls).task.vector_fidelities)

    @property
    def name(self) -> str:
        """The id without ``paragym/`` (file and folder names use it)."""
        return self.id.split("/", 1)[1]

    @property
    def version(self) -> int:
        """The N of ``-vN``."""
        return int(self.id.rsplit("-v", 1)[1])


#: the names of a ladder's rungs, easiest first: rung k of a task's ladder vN is ``paragym/<Name>-<RUNG_NAMES[k]>-vN``
RUNG_NAMES = ("Easy", "Medium", "Hard")


def _ladder(name: str, module: str, steps: int, task: str, summary: str, version: int = 0,
            models_from: int | None = None, kinematic_as: int | None = None) -> tuple[EnvRow, ...]:
    """The rows of a task's ladder ``version``: ``paragym/<name>-<rung>-v<version>``, its classes
    ``<name><rung>Env`` and ``<name><rung>VectorEnv`` (``<name><rung>V<version>Env`` and so on past v0) in
    ``module``; ``summary`` is completed with the rung. ``models_from``: the ladder version whose rungs' shipped
    models these rungs play (:attr:`EnvRow.models_from`); ``kinematic_as``: the ladder version whose rungs'
    kinematic fidelity these rungs are (:attr:`EnvRow.kinematic_as`)."""
    tag = f"V{version}" if version else ""
    return tuple(EnvRow(f"paragym/{name}-{rung}-v{version}", f"{module}:{name}{rung}{tag}Env",
                        f"{module}:{name}{rung}{tag}VectorEnv", steps, task, "random", ("random",),
                        f"{summary}: rung {k} ({rung.lower()})", rung=k,
                        models_from=None if models_from is None else f"paragym/{name}-{rung}-v{models_from}",
                        kinematic_as=None if kinematic_as is None else f"paragym/{name}-{rung}-v{kinematic_as}")
                 for k, rung in enumerate(RUNG_NAMES))


# The scenario names are each task's (``Task.scenario_names``): the rows say None. Paper 004 has three drives
# and no single "paper" case: its scenario 2, the push, stands for it.

ROWS: tuple[EnvRow, ...] = (
    EnvRow("paragym/CaPaManCollisionFree-v0", "paragym.envs.capaman:CaPaManCollisionFreeEnv",
           "paragym.envs.capaman:CaPaManCollisionFreeVectorEnv", 400, "capaman", "paper", None,
           "CaPaMan 3-DOF: tour T.C.1->2->3->1 around obstacles, whole manipulator collision-free (paper 000)"),
    EnvRow("paragym/CaPaManCollisionFree-v1", "paragym.envs.capaman:CaPaManCollisionFreeV1Env",
           "paragym.envs.capaman:CaPaManCollisionFreeV1VectorEnv", 400, "capaman", "paper", None,
           "CaPaMan v1: the v0 tour with goal-relative observations, a clearance look-ahead and a time penalty"),
    EnvRow("paragym/HybridSingularityFree-v0", "paragym.envs.hybrid:HybridSingularityFreeEnv",
           "paragym.envs.hybrid:HybridSingularityFreeVectorEnv", 100, "hybrid", "paper", None,
           "hexapod + tripod (9 actuators): polynomial path without singular poses or leg-limit violations "
           "(paper 002)"),
    EnvRow("paragym/HybridSingularityFree-v1", "paragym.envs.hybrid:HybridSingularityFreeV1Env",
           "paragym.envs.hybrid:HybridSingularityFreeV1VectorEnv", 100, "hybrid", "paper", None,
           "hybrid v1: the v0 path with the end pose P1, and P1 solved at the current split, in the observation"),
    EnvRow("paragym/HybridSingularityFree-v2", "paragym.envs.hybrid:HybridSingularityFreeV2Env",
           "paragym.envs.hybrid:HybridSingularityFreeV2VectorEnv", 100, "hybrid", "paper", None,
           "hybrid v2: v1's task; in dynamic fidelity E's orientation is tracked too and a broken mechanism fails",
           models_from="paragym/HybridSingularityFree-v1"),
    EnvRow("paragym/Orthoglide2PRRKappa-v0", "paragym.envs.orthoglide:Orthoglide2PRRKappaEnv",
           "paragym.envs.orthoglide:Orthoglide2PRRKappaVectorEnv", 1000, "orthoglide", "paper", None,
           "2PRR Orthoglide + translating table: track a path, keep the condition number of J low (paper 003)"),
    EnvRow("paragym/Orthoglide2PRRKappa-v1", "paragym.envs.orthoglide:Orthoglide2PRRKappaV1Env",
           "paragym.envs.orthoglide:Orthoglide2PRRKappaV1VectorEnv", 1000, "orthoglide", "paper", None,
           "2PRR v1: the v0 task, with success that requires tracking in every action mode and fidelity",
           models_from="paragym/Orthoglide2PRRKappa-v0"),
    EnvRow("paragym/Orthoglide2PRRKappa-v2", "paragym.envs.orthoglide:Orthoglide2PRRKappaV2Env",
           "paragym.envs.orthoglide:Orthoglide2PRRKappaV2VectorEnv", 1000, "orthoglide", "paper", None,
           "2PRR v2: v1's task; in dynamic fidelity the table runs beneath the sliders' guides instead of into one",
           models_from="paragym/Orthoglide2PRRKappa-v0"),
    EnvRow("paragym/MobileTripodOdometry-v0", "paragym.envs.tripod:MobileTripodOdometryEnv",
           "paragym.envs.tripod:MobileTripodOdometryVectorEnv", 700, "tripod", "push", None,
           "mobile tripod: estimate the three drive units under slip from odometry and leg encoders (paper 004)"),
    EnvRow("paragym/MobileTripodOdometry-v1", "paragym.envs.tripod:MobileTripodOdometryV1Env",
           "paragym.envs.tripod:MobileTripodOdometryV1VectorEnv", 700, "tripod", "push", None,
           "mobile tripod v1: per unit, how far to trust the encoders' correction of the odometry (paper 004)"),
    EnvRow("paragym/MobileTripodOdometry-v2", "paragym.envs.tripod:MobileTripodOdometryV2Env",
           "paragym.envs.tripod:MobileTripodOdometryV2VectorEnv", 700, "tripod", "push", None,
           "mobile tripod v2: v1's task, where a folded mechanism (a leg past horizontal) ends the episode as a "
           "failure", models_from="paragym/MobileTripodOdometry-v1"),
    EnvRow("paragym/MobileTripodOdometry-v3", "paragym.envs.tripod:MobileTripodOdometryV3Env",
           "paragym.envs.tripod:MobileTripodOdometryV3VectorEnv", 700, "tripod", "push", None,
           "mobile tripod v3: v2's task; its dynamic fidelity at converged solver settings, the units on their wheels",
           models_from="paragym/MobileTripodOdometry-v1", kinematic_as="paragym/MobileTripodOdometry-v2"),
    *_ladder("CaPaManCollisionFree", "paragym.envs.capaman", 400, "capaman",
             "CaPaMan ladder: v1's tour among capsule posts standing on the straight lines between the T.P.s"),
    *_ladder("Orthoglide2PRRKappa", "paragym.envs.orthoglide", 1000, "orthoglide",
             "2PRR ladder: v1's task on generated laps, asking a mean kappa the least-norm motion misses"),
    *_ladder("HybridSingularityFree", "paragym.envs.hybrid", 100, "hybrid",
             "hybrid ladder: v2's task on generated paths that break a leg limit midway at the start split"),
    *_ladder("MobileTripodOdometry", "paragym.envs.tripod", 700, "tripod",
             "mobile tripod ladder: v2's task on generated drives with pushes odometry alone cannot see"),
    *_ladder("HybridSingularityFree", "paragym.envs.hybrid", 100, "hybrid",
             "hybrid ladder v1: v2's task, the split its only lever, on paths that no constant split rate clears",
             version=1),
    *_ladder("MobileTripodOdometry", "paragym.envs.tripod", 700, "tripod",
             "mobile tripod ladder v1: the ladder v0's drives at v3's converged physics", version=1, models_from=0,
             kinematic_as=0),
    *_ladder("Orthoglide2PRRKappa", "paragym.envs.orthoglide", 1000, "orthoglide",
             "2PRR ladder v1: the ladder v0's laps, in dynamic fidelity with v2's table beneath the guides",
             version=1, models_from=0, kinematic_as=0),
    *_ladder("HybridSingularityFree", "paragym.envs.hybrid", 100, "hybrid",
             "hybrid ladder v2: the ladder v1's pairs, certified with every stroke 1 mm inside its limits",
             version=2, models_from=1),
)

_BY_ID = {r.id: r for r in ROWS}


def rows() -> tuple[EnvRow, ...]:
    """Every registered row: paragym's own (:data:`ROWS`), then those added since (:func:`add`)."""
    return tuple(_BY_ID.values())


def add(new: EnvRow) -> EnvRow:
    """Add a row: an env id of a task defined outside paragym (its env classes and its bench module,
    :attr:`EnvRow.bench`). :func:`paragym.register` adds it and registers it with Gymnasium. A row
    already added is left as it is; another row under the same id is a ValueError."""
    if not isinstance(new, EnvRow):
        raise TypeError(f"row must be a paragym.registry.EnvRow; got {type(new).__name__}")
    if not new.id.startswith("paragym/") or "-v" not in new.id:
        raise ValueError(f"row id must look like paragym/<Name>-v<N>; got {new.id!r}")
    if _BY_ID.get(new.id, new) != new:
        raise ValueError(f"{new.id} is registered already, with another row")
    _BY_ID[new.id] = new
    return new


def check_env_id(env_id: str) -> str:
    """The full id of a registered paragym env (the ``paragym/`` prefix may be
    left out), or a ValueError listing the registered ids."""
    if not isinstance(env_id, str):
        raise ValueError(f"env id must be a string; got {env_id!r}")
    full = env_id if env_id.startswith("paragym/") else f"paragym/{env_id}"
    if full not in _BY_ID:
        raise ValueError(f"unknown env id {env_id!r}; registered: {', '.join(_BY_ID)}")
    return full


def row(env_id: str) -> EnvRow:
    """The row of ``env_id`` (checked: :func:`check_env_id`)."""
    return _BY_ID[check_env_id(env_id)]


def task_of(env_id: str) -> str:
    """The task ``env_id`` belongs to."""
    return row(env_id).task


def rows_of(task: str) -> tuple[EnvRow, ...]:
    """The versions of ``task``, oldest first (its ladder's rungs are not among them: :func:`ladder_of`)."""
    return tuple(sorted((r for r in rows() if r.task == task and r.rung is None), key=lambda r: r.version))


def ladder_of(task: str) -> tuple[EnvRow, ...]:
    """The rungs of ``task``'s difficulty ladders, easiest first, the oldest ladder first (empty: it has none)."""
    return tuple(sorted((r for r in rows() if r.task == task and r.rung is not None),
                        key=lambda r: (r.version, r.rung)))


def ladder(env_id: str) -> tuple[EnvRow, ...]:
    """The rungs of the ladder the rung ``env_id`` is on, easiest first (a ValueError for an id that is no rung)."""
    r = row(env_id)
    if r.rung is None:
        raise ValueError(f"{r.id} is no rung of a ladder")
    return next(rungs for rungs in ladders(r.task) if r in rungs)


def ladders(task: str) -> tuple[tuple[EnvRow, ...], ...]:
    """``task``'s difficulty ladders, the oldest first: each its rungs, easiest first (:func:`ladder_of` by
    version)."""
    out: dict[int, list[EnvRow]] = {}
    for r in ladder_of(task):
        out.setdefault(r.version, []).append(r)
    return tuple(tuple(rungs) for rungs in out.values())


def newest() -> tuple[str, ...]:
    """The newest id of every task, in the order the tasks first appear."""
    tasks = dict.fromkeys(r.task for r in rows())
    return tuple(rows_of(t)[-1].id for t in tasks)


def first_version(env_id: str) -> str:
    """The oldest id of ``env_id``'s task: later versions keep its scenarios and metrics."""
    return rows_of(task_of(env_id))[0].id
