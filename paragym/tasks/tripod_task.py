"""The mobile tripod's contract (:class:`paragym.tasks.base.Task`, paper 004): the one object the single env,
the vector env, the leaderboard and validation read the task from."""

from __future__ import annotations

from typing import Any

import numpy as np

from paragym.mechanisms import tripod as mt
from paragym.tasks import tripod as scenarios_module
from paragym.tasks.base import BoxSpec, Evaluation, Task, TaskBase, reward_terms
from paragym.tasks.tripod import TripodScenario
from paragym.tasks.tripod_step import (
    ENGINES,
    FAILURES,
    LADDER_RULES,
    LADDER_RULES_V1,
    REWARD_TERMS,
    RULES,
    TripodParams,
    TripodRules,
    TripodState,
    reset,
    step,
)
from paragym.tasks.tripod_worlds import DynamicWorld

#: the task's world: the dynamics, or None (the kinematic model is all there is)
World = DynamicWorld | None

__all__ = ["LADDER_RULES", "LADDER_RULES_V1", "RULES", "TASK", "TripodTask", "detected_fault"]


class TripodTask(TaskBase):
    """The mobile tripod's contract (:class:`paragym.tasks.base.Task`): paper 004's estimation of the drive
    units under slip."""

    name = "tripod"
    scenario_names = scenarios_module.SCENARIOS
    failures = FAILURES
    Scenario = TripodScenario
    Params = TripodParams
    Rules = TripodRules
    State = TripodState
    #: KF validation (dynamic fidelity): the upper plate, sampled at 100 Hz (a slow vehicle)
    engines = ENGINES
    sensor_layout: dict[str, float] = {"r": 0.3, "depth": 0.1, "rate": 100.0}

    def paper_scenario(self) -> TripodScenario:
        return scenarios_module.paper_scenario()

    def random_scenario(self, rng: np.random.Generator, params: TripodParams) -> TripodScenario:
        return self.draw_scenarios("random", [rng], params, None)[0]  # the rung's generator on a rung

    def validate_scenario(self, scenario: TripodScenario, params: TripodParams) -> None:
        scenarios_module.validate_scenario(scenario)

    def draw_scenarios(self, choice: Any, rngs: list[np.random.Generator], params: TripodParams,
                       world: World) -> list[TripodScenario]:
        return scenarios_module.draw_scenarios(choice, rngs, params.rules.rung)

    def spaces(self, params: TripodParams) -> tuple[BoxSpec, BoxSpec]:
        return (BoxSpec(-100.0, 100.0, (params.obs_size,)),
                BoxSpec(-1.0, 1.0, (params.action_size,)))

    def make_world(self, params: TripodParams, n: int, render_mode: str | None) -> World:
        if params.fidelity != "dynamic":
            return None
        return DynamicWorld(params.geometry, params.dynamics, gui=render_mode == "human",
                            calibrated_push=params.rules.rung is not None, engine=params.engine,
                            on_wheels=params.rules.converged)

    def reset(self, state: TripodState, params: TripodParams, rows: np.ndarray, scenarios: list[TripodScenario],
              rngs: list[np.random.Generator], world: World) -> None:
        reset(state, params, rows, scenarios, rngs)
        if world is not None:
            world.reset(state)

    #: the transition itself (:func:`paragym.tasks.tripod_step.step`: the contract's signature)
    step = staticmethod(step)

    def evaluate(self, state: TripodState, params: TripodParams, world: World) -> Evaluation:
        """Success: the drive's end reached with the estimate's mean unit error below ``success_error`` (and,
        in v2, the mechanism never folded), as :func:`paragym.tasks.tripod_step.decide` decided it for every robot
        the transition evaluated."""
        s = state
        if s.evaluation is None:  # the same buffers every call
            numbers = {"unit_error": s.unit_error, "plate_error": s.plate_error, "t": s.drive.t}
            numbers.update(reward_terms(s.terms, REWARD_TERMS))
            s.evaluation = Evaluation(s.success, s.failure, numbers)
        return s.evaluation

    def details(self, state: TripodState, params: TripodParams, world: World, i: int) -> dict[str, Any]:
        s, d = state, state.drive
        info = {"true_units": d.true[i].copy(), "estimate": s.estimate[i].copy(), "odometry": d.odometry[i].copy(),
                "eta": s.eta_read[i].copy(), "detected_fault": detected_fault(state, params, i)}
        if params.trust_action:  # the smoothed encoder distances that v1's correction steers to
            info["encoder_distances"] = s.smoothed[i].copy()
        return info

    def render(self, cache: dict[str, Any], state: TripodState, params: TripodParams, world: World, i: int,
               gui: bool) -> np.ndarray | None:
        from paragym.sim.tripod_scene import TripodScene

        d = state.drive

        def pose(scene: Any) -> None:
            _, rotation, centre = mt.forward(d.true[i:i + 1], eta0=d.eta[i], geometry=params.geometry)
            scene.set_state(d.true[i], centre[0], rotation[0], params.geometry)

        return self.drawn(cache, world, gui, lambda: TripodScene(d.scenarios[i].terrain, gui=gui), pose)


def detected_fault(state: TripodState, params: TripodParams, i: int) -> tuple[int, str] | None:
    """The paper's reading of eq 4 against eq 5 for robot ``i``'s current estimate
    (:func:`paragym.mechanisms.tripod.k_singled_out`, 3 cm): which unit looks faulty, and whether eta says it went
    inward or outward."""
    s = state
    if s.drive.k[i] == 0:
        return None
    k = mt.k_singled_out(s.eta_read[i], s.estimate[i], mt.kernel_consts(params.geometry), 0.03)
    if k < 0:
        return None
    # eta grows when a unit moves inward (eta measured down from the plate)
    return k, "inward (bump or push)" if s.eta_read[i, k] > s.last_eta[i, k] else "outward (hole or slip)"


#: the mobile tripod task (paper 004)
TASK: Task[TripodState, TripodParams, TripodScenario, World] = TripodTask()


