"""The task contract, and what every task shares.

A task is a paper's problem written once over N robots. :class:`Task` names
everything a task supplies, each once; :class:`paragym.envs.base.ParagymEnv`
(N = 1) and :class:`paragym.envs.vector.ParagymVectorEnv` (N robots) are
generic shells over it, and the leaderboard and episode validation read what
its :meth:`Task.evaluate` decides. An env id is a task and one value of the
task's ``Rules`` (its version's rules, as data); the registry row names the
task (:mod:`paragym.registry`).

An env, its vector env, a planner and the CLI all take a scenario as a name
("paper", "random", ...) or as a custom scenario object; :func:`resolve_scenario`
checks it, with one message for every task.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple, Protocol, TypeVar, runtime_checkable

import numpy as np

from paragym.registry import RUNG_NAMES
from paragym.sim.mujoco_sim import vector_engine

if TYPE_CHECKING:
    from paragym.sim.engine import Sim

__all__ = ["BROKEN_GAP", "BoxSpec", "Evaluation", "SimulatedWorld", "Task", "TaskBase", "TaskParams", "TaskState",
           "World", "check_choice", "check_control_period", "check_instance", "check_number", "knob_table",
           "refuse_unknown", "renamed", "reward_terms", "resolve_scenario", "started"]

S = TypeVar("S")
#: a task's state, parameters, scenario and world (:class:`Task`'s type parameters); the state is only ever
#: handed to the task, the others also come from it
StateT = TypeVar("StateT", contravariant=True)
ParamsT = TypeVar("ParamsT")
ScenarioT = TypeVar("ScenarioT")
WorldT = TypeVar("WorldT")


def resolve_scenario(choice: Any, names: tuple[str, ...], custom: type[S],
                     validate: Callable[[S], Any] | None = None, name: str = "scenario") -> str | S:
    """``choice`` if it is one of ``names`` or a ``custom`` object that
    ``validate`` accepts (``validate`` raises ValueError/TypeError naming the
    field that cannot run). An unknown name is a ValueError, any other type a
    TypeError, both saying "<name> must be one of ... or a <Custom>"."""
    if isinstance(choice, str) and choice in names:
        return choice
    if isinstance(choice, custom):
        if validate is not None:
            validate(choice)
        return choice
    error = ValueError if isinstance(choice, str) else TypeError
    one_of = f"one of {', '.join(map(repr, names))} or " if names else ""
    raise error(f"{name} must be {one_of}a {custom.__name__}; got {choice!r:.120}")

#: a loop of a closed chain open by more than this (m) in dynamic fidelity is a broken mechanism: the episode ends
#: as a failure ("broken") in the ids whose rules say so (the presets hold their loops within 1 mm under contact)
BROKEN_GAP = 0.005


def started(scenarios: list[S | None], i: int) -> S:
    """Robot ``i``'s scenario (a state's ``scenarios``), which its reset set: a RuntimeError before it."""
    scenario = scenarios[i]
    if scenario is None:
        raise RuntimeError(f"robot {i} has no scenario yet: call reset() first")
    return scenario


def renamed(module: str, old_to_new: dict[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` that still answers to the names of before paragym 0.9 (``old_to_new``) with
    a DeprecationWarning naming the new one: the tasks share one vocabulary now (``<Task>Scenario``,
    ``<Task>State``, ``paper_scenario()``, ``random_scenario(rng)``)."""
    import sys
    import warnings

    def __getattr__(name: str) -> Any:
        if name in old_to_new:
            warnings.warn(f"{module}.{name} is {module}.{old_to_new[name]} since paragym 0.9", DeprecationWarning,
                          stacklevel=2)
            return getattr(sys.modules[module], old_to_new[name])
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return __getattr__


# --- the contract ---------------------------------------------------------------------------------------------------


class BoxSpec(NamedTuple):
    """A space of one robot, as data (the envs make it a float32 ``gymnasium.spaces.Box``): every component
    within ``[low, high]``, of ``shape``."""

    low: float
    high: float
    shape: tuple[int, ...]


class Evaluation(NamedTuple):
    """What a task decides of its N robots after a reset or a step (:meth:`Task.evaluate`). The arrays are the
    state's buffers, rewritten by the next call: copy what you keep.

    Attributes:
        success: (N,) bool: the robot's episode has ended and succeeded (``info["is_success"]``).
        failure: (N,) int: why it failed, an index into :attr:`Task.failures` (0: it has not).
        numbers: the per-robot numbers every env's info carries, each an (N,) array under a stable name
            (the vector env's info holds them all; the single env's the number of its one robot).
    """

    success: np.ndarray
    failure: np.ndarray
    numbers: dict[str, np.ndarray]


