"""A minimal task defined outside paragym's own modules: the proof that adding a task is a recipe.

A point in the plane steers to a goal. The task is one module (this file): its env, the N = 1
case of a transition written over N robots as paragym's tasks are; its bench (``BENCH``: what
the CLI, the leaderboard and the docs know of it); its registry row (``ROW``), registered on
import. No module of paragym is edited for it (``tests/test_adding_a_task.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

import paragym
from paragym.baselines.tasks import Bench, BuiltIn, Column, Target, zero_factory
from paragym.envs.base import ParagymEnv
from paragym.registry import EnvRow
from paragym.rollout import Episode

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
    def new(cls, n: int) -> PointState:
        return cls(np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 4), np.float32), np.zeros(n), np.zeros(n, bool),
                   [None] * n)


class PointReachEnv(ParagymEnv):
    """Steer a point in the plane to its goal.

    ## Description
    A minimal task of the test suite: the point moves by the action, scaled to 5 cm per step.

    ## Action Space
    ``Box(-1, 1, (2,), float32)``: the step, scaled by 5 cm.

    ## Observation Space
    ``Box(-2, 2, (4,), float32)``:

    ====  ==========================
    0-1   the point's position (m)
    2-3   the goal minus the point (m)
    ====  ==========================

    ## Rewards
    The decrease of the distance to the goal (m).

    ## Starting State
    The scenario's start.

    ## Episode End
    Terminated within 5 cm of the goal (``is_success``); truncated after 50 steps.

    ## Arguments
    ``scenario``: "paper" or "random"; ``render_mode``: "rgb_array".

    ## Version History
    * v0: the test suite's task.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, scenario: str = "random", render_mode: str | None = None) -> None:
        super().__init__(render_mode)
        if scenario not in ("paper", "random"):
            raise ValueError(f"scenario must be 'paper' or 'random'; got {scenario!r}")
        self.scenario_arg = scenario
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = spaces.Box(-2.0, 2.0, (4,), np.float32)
        self.state = PointState.new(1)

    def _start(self, rows: np.ndarray, rngs: list[np.random.Generator], options: dict[str, Any]) -> list[Any]:
        s = self.state
        out = []
        for row, rng in zip(rows, rngs, strict=True):
            sc = paper_scenario() if self.scenario_arg == "paper" else random_scenario(rng)
            s.pos[row], s.goal[row], s.scenarios[row] = sc.start, sc.goal, sc
            out.append(sc)
        s.reward[rows], s.terminated[rows] = 0.0, False
        self._observe_rows(rows)
        return out

    def _transition(self, actions: np.ndarray, active: np.ndarray) -> None:
        s = self.state
        before = np.linalg.norm(s.goal - s.pos, axis=1)
        s.pos[active] = np.clip(s.pos[active] + STEP * actions[active], -1.5, 1.5)
        after = np.linalg.norm(s.goal - s.pos, axis=1)
        s.reward[active] = (before - after)[active]
        s.terminated[active] = after[active] < REACH
        self._observe_rows(np.flatnonzero(active))

    def _observe_rows(self, rows: np.ndarray) -> None:
        s = self.state
        s.obs[rows] = np.concatenate([s.pos[rows], s.goal[rows] - s.pos[rows]], axis=1)

    def _info(self) -> dict[str, Any]:
        s = self.state
        return {"distance": float(np.linalg.norm(s.goal[0] - s.pos[0])), "is_success": bool(s.terminated[0]),
                "failure": None}

    def _render_rgb(self) -> np.ndarray:
        img = np.full((64, 64, 3), 255, np.uint8)
        for xy, colour in ((self.state.goal[0], (0, 160, 0)), (self.state.pos[0], (200, 0, 0))):
            i, j = (np.clip((np.asarray(xy) + 1.5) / 3.0 * 63, 0, 63)).astype(int)
            img[max(0, 63 - j - 2):64 - j + 1, max(0, i - 2):i + 3] = colour
        return img


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

ROW = paragym.register_env(EnvRow("paragym/PointReach-v0", "point_task:PointReachEnv", None, 50, "point", "paper",
                                  ("paper", "random"), "a point steers to its goal (the test suite's task)",
                                  bench="point_task"))
