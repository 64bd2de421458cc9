"""The hybrid's bench (paper 002): its leaderboard metrics, policies, physics settings and CLI adapters."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from paragym import registry
from paragym.baselines.tasks import (
    Ablation,
    AblationRow,
    Bench,
    BuiltIn,
    Column,
    Option,
    Target,
    best_constant_floors,
    init_defaults,
    tightest,
    zero_factory,
)
from paragym.rollout import Episode
from paragym.sim.hybrid_dynamic import HybridDynamics

#: the rungs of the hybrid's difficulty ladder v0 (:func:`paragym.registry.ladders`): v2's rules on their own pairs
LADDER = tuple(r.id for r in registry.ladders("hybrid")[0])
#: the rungs of its ladders v1 and v2: v2's rules with the split as the only lever, on their own pairs
SPLIT_LADDER = tuple(r.id for rungs in registry.ladders("hybrid")[1:] for r in rungs)
V2 = ("paragym/HybridSingularityFree-v2", *LADDER)
BEFORE_V2 = ("paragym/HybridSingularityFree-v0", "paragym/HybridSingularityFree-v1")
#: HybridSingularityFree-v2's reference plans its strokes this far (m) inside their limits, where it can: a
#: simulated actuator chasing a stroke planned at its limit overshoots it by up to 0.5 mm
STROKE_MARGIN = 0.001
#: how many detours v2's and the rungs' reference may take where its split schedule cannot follow the splits that
#: work (the planner's step 4, ``max_repairs``): the rungs draw paths on which some split works at every pose but
#: the working splits jump faster than the rate limit lets Delta move
MAX_REPAIRS = 20
#: the best constant action of each rung: :func:`paragym.baselines.simple.best_constant` over {-1, 0, 1}^4 on reset
#: seeds 0-29 (26, 26 and 24 of 30 successes on the easy, medium and hard rungs: the rungs are drawn for the split
#: alone, and E held 20 mm above its path clears the leg limit). On v2 the
#: zero action is the best (13 of 30), which the zero floor already ranks.
BEST_CONSTANT = {LADDER[0]: (0.0, 0.0, 0.0, 1.0), LADDER[1]: (0.0, 0.0, 0.0, 1.0), LADDER[2]: (0.0, 0.0, 0.0, 1.0)}
#: the horizons (samples) of the lookahead rule ranked on the ladder v1: each rung's generator makes it fail at
#: its own (:data:`paragym.tasks.hybrid.SPLIT_LADDER`); 20 is a longer sight than any rung's
LOOKAHEADS = (1, 5, 20)
#: the ids whose observation shows the end pose's stroke excess and its change with the split (v1's indices 45-47)
SHOWS_EXCESS = ("paragym/HybridSingularityFree-v1", "paragym/HybridSingularityFree-v2", *LADDER)


def metrics(ep: Episode) -> dict[str, float]:
    """The per-episode numbers the leaderboard averages into the bench's columns."""
    mu = np.array([[i["mu_hexapod"], i["mu_tripod"]] for i in ep.infos])
    within = np.array([i["within_limits"] for i in ep.infos])
    free = np.array([i["free"] for i in ep.infos])
    offsets = np.array([i["offset"] for i in ep.infos])
    return {"min_mu": float(mu.min()), "limit_violations": float((~within).sum()),
            "bad_poses": float((~free).sum()), "max_detour_mm": float(np.abs(offsets).max() * 1000)}