@runtime_checkable
class TaskParams(Protocol):
    """A task's parameters: every argument of its env, checked once (:meth:`from_kwargs`)."""

    @property
    def fidelity(self) -> str:
        """The env's ``fidelity`` argument: "kinematic" or "dynamic"."""
        ...

    @classmethod
    def from_kwargs(cls, rules: Any, **kwargs: Any) -> TaskParams:
        """The parameters of an env id with ``rules`` made with ``kwargs`` (its env's keyword arguments,
        ``render_mode`` aside): the one place the arguments are checked, each refusal a ValueError or
        TypeError naming the argument, an unknown one a TypeError naming it."""
        ...


@runtime_checkable
class TaskState(Protocol):
    """The state of N robots: arrays with one row per robot; the transition writes ``obs``, ``reward``
    and ``terminated``; ``scenarios`` holds each robot's scenario."""

    obs: np.ndarray
    reward: np.ndarray
    terminated: np.ndarray

    @property
    def scenarios(self) -> Sequence[Any]:
        """Each robot's scenario (None before its first reset)."""
        ...

    @classmethod
    def empty(cls, n: int, params: Any) -> TaskState:
        """The state of ``n`` robots under ``params``, before any reset."""
        ...


@runtime_checkable
class World(Protocol):
    """Where a task's robots move besides its kinematic model: a PyBullet scene that checks collisions or a
    dynamic fidelity. ``None`` where the kinematic model is all there is. A world that simulates one robot
    under PyBullet's dynamics is what episode validation reads (:mod:`paragym.validation.episode`)."""

    def close(self) -> None:
        """Disconnect its PyBullet clients."""
        ...


@runtime_checkable
class SimulatedWorld(World, Protocol):
    """A world that simulates one robot (robot 0) under a physics engine's dynamics: what episode validation
    reads (:mod:`paragym.validation.episode`, through the env's ``body_motion``, ``commanded_pose`` and
    ``step_duration``). ``state`` and ``params`` are its task's."""

    @property
    def scene(self) -> Any:
        """Robot 0's scene: what KF validation judges, and draws."""
        ...

    def body(self) -> tuple[Sim, str, int, np.ndarray, float]:
        """The validated body: (its engine, body name, link index, the judged point in the link's frame (m), the
        engine's physics step (s))."""
        ...

    def commanded_pose(self, state: Any, params: Any) -> np.ndarray:
        """The validated body's pose that the last action commanded: x, y, z (m), roll, pitch, yaw (rad)."""
        ...

    def step_duration(self, state: Any, params: Any) -> float:
        """Simulated seconds of the step just taken (whole physics steps)."""
        ...


