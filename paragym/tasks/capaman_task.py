"""The CaPaMan's contract (:class:`paragym.tasks.base.Task`, paper 000): the one object the single env, the
vector env, the leaderboard and validation read the task from."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from paragym.sim.capaman_dynamic import CaPaManDynamicScene
from paragym.sim.capaman_scene import CaPaManScene
from paragym.tasks import capaman as scenarios_module
from paragym.tasks.base import BoxSpec, Evaluation, Task, TaskBase, reward_terms, started
from paragym.tasks.capaman import CaPaManScenario
from paragym.tasks.capaman_step import (
    ENGINES,
    FAILURES,
    LADDER_RULES,
    REWARD_TERMS,
    RULES,
    CaPaManParams,
    CaPaManRules,
    CaPaManState,
    reset,
    step,
)
from paragym.tasks.capaman_worlds import (
    DynamicWorld,
    GridWorld,
    MuJoCoWorld,
    PostWorld,
    SceneWorld,
    World,
    _clusters,
)

__all__ = ["LADDER_RULES", "RULES", "TASK", "CaPaManTask"]


class CaPaManTask(TaskBase):
    """The CaPaMan's contract (:class:`paragym.tasks.base.Task`): paper 000's collision-free tour."""

    name = "capaman"
    scenario_names = scenarios_module.SCENARIOS
    failures = FAILURES
    Scenario = CaPaManScenario
    Params = CaPaManParams
    Rules = CaPaManRules
    State = CaPaManState
    #: KF validation (dynamic fidelity): paper 000's accelerometer array on the movable plate about H
    engines = ENGINES
    vector_fidelities = ("kinematic", "dynamic")
    sensor_layout: dict[str, float] = {}

    def paper_scenario(self) -> CaPaManScenario:
        return scenarios_module.paper_scenario()

    def random_scenario(self, rng: np.random.Generator, params: CaPaManParams) -> CaPaManScenario:
        """One scenario of the paper's generator (a kinematic PyBullet scene of its own checks it), or the
        rung's."""
        if params.rules.rung is not None:  # the rung's generator, which needs no scene
            return scenarios_module.ladder_scenarios([rng], params.rules.rung, params.geometry)[0]
        with _checker(params, None) as scene:
            return scenarios_module.random_scenario(rng, scene, _clusters(params.geometry))

    def validate_scenario(self, scenario: CaPaManScenario, params: CaPaManParams) -> None:
        """A custom scenario's check, in a kinematic PyBullet scene of its own."""
        with _checker(params, None) as scene:
            scenarios_module.validate_scenario(scenario, scene, rung=params.rules.rung)

    def draw_scenarios(self, choice: Any, rngs: list[np.random.Generator], params: CaPaManParams,
                       world: World) -> list[CaPaManScenario]:
        if params.rules.rung is None:
            return scenarios_module.draw_scenarios(choice, rngs, world.checker(), _clusters(params.geometry))
        if scenarios_module.resolve_scenario(choice) == "random":
            return scenarios_module.ladder_scenarios(rngs, params.rules.rung,
                                                     params.geometry)
        if choice == "paper":
            raise ValueError("a rung's scenarios are its own: scenario 'random' or a CaPaManScenario of capsule "
                             "posts (the paper's case stands a cylinder, which the capsule model does not take)")
        with _checker(params, world) as scene:  # the world's checker scene
            scenarios_module.validate_scenario(choice, scene, rung=params.rules.rung)
        return [choice for _ in rngs]

    def vector_params(self, rules: CaPaManRules, kwargs: dict[str, Any]) -> CaPaManParams:
        native = "grid" if rules.rung is None else "posts"
        if kwargs.get("collision", native) != native:
            raise ValueError(f"the native CaPaMan vector env checks collisions with collision={native!r}: use "
                             "gymnasium's sync/async modes for PyBullet's check")
        return super().vector_params(rules, {**kwargs, "collision": native})

    def spaces(self, params: CaPaManParams) -> tuple[BoxSpec, BoxSpec]:
        return (BoxSpec(-1.0, 1.0, (params.obs_size,)), BoxSpec(-1.0, 1.0, (3,)))

    def make_world(self, params: CaPaManParams, n: int, render_mode: str | None) -> World:
        """The grid or the posts (N robots; the checker scene comes when asked), in the dynamic fidelity under
        MuJoCo's dynamics (N robots); the kinematic PyBullet scene or PyBullet's dynamics (one robot)."""
        gui, g = render_mode == "human", params.geometry
        kinematic: GridWorld | PostWorld | None = None
        if params.collision == "grid":
            kinematic = GridWorld(n, g, params.clearance_cap, draws=render_mode is not None, gui=gui)
        if params.collision == "posts":
            kinematic = PostWorld(n, g, params.clearance_cap, params.max_obstacles, draws=render_mode is not None,
                                  gui=gui)
        if kinematic is not None:
            if params.fidelity == "kinematic":
                return kinematic
            # MuJoCo alone: the kernel's collision test in the dynamic fidelity needs it (CaPaManParams)
            return MuJoCoWorld(kinematic, params.dynamics, params.engine, params.control_period, n,
                               params.max_obstacles, gui=gui)
        if params.fidelity == "kinematic":
            return SceneWorld(CaPaManScene(g, gui=gui, clearance_cap=params.clearance_cap,
                                           draws=render_mode is not None))
        return DynamicWorld(CaPaManDynamicScene(g, params.dynamics, gui=gui, clearance_cap=params.clearance_cap,
                                                engine=params.engine),
                            params.control_period)

    @staticmethod
    def _probe(params: CaPaManParams, world: World) -> World | None:
        """v1's look-ahead world: the kinematic one (for the dynamics, the kinematic checker scene)."""
        return world.probe() if params.goal_relative else None

    def reset(self, state: CaPaManState, params: CaPaManParams, rows: np.ndarray, scenarios: list[CaPaManScenario],
              rngs: list[np.random.Generator], world: World) -> None:
        reset(state, params, rows, scenarios, world, self._probe(params, world))

    def step(self, state: CaPaManState, params: CaPaManParams, actions: np.ndarray, active: np.ndarray,
             world: World) -> None:
        step(state, params, actions, active, world, self._probe(params, world))

    def evaluate(self, state: CaPaManState, params: CaPaManParams, world: World) -> Evaluation:
        """Success: the tour T.C.1 -> 2 -> 3 -> 1 complete with no collision (and, in dynamic fidelity, the
        mechanism whole), as :func:`paragym.tasks.capaman_step.decide` decided it for every robot the transition
        evaluated."""
        s = state
        if s.evaluation is None:  # the same buffers every call
            numbers = {"collision": s.collision, "clearance": s.clearance, "reached": s.reached,
                       "target_index": s.target_index, "path_length": s.path_length}
            numbers.update(reward_terms(s.terms, REWARD_TERMS))
            s.evaluation = Evaluation(s.success, s.failure, numbers)
        return s.evaluation

    def details(self, state: CaPaManState, params: CaPaManParams, world: World, i: int) -> dict[str, Any]:
        return {"nearest_part": state.near[i], "alpha": state.alpha[i].copy(), "tool_tip": state.tip[i].copy()}

    def render(self, cache: dict[str, Any], state: CaPaManState, params: CaPaManParams, world: World, i: int,
               gui: bool) -> np.ndarray | None:
        return world.draw(i, started(state.scenarios, i), state.alpha[i], gui)


@contextmanager
def _checker(params: CaPaManParams, world: World | None) -> Iterator[CaPaManScene]:
    """The kinematic scene that checks scenarios: the world's, or one of its own for the call (then closed)."""
    if world is not None:
        yield world.checker()
        return
    scene = CaPaManScene(params.geometry, draws=False)
    try:
        yield scene
    finally:
        scene.close()


#: the CaPaMan task (paper 000)
TASK: Task[CaPaManState, CaPaManParams, CaPaManScenario, World] = CaPaManTask()


