"""Everything the outer layers know of a task, in one bench module per task.

The CLI, the leaderboard and the policies list look a task up here, through
the registry row of an env id (:attr:`paragym.registry.EnvRow.bench`), and
never tell tasks apart by name. A bench module defines ``BENCH``, a
:class:`Bench`: the leaderboard's per-episode metrics, their columns, the
metric that ranks after the success rate and the reference's expected
success; the built-in policies and the ids they play; the physics settings
of the leaderboard's dynamic episodes; and the CLI's adapters (the demo's
picture, the reference planner's offline run, the validation of its plan).

Adding a task is one bench module beside the env's own modules
(``docs/guides/adding-a-task.md``).
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from paragym import registry
from paragym.baselines.stats import mean_ci
from paragym.rollout import Episode

__all__ = ["Ablation", "AblationRow", "Bench", "BuiltIn", "Column", "Option", "Target", "bench_of", "dynamic_kwargs",
           "init_defaults", "missing", "random_factory", "tightest", "zero_factory"]

#: a policy factory: ``factory(env, seed) -> policy`` (:mod:`paragym.baselines.policies`)
Factory = Callable[[gym.Env, int], Any]
#: a CLI adapter: ``run(env, args, out, stem) -> exit code`` (the env made on the chosen scenario)
Adapter = Callable[[gym.Env, argparse.Namespace, Path, str], int]


@dataclass(frozen=True)
class AblationRow:
    """One design change of a task's ablation (``benchmarks/ablation.py``): trained and measured the same way.

    Attributes:
        label: what the row changes, as the table says it.
        env_id: the env it trains and is evaluated on.
        env_kwargs: the env's arguments for the row.
        overrides: PPO settings over the ablation's protocol.
        steps: env steps of training.
    """

    label: str
    env_id: str
    env_kwargs: dict[str, Any]
    overrides: dict[str, Any]
    steps: int


@dataclass(frozen=True)
class Ablation:
    """The ablation behind a task's later version: its rows, in the order they were tried, and how it is read.

    Attributes:
        rows: the design changes (:class:`AblationRow`).
        beside: the env id and the policies (floors, reference) the table compares with.
        metric: the task's column: (label, value of an episode from its infos).
        ppo_from: the env id whose ``ppo.yml`` entry the rows train with; None: the shared protocol
            (``benchmarks/ablation.py``'s ``PROTOCOL``).
    """

    rows: tuple[AblationRow, ...]
    beside: tuple[str, tuple[str, ...]]
    metric: tuple[str, Callable[[list[dict[str, Any]]], float]]
    ppo_from: str | None = None


@dataclass(frozen=True)
class Option:
    """A command-line option of a task's own, for its ``plan`` and ``validate`` adapters: ``paragym plan ENV
    --flag VALUE`` sets ``args.<dest>`` (``--dt`` -> ``args.dt``) for the env's task only.

    Attributes:
        commands: the commands that take it ("plan", "validate").
        flag: the option, e.g. "--dt".
        type: what its value is read as.
        default: its value when not given, per command (a dict) or for all.
        help: what it sets, with its unit.
    """

    commands: tuple[str, ...]
    flag: str
    type: type
    default: Any
    help: str

    def default_for(self, command: str) -> Any:
        """The default of ``command``."""
        return self.default.get(command) if isinstance(self.default, dict) else self.default


@dataclass(frozen=True)
class Column:
    """A leaderboard column: a key of the task's metrics, its label and its number format; ``exact``: the
    metric counts or flags something (a collision, a target reached, a pose outside the limits), so that
    ``paragym verify`` requires it equal on another machine, as it does the success and the length, where a
    continuous metric may differ within the results file's tolerance."""

    key: str
    label: str
    fmt: str = ".2f"
    exact: bool = False


@dataclass(frozen=True)
class BuiltIn:
    """A built-in policy of the task: its name, ``factory(env, seed)``, kind
    (:data:`paragym.baselines.policies.KINDS`), description, parameters
    (recorded in its producer) and the ids it plays (None: every id of the
    task)."""

    name: str
    factory: Factory
    kind: str
    description: str
    params: dict[str, Any] | Callable[[], dict[str, Any]] | None = None
    ids: tuple[str, ...] | None = None

    def plays(self, env_id: str) -> bool:
        return self.ids is None or env_id in self.ids


@dataclass(frozen=True)
class Target:
    """One condition of a solved task, on the check's episodes.

    * With a ``value``: the mean of ``key`` ("success": the success rate; "return"; else a key of the bench's
      metrics) reaches it (at least it for ``direction`` +1, at most it for -1).
    * With ``against`` (another policy): the policy beats ``factor`` times that policy's figure, episode by
      episode: the Student-t 95 % interval of the mean per-episode gap (better side positive) lies wholly
      above 0. A mean that is better by chance, or equal to a floor's, does not solve a task.

    ``ids``: the env ids the target applies to (None: every id of the task)."""

    key: str
    direction: int
    value: float | None = None
    against: str | None = None
    factor: float = 1.0
    ids: tuple[str, ...] | None = None

    def applies(self, env_id: str) -> bool:
        """Whether this target is one of ``env_id``'s."""
        return self.ids is None or env_id in self.ids

    def __post_init__(self) -> None:
        if self.direction not in (-1, 1):
            raise ValueError(f"direction must be +1 (at least) or -1 (at most); got {self.direction!r}")
        if (self.value is None) == (self.against is None):
            raise ValueError("a Target has either a value or a policy to compare against, not both or neither")

    def met(self, figures: np.ndarray, others: np.ndarray | None = None) -> bool:
        """Whether the per-episode ``figures`` meet this target: their mean against the value, or, paired
        with the ``against`` policy's figures on the same episodes (``others``), beyond its interval."""
        figures = np.asarray(figures, float)
        if self.against is None:
            return bool(self.direction * (figures.mean() - self.value) >= 0)
        low = mean_ci(self.direction * (figures - self.factor * np.asarray(others, float)))[0]
        return bool(low > 0)  # nan (fewer than two episodes) is not a win

    def describe(self) -> str:
        if self.against is None:
            return f"{self.key} {'>=' if self.direction > 0 else '<='} {self.value:g}"
        other = f"{self.factor:g} x {self.against}'s" if self.factor != 1.0 else f"{self.against}'s"
        return f"{self.key} {'>' if self.direction > 0 else '<'} {other} (paired, 95 %)"


@dataclass(frozen=True)
class Bench:
    """One task's bench.

    Attributes:
        task: the task's name (:attr:`paragym.registry.EnvRow.task`).
        metrics: ``metrics(episode) -> {key: value}``, the per-episode numbers the leaderboard averages.
        columns: the metrics' columns, in table order.
        primary: (key, +1 if higher is better else -1): ranks after the success rate; "return" is the return.
        reference: the name of the paper's method among the policies.
        reference_success: the success rate the tests hold the reference to on its first 20 episodes.
        policies: the built-in policies (the floor "random", which every task has, is added to them).
        dynamics: ``dynamics() -> settings``: the physics settings of the leaderboard's dynamic episodes
            (the env's ``dynamics`` argument); None: the task has no dynamic fidelity.
        demo: what ``paragym demo`` names the reference in its output.
        plot_episode: ``plot_episode(episode, path) -> path``: the demo's picture; None: the episode's
            first frame and its rewards (:func:`paragym.plots.plot_episode`).
        plan: the reference planner's offline run (``paragym plan``); None: the task has none.
        ablation: the ablation behind the task's later version (:class:`Ablation`), which
            ``benchmarks/ablation.py`` runs; None: none.
        options: the task's own command-line options of ``plan`` and ``validate`` (:class:`Option`), which its
            adapters read from ``args``.
        validate_plan: the CLI's plan-execute-validate of the reference plan (``paragym validate`` without
            ``--policy``); None: ``paragym validate`` validates the reference policy's episode.
        validated_plan: ``check(seed) -> (passed, summary)``, the leaderboard's KF validation of the
            reference plan on the paper's case; None: not validated apart from the dynamic episodes.
        solved: when a learned policy has solved the task: every :class:`Target`
            holds (``benchmarks/time_to_solve.py``); empty: the task states none.
        dynamic_tolerance: (rtol, atol): how far a dynamic-fidelity episode's return and continuous metrics
            may move when re-run on another CPU (``paragym verify``). Where PyBullet's contacts amplify a
            last-bit difference of libm or BLAS into a different trajectory, the task states the spread that
            ``benchmarks/cpu_dependence.py`` measured (``docs/reports/cpu.md``); success, length and the
            exact columns are compared exactly all the same.
    """

    task: str
    metrics: Callable[[Episode], dict[str, float]]
    columns: tuple[Column, ...]
    primary: tuple[str, int]
    reference: str
    reference_success: float
    policies: tuple[BuiltIn, ...]
    dynamics: Callable[[], Any] | None
    demo: str
    plot_episode: Callable[[Episode, Path], Path] | None = None
    plan: Adapter | None = None
    validate_plan: Adapter | None = None
    options: tuple[Option, ...] = ()
    ablation: Ablation | None = None
    validated_plan: Callable[[int], tuple[bool, dict[str, Any]]] | None = None
    solved: tuple[Target, ...] = ()
    dynamic_tolerance: tuple[float, float] = (1e-6, 1e-9)

    def label(self, key: str) -> str:
        """The column label of metric ``key`` ("return" for the return)."""
        return "return" if key == "return" else next(c.label for c in self.columns if c.key == key)

    def exact_metrics(self) -> tuple[str, ...]:
        """The metrics ``paragym verify`` compares exactly: the exact columns', and ``policy_failed``."""
        return (*(c.key for c in self.columns if c.exact), "policy_failed")

    def fmt(self, key: str) -> str:
        return next((c.fmt for c in self.columns if c.key == key), ".2f")

    def kind_of(self, env_id: str, name: str, stored: str) -> str:
        """The kind of built-in policy ``name`` on ``env_id`` today ("floor" for the random floor every
        task has); ``stored`` (the kind its rows were stored with) for a policy the bench does not know.
        A row's kind is a label, not part of what produced it: a re-labelled policy is labelled anew."""
        if name == "random":
            return "floor"
        return next((p.kind for p in self.policies if p.name == name and p.plays(env_id)), stored)

    def reference_of(self, env_id: str) -> BuiltIn:
        """The built-in reference policy that plays ``env_id`` (an id of several versions may have several)."""
        return next(p for p in self.policies if p.name == self.reference and p.plays(env_id))


def bench_of(env_id: str) -> Bench:
    """The bench of ``env_id``'s task (its row's bench module's ``BENCH``)."""
    module = importlib.import_module(registry.row(env_id).bench_module)
    found = getattr(module, "BENCH", None)
    if not isinstance(found, Bench):
        raise TypeError(f"{module.__name__} must define BENCH, a paragym.baselines.tasks.Bench")
    return found


def dynamic_kwargs(env_id: str, engine: str = "pybullet") -> dict[str, Any]:
    """The env's arguments for the leaderboard's dynamic episodes in ``engine`` ("pybullet" or "mujoco"), and for
    training under physics, the physics settings explicit (they are part of each row's producer,
    :func:`paragym.baselines.leaderboard.suite.dynamic_producer`): the task bench's (:attr:`Bench.dynamics`), and
    MuJoCo's default settings (:class:`paragym.sim.mujoco_sim.MuJoCoSettings`) in MuJoCo. A ValueError for a task
    without a dynamic fidelity."""
    settings = bench_of(env_id).dynamics
    if settings is None:
        raise ValueError(f"{env_id} has no dynamic fidelity (its task's bench names no dynamics)")
    kwargs = {"fidelity": "dynamic", "dynamics": settings()}
    if engine != "pybullet":
        from paragym.sim.mujoco_sim import ENGINES, MuJoCoSettings
        from paragym.tasks.base import check_choice

        check_choice("engine", engine, ENGINES)
        kwargs["engine"] = MuJoCoSettings()
    return kwargs


def missing(bench: Bench, env_id: str) -> list[str]:
    """What ``bench`` lacks to serve ``env_id``: names of the missing parts (empty: complete)."""
    out = []
    keys = {c.key for c in bench.columns}
    if bench.primary[0] != "return" and bench.primary[0] not in keys:
        out.append(f"a column for the primary metric {bench.primary[0]!r}")
    if bench.primary[1] not in (-1, 1):
        out.append("the primary metric's direction (+1 or -1)")
    names = [p.name for p in bench.policies if p.plays(env_id)]
    if bench.reference not in names:
        out.append(f"the reference policy {bench.reference!r} among the policies of {env_id}")
    if len(names) != len(set(names)):
        out.append(f"one policy per name on {env_id} (two play {sorted(n for n in names if names.count(n) > 1)})")
    if not 0.0 <= bench.reference_success <= 1.0:
        out.append("a reference success rate in [0, 1]")
    if not callable(bench.metrics):
        out.append("metrics (callable)")
    for name in ("dynamics", "plot_episode", "plan", "validate_plan", "validated_plan"):
        if getattr(bench, name) is not None and not callable(getattr(bench, name)):
            out.append(f"{name} (callable or None)")
    for t in bench.solved:
        if not isinstance(t, Target):
            out.append(f"solved targets that are Targets (got {t!r})")
        elif t.key not in keys | {"success", "return"}:
            out.append(f"a column for the solved target's figure {t.key!r}")
        elif t.applies(env_id) and t.against is not None and t.against not in names:
            out.append(f"the policy {t.against!r} that a solved target compares against, on {env_id}")
    rtol, atol = (tuple(bench.dynamic_tolerance) + (None, None))[:2]
    if len(bench.dynamic_tolerance) != 2 or not all(isinstance(v, float) and v >= 0 for v in (rtol, atol)):
        out.append(f"a dynamic tolerance of two non-negative floats (rtol, atol); got {bench.dynamic_tolerance!r}")
    if bench.validated_plan is not None and bench.dynamics is None:
        out.append("dynamics, which the KF validation of the reference plan runs under")
    return out


def init_defaults(cls: type, omit: tuple[str, ...] = (), **overrides: Any) -> dict[str, Any]:
    """The keyword defaults of ``cls.__init__`` (dataclasses as dicts), with
    ``overrides``: a planner's parameters as its constructor sets them. ``omit``: parameters left out, those
    added to the constructor after rows were recorded whose default keeps the policy as it was (so that its
    producer, and its stored rows, stay)."""
    out: dict[str, Any] = {}
    for name, p in inspect.signature(cls.__init__).parameters.items():
        if name != "self" and name not in omit and p.default is not inspect.Parameter.empty:
            out[name] = p.default
    out.update(overrides)
    return {k: dataclasses.asdict(v) if dataclasses.is_dataclass(v) else v for k, v in out.items()}


def tightest(report: Any) -> str:
    """The judged component of a validation report closest to its tolerance, as text."""
    worst = max(report.components, key=lambda c: c.error_judged / c.tolerance)
    return (f"tightest component {worst.name}: error {worst.error_judged:.3f} against tolerance "
            f"{worst.tolerance:.3f}, correlation {worst.correlation:.2f}")


def random_factory(env: gym.Env, seed: int) -> Any:
    """Uniformly random actions: the floor every task has."""
    from paragym.baselines.simple import RandomPolicy

    return RandomPolicy(env.action_space, seed)


def zero_factory(env: gym.Env, seed: int) -> Any:
    """The zero action: a floor, and in three tasks one of the paper's cases."""
    from paragym.baselines.simple import ZeroPolicy

    return ZeroPolicy(env.action_space)


@dataclass(frozen=True)
class BestConstant:
    """A task's best-constant floor as a policy factory: always the action ``actions`` names for the env's id
    (read from ``env.spec``, so the env must come from ``gym.make``), each found by
    :func:`paragym.baselines.simple.best_constant` and named by the task's bench."""

    actions: tuple[tuple[str, tuple[float, ...]], ...]

    def __call__(self, env: gym.Env, seed: int) -> Any:
        from paragym.baselines.simple import ConstantPolicy

        table = dict(self.actions)
        env_id = env.spec.id if env.spec is not None else None
        if env_id not in table:
            raise ValueError(f"best-constant plays {', '.join(table)} (made with gym.make); got {env_id!r}")
        return ConstantPolicy(env.action_space, table[env_id])


def best_constant_floors(actions: dict[str, tuple[float, ...]], what: str) -> tuple[BuiltIn, ...]:
    """The best-constant floor of every id in ``actions`` (id -> its best constant action), one row each (the
    action is in its producer): ``what`` says what the action does, e.g. "trust {action} in the paper's
    correction of units 1-3" ({action} reads as (a, b, c))."""
    factory = BestConstant(tuple((env_id, tuple(map(float, a))) for env_id, a in actions.items()))
    return tuple(BuiltIn("best-constant", factory, "floor",
                         "the best constant action: " + what.format(action="(" + ", ".join(f"{v:g}" for v in a) + ")"),
                         {"action": [float(v) for v in a]}, ids=(env_id,)) for env_id, a in actions.items())