@runtime_checkable
class Task(Protocol[StateT, ParamsT, ScenarioT, WorldT]):
    """Everything a task supplies, each once. One object per task (``paragym.tasks.<task>_task.TASK``),
    generic over its state, parameters, scenario and world (``WorldT``: a :class:`World`, or None where the
    kinematic model is all there is): ``TASK: Task[MyState, MyParams, MyScenario, MyWorld | None]`` has the type
    checker hold the task to this contract (``.ci/typecheck``).

    Attributes:
        name: the task's name, as the registry rows and the bench name it.
        scenario_names: every named ``scenario`` argument (the registry reads them here).
        failures: the names of ``info["failure"]``, indexed by :attr:`Evaluation.failure` (0: None).
        Scenario: the scenario's frozen dataclass.
        Params: the parameters (:class:`TaskParams`), built by ``Params.from_kwargs(rules, **kwargs)``.
        Rules: the rules of one version, as data; the env id's class holds one value of it.
        State: the state of N robots (:class:`TaskState`), ``State.empty(n, params)``.
        vector_fidelities: the fidelities its native vector env runs.
        engines: the physics engines of its dynamic fidelity (the env's ``engine`` argument,
            :mod:`paragym.sim.mujoco_sim`), PyBullet's first, the default.
        sensor_layout: the accelerometer array of KF validation on the validated body
            (:meth:`paragym.validation.sensors.AccelerometerArray.paper_layout`'s arguments).
    """

    # (read-only: a task's constants, class attributes of its class)
    @property
    def name(self) -> str: ...
    @property
    def scenario_names(self) -> tuple[str, ...]: ...
    @property
    def failures(self) -> tuple[str | None, ...]: ...
    @property
    def Scenario(self) -> type[ScenarioT]: ...  # noqa: N802 (a class, named as one)
    @property
    def Params(self) -> type[TaskParams]: ...  # noqa: N802
    @property
    def Rules(self) -> type: ...  # noqa: N802
    @property
    def State(self) -> type[TaskState]: ...  # noqa: N802
    @property
    def vector_fidelities(self) -> tuple[str, ...]: ...
    @property
    def engines(self) -> tuple[str, ...]: ...
    @property
    def sensor_layout(self) -> dict[str, float]: ...

    def paper_scenario(self) -> ScenarioT:
        """The paper's case."""
        ...

    def random_scenario(self, rng: np.random.Generator, params: ParamsT) -> ScenarioT:
        """One random scenario drawn from ``rng`` that the task can run."""
        ...

    def validate_scenario(self, scenario: ScenarioT, params: ParamsT) -> None:
        """Raise a ValueError or TypeError naming the field of a custom ``scenario`` that cannot run."""
        ...

    def draw_scenarios(self, choice: Any, rngs: list[np.random.Generator], params: ParamsT,
                       world: WorldT) -> list[ScenarioT]:
        """One checked scenario per generator for the ``scenario`` argument ``choice`` (a name or a custom
        scenario): what ``reset`` starts."""
        ...

    def spaces(self, params: ParamsT) -> tuple[BoxSpec, BoxSpec]:
        """The observation and action spaces of one robot."""
        ...

    def vector_params(self, rules: Any, kwargs: dict[str, Any]) -> ParamsT:
        """The native vector env's parameters for an env id with ``rules`` made with ``kwargs``: the single env's
        (``Params.from_kwargs``), refused (ValueError) in a fidelity the native vector env does not run
        (:class:`TaskBase` has the usual rule)."""
        ...

    def make_world(self, params: ParamsT, n: int, render_mode: str | None) -> WorldT:
        """The :class:`World` of ``n`` robots that ``params.fidelity`` asks for, or None."""
        ...

    def reset(self, state: StateT, params: ParamsT, rows: np.ndarray, scenarios: list[ScenarioT],
              rngs: list[np.random.Generator], world: WorldT) -> None:
        """Start robots ``rows`` (integer indices) on ``scenarios`` (one generator each) and evaluate them."""
        ...

    def step(self, state: StateT, params: ParamsT, actions: np.ndarray, active: np.ndarray, world: WorldT) -> None:
        """Step the ``active`` robots (an (N,) mask) with ``actions`` (N, ...) inside the action space."""
        ...

    def evaluate(self, state: StateT, params: ParamsT, world: WorldT) -> Evaluation:
        """Success, failure and the info's numbers of every robot: what every consumer reads. paragym's tasks
        decide success in one compiled ``decide()`` their transition calls and report its buffers here; a task
        without kernels may decide here."""
        ...

    def details(self, state: StateT, params: ParamsT, world: WorldT, i: int) -> dict[str, Any]:
        """The single env's further info of robot ``i`` (arrays, names: what is not an (N,) number), as a new
        dict: the single env adds the numbers and the outcome to it. Its names differ from the numbers'."""
        ...

    def render(self, cache: dict[str, Any], state: StateT, params: ParamsT, world: WorldT, i: int,
               gui: bool) -> np.ndarray | None:
        """Robot ``i`` drawn by PyBullet (an RGB array); None with ``gui``, where the GUI's window shows it.
        ``cache`` is the env's: a scene built on the first call is kept there (``cache["scene"]``) and closed
        with the env."""
        ...


class TaskBase:
    """What most tasks' contracts share, which a task may keep or override: the native vector env runs the
    kinematic fidelity with the single env's arguments; no further info; no accelerometer layout."""

    name: str = ""
    Params: ClassVar[type[TaskParams]]
    vector_fidelities: tuple[str, ...] = ("kinematic",)
    engines: tuple[str, ...] = ("pybullet",)
    sensor_layout: dict[str, float] = {}

    def vector_params(self, rules: Any, kwargs: dict[str, Any]) -> Any:
        """The single env's parameters, refused (ValueError) in a fidelity the native vector env does not run; its
        dynamic fidelity is MuJoCo alone (:func:`paragym.sim.mujoco_sim.vector_engine`)."""
        if kwargs.get("fidelity", "kinematic") == "dynamic" and "dynamic" in self.vector_fidelities:
            kwargs = {**kwargs, "engine": vector_engine(kwargs.get("engine", "pybullet"))}
        params = self.Params.from_kwargs(rules, **kwargs)
        if params.fidelity not in self.vector_fidelities:
            raise ValueError(f"the native {self.name} vector env is {' or '.join(self.vector_fidelities)}: use "
                             f"gymnasium's sync/async vector modes for the {params.fidelity} fidelity")
        return params

    def details(self, state: Any, params: Any, world: Any, i: int) -> dict[str, Any]:
        return {}

    @staticmethod
    def drawn(cache: dict[str, Any], world: Any, gui: bool, build: Callable[[], Any],
              pose: Callable[[Any], None], i: int = 0) -> np.ndarray | None:
        """A render of a task whose dynamic world draws itself and whose kinematic model is drawn by a scene of
        its own: the world's scene of robot ``i`` (nothing in the GUI, which shows the simulation as it runs),
        else the scene kept in ``cache`` (built by ``build()`` on first use), posed by ``pose(scene)``."""
        if world is not None:
            return None if gui else getattr(world, "scenes", [world.scene])[i].render()
        if "scene" not in cache:
            cache["scene"] = build()
        pose(cache["scene"])
        return cache["scene"].render()


