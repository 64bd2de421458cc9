"""A minimal task defined outside paragym's own modules: the proof that adding a task is a recipe.

A point in the plane steers to a goal. The task is one module (this file): its contract
(``TASK``, a :class:`paragym.tasks.base.Task` over N robots), its single and native vector env
(the generic shells, an id's class naming the task and its rules), its bench (``BENCH``: what
the CLI, the leaderboard and the docs know of it) and its registry row (``ROW``), registered on
import. No module of paragym is edited for it (``tests/test_adding_a_task.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import paragym
from paragym.baselines.tasks import Bench, BuiltIn, Column, Target, zero_factory
from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.registry import EnvRow
from paragym.rollout import Episode
from paragym.tasks.base import BoxSpec, Evaluation, Task, TaskBase, check_number, refuse_unknown, resolve_scenario

STEP = 0.05  # m per step at full action
REACH = 0.05  # m: success within this of the goal


@dataclass(frozen=True)
class PointScenario:
    """Where the point starts and where its goal is (m)."""

    name: str
    start: tuple[float, float]
    goal: tuple[float, float]


def paper_scenario() -> PointScenario:
    return PointScenario("paper", (0.0, 0.0), (0.6, 0.3))


def random_scenario(rng: np.random.Generator) -> PointScenario:
    start, goal = rng.uniform(-1.0, 1.0, 2), rng.uniform(-1.0, 1.0, 2)
    return PointScenario("random", (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1])))


def validate_scenario(scenario: PointScenario) -> None:
    """A custom scenario that can run: start and goal, two finite numbers each, inside the square of side 3 m."""
    for name in ("start", "goal"):
        xy = np.asarray(getattr(scenario, name), float)
        if xy.shape != (2,) or not np.all(np.isfinite(xy)) or np.abs(xy).max() > 1.5:
            raise ValueError(f"scenario.{name} must be two finite numbers within +-1.5 m; got {xy}")


@dataclass(frozen=True)
class PointRules:
    """The rules of one version: v0 only."""

    version: int


@dataclass(frozen=True)
class PointParams:
    """The env's arguments."""

    scenario: Any = "random"
    reach: float = REACH
    fidelity: str = "kinematic"

    @classmethod
    def from_kwargs(cls, rules: PointRules, scenario: Any = "random", reach: float = REACH,
                    **unknown: Any) -> PointParams:
        refuse_unknown(unknown, (), "PointReach")
        resolve_scenario(scenario, ("paper", "random"), PointScenario, validate_scenario)
        return cls(scenario, check_number("reach", reach, unit=" m"))


@dataclass
class PointState:
    """N robots: positions, goals and what a step reports."""

    pos: np.ndarray
    goal: np.ndarray
    obs: np.ndarray
    reward: np.ndarray
    terminated: np.ndarray
    scenarios: list[Any] = field(default_factory=list)

    @classmethod
    def empty(cls, n: int, params: PointParams) -> PointState:
        return cls(np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 4), np.float32), np.zeros(n), np.zeros(n, bool),
                   [None] * n)