def polynomial_detour(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode, seeded (a :class:`BuiltIn` factory)."""
    from paragym.planners.polynomial_detour import PolynomialDetourPolicy

    return PolynomialDetourPolicy()


def polynomial_detour_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner

    # the planner as v0's and v1's rows were made: step 4 did not exist (max_repairs 0), so it is not named
    return {"planner": init_defaults(PolynomialDetourPlanner, omit=("max_repairs",))}


def polynomial_detour_margin(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode, seeded (a :class:`BuiltIn` factory)."""
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner, PolynomialDetourPolicy

    u = env.unwrapped
    return PolynomialDetourPolicy(PolynomialDetourPlanner(u.geometry, j_bar=u.j_bar, stroke_margin=STROKE_MARGIN,
                                                          max_repairs=MAX_REPAIRS))


def polynomial_detour_margin_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner

    return {"planner": {**init_defaults(PolynomialDetourPlanner, geometry=None), "stroke_margin": STROKE_MARGIN,
                        "j_bar": "the env's", "max_repairs": MAX_REPAIRS}}


def split_reference(env: gym.Env, seed: int) -> Any:
    """A fresh policy for one episode (a :class:`BuiltIn` factory): the ladder v1's reference, paper 002's
    serial optimisation of the split (the planner with no offset to detour by: ``j_bar`` 0) commanding the
    split alone; the rung's generator certifies that it plans every drawn pair."""
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner, PolynomialDetourPolicy

    return PolynomialDetourPolicy(PolynomialDetourPlanner(env.unwrapped.geometry, j_bar=0.0,
                                                          stroke_margin=STROKE_MARGIN), split_only=True)


def split_reference_params() -> dict[str, Any]:
    """The settings its policy plays with, as the leaderboard records them."""
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner

    return {"planner": {**init_defaults(PolynomialDetourPlanner, geometry=None), "stroke_margin": STROKE_MARGIN,
                        "j_bar": 0.0}, "split_only": True}


class Lookahead:
    """The ladder v1's model rule: the split rate among 0, -1, +1 that keeps the next ``horizon`` samples of the
    nominal path furthest inside eq 14's bounds, the split moved at that rate
    (:func:`paragym.tasks.hybrid.lookahead_split`, the rule each rung's generator makes fail at its horizons).
    It knows the kinematics and the whole path (``info["scenario"]``) and plans nothing."""

    def __init__(self, horizon: int) -> None:
        self.horizon = horizon

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        from paragym.tasks.hybrid import nominal_rows, split_args

        sc = info["scenario"]
        self.path = nominal_rows(np.array([sc.p0]), np.array([sc.p1]))[0]
        _, self.consts, self.limits = split_args(sc.geometry)
        self.step, self.work, self.lengths = info["max_delta_step"], np.empty((5, 6, 6)), np.empty(9)

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        from paragym.tasks.hybrid import lookahead_split

        rate = lookahead_split(self.path, info["step"], info["delta"], self.horizon, self.step, self.consts,
                               self.limits, self.lengths, self.work)
        return np.array([rate], np.float32)


def lookahead(horizon: int) -> Any:
    """The :class:`BuiltIn` factory of :class:`Lookahead` at ``horizon``."""
    return lambda env, seed: Lookahead(horizon)


class StrokeRule:
    """The ladder v1's two-line rule, read from the observation: when the hexapod's strokes (indices 14-19) are
    the nearer to a limit and beyond ``threshold`` of the half range, step Delta ``sign``; when the tripod's
    (20-22) are, step it the other way; else hold. ``sign`` and ``threshold`` are the best of {+1, -1} x
    {0.5, 0.7, 0.85, 0.95} on the easy rung's reset seeds 0-29 (by successes, then mean return)."""

    def __init__(self, threshold: float = 0.7, sign: float = 1.0) -> None:
        self.threshold, self.sign = threshold, sign

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        hexapod, tripod = float(np.abs(obs[14:20]).max()), float(np.abs(obs[20:23]).max())
        if max(hexapod, tripod) <= self.threshold:
            return np.zeros(1, np.float32)
        return np.array([self.sign if hexapod >= tripod else -self.sign], np.float32)


def plot_episode(ep: Episode, path: Path) -> Path:
    """The demo's picture of one episode, written to ``path``."""
    from paragym.plots.hybrid import plot_episode as plot_hybrid_episode

    return plot_hybrid_episode(ep, path)


def plan(env: gym.Env, args: argparse.Namespace, out: Path, stem: str) -> int:
    """Paper 002's planner on the env's scenario, as the id's reference plans it: figures, nominal vs planned."""
    import json

    from paragym.mechanisms import hybrid
    from paragym.plots.hybrid import plot_plan as plot_hybrid_plan
    from paragym.trajectories import nominal_path

    obs, info = env.reset(seed=args.seed)
    sc = info["scenario"]
    g = sc.geometry
    policy = BENCH.reference_of(env.spec.id).factory(env, args.seed)
    policy.reset(obs, info)
    plan = policy.plan
    nominal = hybrid.solve(nominal_path(np.array(sc.p0), np.array(sc.p1))[1], 0.5, g, validate=False)
    rows = (("nominal, Delta = 0.5", nominal.free, nominal.lengths, nominal.mu_hexapod, nominal.mu_tripod),
            ("planned", plan.free, plan.lengths, plan.mu_hexapod, plan.mu_tripod))
    print(f"{'':22s} {'singular/limit poses':>21s} {'strokes [mm]':>16s} {'min mu hexapod':>15s} "
          f"{'min mu tripod':>14s}")
    stats = {}
    for name, free, lengths, mu_h, mu_t in rows:
        print(f"{name:22s} {int((~free).sum()):>13d} of {len(free):<5d} {lengths.min() * 1000:7.1f}-"
              f"{lengths.max() * 1000:6.1f} {mu_h.min():15.3f} {mu_t.min():14.3f}")
        stats[name] = {"bad_poses": int((~free).sum()), "stroke_range_m": [float(lengths.min()), float(lengths.max())],
                       "min_mu_hexapod": float(mu_h.min()), "min_mu_tripod": float(mu_t.min())}
    methods = np.bincount(plan.method, minlength=3)
    print(f"Delta {plan.delta.min():.2f}-{plan.delta.max():.2f}; samples: {methods[0]} nominal, {methods[1]} serial, "
          f"{methods[2]} detour (largest offset {np.abs(plan.offsets).max() * 1000:.1f} mm); limits "
          f"{g.l_min * 1000:.2f}-{g.l_max * 1000:.2f} mm, singular below {g.singularity_threshold}")
    title = (f"paper 002 planner, {sc.name} scenario: {int((~plan.free).sum())} singular/limit poses "
             f"(nominal at Delta = 0.5: {int((~nominal.free).sum())})")
    png = plot_hybrid_plan(plan, out / f"{stem}.png", title, g.l_min, g.l_max, g.singularity_threshold)
    (out / f"{stem}.json").write_text(json.dumps({"scenario": sc.name, "p0": sc.p0, "p1": sc.p1, **stats,
                                                  "delta": plan.delta.tolist(), "offsets_m": plan.offsets.tolist(),
                                                  "strokes_m": plan.lengths.tolist()}, indent=2))
    print(f"wrote {png} and {out / (stem + '.json')}")
    return 0


def validate_plan(env: gym.Env, args: argparse.Namespace, out: Path, stem: str) -> int:
    """Plan (paper 002), drive the nine actuators in the dynamic model, compare E, validate, report."""
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner
    from paragym.validation.hybrid import validate_hybrid
    from paragym.validation.report import write_report

    stem += f"_{args.duration:g}s"
    obs, info = env.reset(seed=args.seed)
    sc = info["scenario"]
    plan = PolynomialDetourPlanner(sc.geometry).plan(np.array(sc.p0), np.array(sc.p1))
    print(f"plan: {int((~plan.free).sum())} singular/limit poses; executing the nine strokes over "
          f"{args.duration:.1f} s in the dynamic simulation ...")
    val = validate_hybrid(plan, args.duration, seed=args.seed)
    rep = val.report
    print(f"platform E against the plan: position error at most {val.position_error * 1000:.2f} mm, orientation "
          f"{np.degrees(val.orientation_error):.3f} deg; ball-joint gaps at most {val.run.closure_error * 1000:.3f} mm")
    print(rep.table())
    return write_report(rep, out / stem, f"hybrid, {sc.name} scenario, {args.duration:.1f} s: "
                                         f"{'PASS' if rep.passed else 'FAIL'}",
                        {"duration_s": args.duration, "position_error_m": val.position_error,
                         "orientation_error_rad": val.orientation_error, "closure_error_m": val.run.closure_error})


def validated_plan(seed: int) -> tuple[bool, dict[str, Any]]:
    """The leaderboard's KF validation of the reference plan on the paper's case: (passed, its summary)."""
    from paragym.planners.polynomial_detour import PolynomialDetourPlanner
    from paragym.tasks.hybrid import paper_scenario
    from paragym.validation.hybrid import validate_hybrid

    sc = paper_scenario()
    plan = PolynomialDetourPlanner(sc.geometry).plan(np.array(sc.p0), np.array(sc.p1))
    val = validate_hybrid(plan, 2.0, seed=seed)
    return val.report.passed, {"text": f"paper 002 plan over 2 s executed by the stage dynamics, accelerometers + "
                                       f"Kalman filter (RTS); {tightest(val.report)}; E within "
                                       f"{val.position_error * 1000:.2f} mm of the plan",
                               "position_error_m": val.position_error}


#: the ablation behind v1 (``benchmarks/ablation.py --task hybrid``), its rows in the order they were tried
ABLATION = Ablation(
    rows=(
        AblationRow("v0, the shipped PPO setup", "paragym/HybridSingularityFree-v0", {}, {}, 2_000_000),
        AblationRow("v1 as released: P1, P1 solved at the split, its stroke excess and look-ahead in the observation",
         "paragym/HybridSingularityFree-v1", {}, {}, 2_000_000),
        AblationRow("v1 + shaping toward a feasible end, w_end 10", "paragym/HybridSingularityFree-v1",
                    {"w_end": 10.0}, {},
         2_000_000),
        AblationRow("the same, longer", "paragym/HybridSingularityFree-v1", {"w_end": 10.0}, {}, 3_000_000),
        AblationRow("v1 + shaping, w_end 30", "paragym/HybridSingularityFree-v1", {"w_end": 30.0}, {}, 2_000_000),
    ),
    beside=("paragym/HybridSingularityFree-v1", ("zero", "polynomial-detour")),
    metric=("singular/limit poses", lambda infos: float(sum(not i["free"] for i in infos))),
    ppo_from="paragym/HybridSingularityFree-v1",
)



class GreedySplit:
    """The hybrid's naive controller (v1 on): E on the nominal path (zero offset), and the split Delta stepped,
    a whole ``max_delta_step`` a step, toward the lower stroke excess of the end pose P1 that the observation
    shows (indices 45-47: e(Delta) and its change one step up and one step down), held where that excess is 0
    or no step lowers it. One line of arithmetic on the observation, blind to the singularities and to the
    strokes along the way."""

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        up, down = float(obs[46]), float(obs[47])
        step = 0.0 if obs[45] <= 0 or min(up, down) >= 0 else (1.0 if up < down else -1.0)
        return np.array([step, 0.0, 0.0, 0.0], np.float32)


def greedy_split(env: gym.Env, seed: int) -> GreedySplit:
    """The naive controller (:class:`GreedySplit`): a floor."""
    return GreedySplit()

BENCH = Bench(
    ablation=ABLATION,
    task="hybrid",
    options=(Option(("validate",), "--duration", float, 2.0, "seconds for the whole path"),),
    metrics=metrics,
    columns=(Column("min_mu", "min singularity measure", ".3f"),
             Column("limit_violations", "leg-limit poses", ".1f", exact=True),
             Column("bad_poses", "singular/limit poses", ".1f", exact=True),
             Column("max_detour_mm", "max detour [mm]", ".1f")),
    primary=("bad_poses", -1),  # the paper's method: every pose singularity-free within the limits
    reference="polynomial-detour",
    reference_success=0.95,  # 1.00 over the full suite
    policies=(
        BuiltIn("polynomial-detour", polynomial_detour, "reference",
                "7th-degree path + serial optimisation of Delta + detour via-poses (paper 002)",
                polynomial_detour_params, ids=BEFORE_V2),
        BuiltIn("polynomial-detour", polynomial_detour_margin, "reference",
                "7th-degree path, serial optimisation of Delta, detour via poses (paper 002), strokes planned 1 mm "
                "inside their limits where the path allows", polynomial_detour_margin_params, ids=V2),
        BuiltIn("polynomial-detour", split_reference, "reference",
                "7th-degree path, serial optimisation of Delta (paper 002; no offset to detour by: the split is the "
                "only lever), strokes planned 1 mm inside their limits where the path allows", split_reference_params,
                ids=SPLIT_LADDER),
        *(BuiltIn(f"lookahead-{h}", lookahead(h), "floor", f"the model rule: the split rate of 0, -1, +1 that keeps "
                  f"the next {h} samples furthest inside eq 14's bounds", {"horizon": h}, ids=SPLIT_LADDER)
          for h in LOOKAHEADS),
        BuiltIn("stroke-rule", lambda env, seed: StrokeRule(), "floor", "the two-line rule: Delta stepped up when "
                "the hexapod's strokes are the nearer to a limit and beyond 0.7 of the half range, down when the "
                "tripod's are", lambda: init_defaults(StrokeRule), ids=SPLIT_LADDER),
        BuiltIn("zero", zero_factory, "floor",
                "= nominal only: the unplanned 7th-degree path at Delta = 0.5 (paper 002's starting point)"),
        BuiltIn("greedy-split", greedy_split, "floor", "the naive controller: the nominal path, the split stepped "
                "toward the end pose's lower stroke excess shown in the observation", ids=SHOWS_EXCESS),
        *best_constant_floors(BEST_CONSTANT, "the split's rate and E's offset from the nominal path {action} "
                              "(in the action's units), the best of {{-1, 0, 1}}^4 on reset seeds 0-29"),
    ),
    dynamics=HybridDynamics.fast,  # the env's default
    demo="polynomial + serial + detour (paper 002)",
    plot_episode=plot_episode,
    plan=plan,
    validate_plan=validate_plan,
    validated_plan=validated_plan,  # v1 and v2 validate v0's plan: the same check, run once
    solved=(Target("success", +1, 0.95),),
)