# --- the argument checks every task's Params.from_kwargs uses ---------------------------------------------------------


def check_number(name: str, value: Any, low: float = 0.0, *, strict: bool = True, high: float | None = None,
                 unit: str = "") -> float:
    """``value`` as a float if it is a finite real number above ``low`` (at or above it unless ``strict``) and
    at most ``high``, else a ValueError (TypeError for a non-number) naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise TypeError(f"{name} must be a number{unit}; got {value!r:.80}")
    v = float(value)
    above = v > low if strict else v >= low
    if not (np.isfinite(v) and above and (high is None or v <= high)):
        rel = ">" if strict else ">="
        upper = f" and <= {high:g}" if high is not None else ""
        raise ValueError(f"{name} must be a finite number {rel} {low:g}{upper}{unit}; got {value!r}")
    return v


def check_choice(name: str, value: Any, choices: tuple[Any, ...]) -> Any:
    """``value`` if it is one of ``choices``, else a ValueError naming ``name`` and them."""
    if not isinstance(value, str | None) or value not in choices:
        raise ValueError(f"{name} must be {' or '.join(map(repr, choices))}; got {value!r:.80}")
    return value


def check_instance(name: str, value: Any, kind: type, none: bool = True) -> Any:
    """``value`` if it is a ``kind`` (or None where ``none``), else a TypeError naming ``name``."""
    if (value is None and none) or isinstance(value, kind):
        return value
    raise TypeError(f"{name} must be a {kind.__name__}{' or None' if none else ''}; got {type(value).__name__}")


def refuse_unknown(kwargs: dict[str, Any], known: tuple[str, ...] | Any, where: str) -> None:
    """A TypeError naming the first of ``kwargs`` not in ``known`` (as Python names an unexpected argument)."""
    for key in kwargs:
        if key not in known:
            raise TypeError(f"{where} got an unexpected keyword argument {key!r}")


def check_control_period(control_period: float, time_step: float, refuse: bool, later: str | None = None) -> None:
    """Simulated time must run at the control period's rate: a ``control_period`` (s) that is not a whole number
    of physics steps of ``time_step`` (s) is refused with a ValueError naming it (``refuse``), or, in a released
    id that ran it rounded, warned about (naming the ``later`` id that refuses it)."""
    import warnings

    from paragym.sim.client import divides, physics_steps

    if divides(control_period, time_step):
        return
    said = (f"control_period {control_period!r} s is not a whole number of physics steps of {time_step!r} s: each "
            f"step would be simulated over {physics_steps(control_period, time_step) * time_step:g} s")
    if refuse:
        raise ValueError(f"{said}; choose a control_period that is a multiple of the dynamics' time_step")
    why = f"; {later} refuses it" if later else ""
    warnings.warn(f"{said} (this id's released behaviour{why})", UserWarning, stacklevel=4)


def reward_terms(terms: np.ndarray, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The info's ``reward_<name>`` of each term: a view of column j of ``terms`` (N, T) per name, as
    Gymnasium's MuJoCo v5 envs report their reward's parts. The reward is their sum."""
    return {f"reward_{name}": terms[:, j] for j, name in enumerate(names)}


def knob_table(ladder: tuple[Any, ...], labels: dict[str, str], indent: str = "") -> str:
    """The knobs of every rung of ``ladder`` (a task's rung dataclasses, easiest first) as a reStructuredText
    table whose columns are ``labels`` (field name -> header): the rung pages show it. A pair of numbers reads
    "low-high"."""
    def cell(value: Any) -> str:
        if isinstance(value, tuple):
            return "-".join(f"{v:g}" for v in value)
        return f"{value:g}" if isinstance(value, float) else str(value)

    rows = [("rung", *labels.values())]
    rows += [(f"{k} ({RUNG_NAMES[k]})", *(cell(getattr(r, name)) for name in labels)) for k, r in enumerate(ladder)]
    widths = [max(len(row[c]) for row in rows) for c in range(len(rows[0]))]
    rule = indent + "  ".join("=" * w for w in widths)
    lines = [indent + "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip() for row in rows]
    return "\n".join([rule, lines[0], rule, *lines[1:], rule])