class PointTask(TaskBase):
    """The task's contract (:class:`paragym.tasks.base.Task`), over N robots."""

    name = "point"
    scenario_names = ("paper", "random")
    failures = (None,)
    Scenario, Params, Rules, State = PointScenario, PointParams, PointRules, PointState

    def paper_scenario(self) -> PointScenario:
        return paper_scenario()

    def random_scenario(self, rng: np.random.Generator, params: PointParams) -> PointScenario:
        return random_scenario(rng)

    def validate_scenario(self, scenario: PointScenario, params: PointParams) -> None:
        validate_scenario(scenario)

    def draw_scenarios(self, choice: Any, rngs: list[np.random.Generator], params: PointParams,
                       world: None) -> list[PointScenario]:
        choice = resolve_scenario(choice, self.scenario_names, PointScenario, validate_scenario)
        if choice == "random":
            return [random_scenario(rng) for rng in rngs]
        return [paper_scenario() if choice == "paper" else choice] * len(rngs)

    def spaces(self, params: PointParams) -> tuple[BoxSpec, BoxSpec]:
        return BoxSpec(-3.0, 3.0, (4,)), BoxSpec(-1.0, 1.0, (2,))

    def make_world(self, params: PointParams, n: int, render_mode: str | None) -> None:
        return None  # the kinematic model is all there is

    def reset(self, state: PointState, params: PointParams, rows: np.ndarray, scenarios: list[PointScenario],
              rngs: list[np.random.Generator], world: None) -> None:
        s = state
        for row, sc in zip(rows, scenarios, strict=True):
            s.pos[row], s.goal[row], s.scenarios[row] = sc.start, sc.goal, sc
        s.reward[rows], s.terminated[rows] = 0.0, False
        _observe(s, rows)

    def step(self, state: PointState, params: PointParams, actions: np.ndarray, active: np.ndarray,
             world: None) -> None:
        s = state
        before = np.linalg.norm(s.goal - s.pos, axis=1)
        s.pos[active] = np.clip(s.pos[active] + STEP * actions[active], -1.5, 1.5)
        after = np.linalg.norm(s.goal - s.pos, axis=1)
        s.reward[active] = (before - after)[active]
        s.terminated[active] = after[active] < params.reach
        _observe(s, np.flatnonzero(active))

    def evaluate(self, state: PointState, params: PointParams, world: None) -> Evaluation:
        s = state
        return Evaluation(s.terminated.copy(), np.zeros(len(s.pos), np.int64),
                          {"distance": np.linalg.norm(s.goal - s.pos, axis=1)})

    def details(self, state: PointState, params: PointParams, world: None, i: int) -> dict[str, Any]:
        return {"position": state.pos[i].copy()}

    def render(self, cache: dict[str, Any], state: PointState, params: PointParams, world: None, i: int,
               gui: bool) -> np.ndarray:
        img = np.full((64, 64, 3), 255, np.uint8)
        for xy, colour in ((state.goal[i], (0, 160, 0)), (state.pos[i], (200, 0, 0))):
            x, y = (np.clip((np.asarray(xy) + 1.5) / 3.0 * 63, 0, 63)).astype(int)
            img[max(0, 63 - y - 2):64 - y + 1, max(0, x - 2):x + 3] = colour
        return img


def _observe(s: PointState, rows: np.ndarray) -> None:
    s.obs[rows] = np.concatenate([s.pos[rows], s.goal[rows] - s.pos[rows]], axis=1)


TASK: Task[PointState, PointParams, PointScenario, None] = PointTask()


class PointReachEnv(ParagymEnv):
    """Steer a point in the plane to its goal.

    ## Description
    A minimal task of the test suite: the point moves by the action, scaled to 5 cm per step.

    ## Action Space
    ``Box(-1, 1, (2,), float32)``: the step, scaled by 5 cm.

    ## Observation Space
    ``Box(-3, 3, (4,), float32)``:

    ====  ==========================
    0-1   the point's position (m)
    2-3   the goal minus the point (m)
    ====  ==========================

    ## Rewards
    The decrease of the distance to the goal (m).

    ## Starting State
    The scenario's start.

    ## Episode End
    Terminated within ``reach`` (5 cm) of the goal (``is_success``); truncated after 50 steps.

    ## Arguments
    ``scenario``: "paper", "random" or a PointScenario; ``reach`` (m); ``render_mode``: "rgb_array".

    ## Version History
    * v0: the test suite's task.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 25}
    task, rules = TASK, PointRules(0)


class PointReachVectorEnv(ParagymVectorEnv):
    """``num_envs`` points stepped together: the same task over N robots."""

    task, rules = TASK, PointRules(0)


class GoStraight:
    """The task's reference: full steps straight at the goal."""

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        d = obs[2:4].astype(np.float64)
        return np.clip(d / max(STEP, np.abs(d).max()), -1.0, 1.0).astype(np.float32)


def go_straight(env: gym.Env, seed: int) -> GoStraight:
    return GoStraight()


def metrics(ep: Episode) -> dict[str, float]:
    return {"final_distance_m": float(ep.infos[-1]["distance"])}


def plot_episode(ep: Episode, path: Path) -> Path:
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(ep.frames[0]).save(path)
    return path


BENCH = Bench(
    task="point",
    metrics=metrics,
    columns=(Column("final_distance_m", "final distance [m]", ".3f"),),
    primary=("final_distance_m", -1),
    reference="go-straight",
    reference_success=1.0,
    policies=(BuiltIn("go-straight", go_straight, "reference", "full steps straight at the goal"),
              BuiltIn("zero", zero_factory, "floor", "stand still")),
    dynamics=None,
    demo="straight at the goal",
    plot_episode=plot_episode,
    solved=(Target("final_distance_m", -1, against="zero", factor=0.5),),
)

ROW = paragym.register_env(EnvRow("paragym/PointReach-v0", "point_task:PointReachEnv", "point_task:PointReachVectorEnv",
                                  50, "point", "paper",
                                  ("paper", "random"), "a point steers to its goal (the test suite's task)",
                                  bench="point_task"))
