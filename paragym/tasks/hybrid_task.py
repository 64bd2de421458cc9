"""The hybrid's contract (:class:`paragym.tasks.base.Task`, paper 002): the one object the single env, the
vector env, the leaderboard and validation read the task from."""

from __future__ import annotations

from typing import Any

import numpy as np

from paragym.mechanisms import hybrid
from paragym.tasks import hybrid as scenarios_module
from paragym.tasks.base import BROKEN_GAP, BoxSpec, Evaluation, Task, TaskBase, reward_terms
from paragym.tasks.hybrid import HybridScenario
from paragym.tasks.hybrid_step import (
    ENGINES,
    FAILURES,
    LADDER_RULES,
    REWARD_TERMS,
    RULES,
    SPLIT_LADDER_RULES,
    SPLIT_LADDER_RULES_V2,
    HybridParams,
    HybridRules,
    HybridState,
    reset,
    step,
)
from paragym.tasks.hybrid_worlds import DynamicWorld, MuJoCoWorld

#: the task's world: the dynamics, or None (the kinematic model is all there is)
World = DynamicWorld | None

__all__ = ["LADDER_RULES", "RULES", "SPLIT_LADDER_RULES", "SPLIT_LADDER_RULES_V2", "TASK", "HybridTask"]


class HybridTask(TaskBase):
    """The hybrid task's contract (:class:`paragym.tasks.base.Task`): paper 002's hexapod + tripod along a
    polynomial path."""

    name = "hybrid"
    scenario_names = scenarios_module.SCENARIOS
    failures = FAILURES
    Scenario = HybridScenario
    Params = HybridParams
    Rules = HybridRules
    State = HybridState
    #: KF validation (dynamic fidelity): the paper's array scaled to platform E
    engines = ENGINES
    vector_fidelities = ("kinematic", "dynamic")
    sensor_layout: dict[str, float] = {"r": 0.06, "depth": 0.03}

    def paper_scenario(self) -> HybridScenario:
        return scenarios_module.paper_scenario()

    def random_scenario(self, rng: np.random.Generator, params: HybridParams) -> HybridScenario:
        return self.draw_scenarios("random", [rng], params, None)[0]  # the rung's generator on a rung

    def validate_scenario(self, scenario: HybridScenario, params: HybridParams) -> None:
        scenarios_module.validate_scenario(scenario)

    def draw_scenarios(self, choice: Any, rngs: list[np.random.Generator], params: HybridParams,
                       world: World) -> list[HybridScenario]:
        return scenarios_module.draw_scenarios(choice, rngs, params.geometry, params.rules.rung, params.max_delta_step,
                                               params.tau)

    def spaces(self, params: HybridParams) -> tuple[BoxSpec, BoxSpec]:
        return (BoxSpec(-10.0, 10.0, (params.obs_size,)), BoxSpec(-1.0, 1.0, (1 if params.rules.split_only else 4,)))

    def make_world(self, params: HybridParams, n: int, render_mode: str | None) -> World:
        """None in the kinematic fidelity (the kernels are the world); the dynamics of one robot (PyBullet's, or
        MuJoCo's over the PyBullet scene), or of N in MuJoCo alone (``engine.mirror`` False)."""
        if params.fidelity != "dynamic":
            return None
        from paragym.sim.hybrid_dynamic import HybridDynamicScene

        scenes = [HybridDynamicScene(params.geometry, params.dynamics, gui=render_mode == "human" and i == 0,
                                     engine=params.engine) for i in range(n)]
        strict = params.rules.strict_dynamics
        alone = params.engine is not None and not params.engine.mirror
        return (MuJoCoWorld if alone else DynamicWorld)(
            scenes, params.control_period, params.track_tolerance, params.track_angle_tolerance if strict else None,
            BROKEN_GAP if strict else None)

    def reset(self, state: HybridState, params: HybridParams, rows: np.ndarray, scenarios: list[HybridScenario],
              rngs: list[np.random.Generator], world: World) -> None:
        reset(state, params, rows, scenarios)
        if world is not None:
            world.reset(state, rows)

    #: the transition itself (:func:`paragym.tasks.hybrid_step.step`: the contract's signature)
    step = staticmethod(step)

    def evaluate(self, state: HybridState, params: HybridParams, world: World) -> Evaluation:
        """Success: u = 1 reached with every pose singularity-free and within the leg limits (eq 14) and, in
        dynamic fidelity, tracked (and the mechanism whole, v2), as :func:`paragym.tasks.hybrid_step.decide`
        decided it for every robot the transition evaluated."""
        s = state
        if s.evaluation is None:  # the same buffers every call
            numbers = {"step": s.k, "delta": s.delta, "mu_hexapod": s.mu_h, "mu_tripod": s.mu_t, "free": s.free,
                       "within_limits": s.within}
            numbers.update(reward_terms(s.terms, REWARD_TERMS))
            s.evaluation = Evaluation(s.success, s.reason, numbers)
        return s.evaluation

    def details(self, state: HybridState, params: HybridParams, world: World, i: int) -> dict[str, Any]:
        return {"u": float(state.u[state.k[i]]), "offset": state.offset[i].copy(), "lengths": state.lengths[i].copy(),
                "max_delta_step": params.max_delta_step, "j_bar": params.j_bar,
                "tracking_error": 0.0 if world is None else float(world.tracking_error[i]),
                "orientation_error": 0.0 if world is None else float(world.orientation_error[i])}

    def render(self, cache: dict[str, Any], state: HybridState, params: HybridParams, world: World, i: int,
               gui: bool) -> np.ndarray | None:
        from paragym.sim.hybrid_scene import HybridScene

        def pose(scene: Any) -> None:
            solved = hybrid.solve(state.pose[i:i + 1], state.delta[i], params.geometry, validate=False)
            scene.set_state(solved.t_a[0], solved.t_e[0])

        return self.drawn(cache, world, gui, lambda: HybridScene(params.geometry, gui=gui), pose, i)


#: the hybrid task (paper 002)
TASK: Task[HybridState, HybridParams, HybridScenario, World] = HybridTask()


