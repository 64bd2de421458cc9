"""The Orthoglide's contract (:class:`paragym.tasks.base.Task`, paper 003): the one object the single env, the
vector env, the leaderboard and validation read the task from."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from paragym.sim.client import divides, physics_steps
from paragym.tasks import orthoglide as scenarios_module
from paragym.tasks.base import BoxSpec, Evaluation, Task, TaskBase, reward_terms, started
from paragym.tasks.orthoglide import OrthoglideScenario
from paragym.tasks.orthoglide_step import (
    ENGINES,
    FAILURES,
    LADDER_RULES,
    LADDER_RULES_V1,
    REWARD_TERMS,
    RULES,
    OrthoglideParams,
    OrthoglideRules,
    OrthoglideState,
    reset,
    step,
)
from paragym.tasks.orthoglide_worlds import DynamicWorld, MuJoCoWorld

#: the task's world: the dynamics, or None (the kinematic model is all there is)
World = DynamicWorld | None

__all__ = ["LADDER_RULES", "LADDER_RULES_V1", "RULES", "TASK", "OrthoglideTask"]


class OrthoglideTask(TaskBase):
    """The Orthoglide task's contract (:class:`paragym.tasks.base.Task`): paper 003's path tracking with the
    2PRR and its table."""

    name = "orthoglide"
    scenario_names = scenarios_module.SCENARIOS
    failures = FAILURES
    Scenario = OrthoglideScenario
    Params = OrthoglideParams
    Rules = OrthoglideRules
    State = OrthoglideState
    #: KF validation (dynamic fidelity): the tool holder at C on link AC, the array in the table's plane, 3 cm
    #: below
    engines = ENGINES
    vector_fidelities = ("kinematic", "dynamic")
    sensor_layout: dict[str, float] = {"r": 0.05, "depth": 0.03}

    def paper_scenario(self) -> OrthoglideScenario:
        return scenarios_module.paper_scenario()

    def random_scenario(self, rng: np.random.Generator, params: OrthoglideParams) -> OrthoglideScenario:
        return self.draw_scenarios("random", [rng], params, None)[0]  # the rung's generator on a rung

    def validate_scenario(self, scenario: OrthoglideScenario, params: OrthoglideParams) -> None:
        scenarios_module.validate_scenario(scenario, params.geometry)

    def draw_scenarios(self, choice: Any, rngs: list[np.random.Generator], params: OrthoglideParams,
                       world: World) -> list[OrthoglideScenario]:
        drawn = scenarios_module.draw_scenarios(choice, rngs, params.geometry, params.rules.rung)
        if world is not None and not world.exact_time:
            _warn_rounded_time(drawn, world)
        return drawn

    def spaces(self, params: OrthoglideParams) -> tuple[BoxSpec, BoxSpec]:
        return (BoxSpec(-10.0, 10.0, (params.obs_size,)),
                BoxSpec(-1.0, 1.0, (3 if params.joint_mode else 1,)))

    def make_world(self, params: OrthoglideParams, n: int, render_mode: str | None) -> World:
        if params.fidelity != "dynamic":
            return None
        from paragym.sim.orthoglide_dynamic import OrthoglideDynamicScene

        scenes = [OrthoglideDynamicScene(params.geometry, params.dynamics, gui=render_mode == "human" and i == 0,
                                         table_below_guides=params.rules.table_below_guides, engine=params.engine)
                  for i in range(n)]
        alone = params.engine is not None and not params.engine.mirror  # MuJoCo alone: N robots at once
        return (MuJoCoWorld if alone else DynamicWorld)(scenes, exact_time=params.rules.exact_time)

    def reset(self, state: OrthoglideState, params: OrthoglideParams, rows: np.ndarray,
              scenarios: list[OrthoglideScenario], rngs: list[np.random.Generator], world: World) -> None:
        reset(state, params, rows, scenarios)
        if world is not None:
            world.reset(state, rows)

    #: the transition itself (:func:`paragym.tasks.orthoglide_step.step`: the contract's signature)
    step = staticmethod(step)

    def evaluate(self, state: OrthoglideState, params: OrthoglideParams, world: World) -> Evaluation:
        """Success: the path's end reached without a failure (a joint limit, the working mode, a singularity;
        in v1 the tracking, and a broken mechanism), as :func:`paragym.tasks.orthoglide_step.decide` decided it
        for every robot the transition evaluated."""
        s = state
        if s.evaluation is None:  # the same buffers every call
            numbers = {"kappa": s.kappa, "tracking_error": s.err, "step": s.k}
            if params.rules.rung is not None:  # the mean kappa so far and the most a success may have
                numbers.update(mean_kappa=s.mean_kappa, kappa_bound=s.bound)
            numbers.update(reward_terms(s.terms, REWARD_TERMS))
            s.evaluation = Evaluation(s.success, s.reason, numbers)
        return s.evaluation

    def details(self, state: OrthoglideState, params: OrthoglideParams, world: World, i: int) -> dict[str, Any]:
        return {"rho": state.rho[i].copy()}

    def render(self, cache: dict[str, Any], state: OrthoglideState, params: OrthoglideParams, world: World, i: int,
               gui: bool) -> np.ndarray | None:
        from paragym.sim.orthoglide_scene import OrthoglideScene

        return self.drawn(cache, world, gui, lambda: OrthoglideScene(params.geometry, gui=gui),
                          lambda scene: scene.set_state(state.rho[i].copy(), started(state.scenarios, i).points), i)


def _warn_rounded_time(drawn: list[OrthoglideScenario], world: DynamicWorld) -> None:
    """v0 in dynamic fidelity simulates each path step over whole physics steps: say so where that is not the
    path's own time (its hole; v1 simulates it exactly)."""
    h = world.scene.base_step
    for path in drawn:
        dt = np.diff(path.t)
        if not all(divides(float(d), h) for d in np.unique(dt)):
            simulated = sum(physics_steps(float(d), h) * h for d in dt)
            warnings.warn(f"the path's {path.t[-1]:g} s are simulated over {simulated:g} s: the dynamic fidelity "
                          f"of paragym/Orthoglide2PRRKappa-v0 rounds each path step to whole physics steps of "
                          f"{h:g} s; v1 and later ids simulate it exactly", UserWarning, stacklevel=4)


#: the Orthoglide task (paper 003)
TASK: Task[OrthoglideState, OrthoglideParams, OrthoglideScenario, World] = OrthoglideTask()


