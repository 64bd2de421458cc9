"""``paragym/HybridSingularityFree-v0``: the hexapod + tripod along a polynomial path (paper 002).

The single env and the native vector env are shells over one transition,
:mod:`paragym.tasks.hybrid_step` (the single env is its N = 1 case); the
scenarios come from :mod:`paragym.tasks.hybrid`.
"""

from __future__ import annotations

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.tasks.base import renamed
from paragym.tasks.hybrid import (
    SPLIT_LADDER_V2,
    HybridScenario,
    knob_table,
    paper_scenario,
    random_scenario,
    random_scenarios,
    split_knob_table,
)
from paragym.tasks.hybrid_task import LADDER_RULES, RULES, SPLIT_LADDER_RULES, SPLIT_LADDER_RULES_V2, TASK

__all__ = ["HybridScenario", "HybridSingularityFreeEasyEnv", "HybridSingularityFreeEasyV1Env",
           "HybridSingularityFreeEasyV1VectorEnv", "HybridSingularityFreeEasyVectorEnv",
           "HybridSingularityFreeEnv", "HybridSingularityFreeHardEnv", "HybridSingularityFreeHardV1Env",
           "HybridSingularityFreeHardV1VectorEnv", "HybridSingularityFreeHardVectorEnv",
           "HybridSingularityFreeMediumEnv", "HybridSingularityFreeMediumV1Env",
           "HybridSingularityFreeMediumV1VectorEnv", "HybridSingularityFreeMediumVectorEnv",
           "HybridSingularityFreeV1Env", "HybridSingularityFreeV1VectorEnv", "HybridSingularityFreeV2Env",
           "HybridSingularityFreeV2VectorEnv", "HybridSingularityFreeEasyV2Env", "HybridSingularityFreeEasyV2VectorEnv",
           "HybridSingularityFreeMediumV2Env", "HybridSingularityFreeMediumV2VectorEnv",
           "HybridSingularityFreeHardV2Env", "HybridSingularityFreeHardV2VectorEnv",
           "HybridSingularityFreeVectorEnv", "paper_scenario",
           "random_scenario", "random_scenarios"]


class HybridSingularityFreeEnv(ParagymEnv):
    """Move a hexapod + tripod's end-effector along a polynomial path without
    singular poses or leg-limit violations.

    ## Description
    Paper 002 (Rakhodaei, Ding, Saadat, Rastegarpanah): a 6-UPU hexapod
    carries a 3-RPS tripod (nine prismatic actuators). The end-effector E
    follows the rest-to-rest 7th-degree path from P0 to P1 (eq 17); the
    episode walks u from 0 to 1 in steps of tau = 0.01. At each step the agent
    chooses how the motion is split between the stages (Delta, eqs 19-20) and
    may offset E's position from the nominal path by at most J-bar (the
    paper's detour); the kinematics is :mod:`paragym.mechanisms.hybrid`.

    ## Action Space
    ``Box(-1, 1, (4,), float32)``: the change of Delta (times
    ``max_delta_step`` = 0.05, Delta held in [0, 1]) and the offset of E's
    x, y, z from the nominal path (times ``j_bar`` = 20 mm). The last pose is
    P1 exactly: its offset is ignored.
    An action outside the Box is clipped to it (the rule of every paragym env,
    :func:`paragym.envs.base.check_action`); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``.

    ## Observation Space
    ``Box(-10, 10, (28,), float32)``:

    ==========  ==========================================================
    0           u, the path parameter (0 to 1)
    1-6         the nominal pose of E at this step (x, y, z / 0.1 m, roll, pitch, yaw / 0.5 rad)
    7-12        the nominal pose at the next step, scaled the same
    13          Delta, the split between the stages (0 to 1)
    14-22       the nine strokes, mapped so that L_min -> -1 and L_max -> +1
    23-24       the singularity measures of the hexapod and the tripod (1 at home, singular below 0.2)
    25-27       the current offset of E from the nominal path / j_bar
    ==========  ==========================================================

    ## Rewards
    Every step's info holds the reward's terms, ``reward_<name>`` for offset, delta, singular, limit, end_shaping
    (:data:`paragym.tasks.hybrid_step.REWARD_TERMS`, since paragym 0.10); the reward is their sum.
    Per step: ``-w_offset |offset| / j_bar`` (deviation from the nominal
    path) ``- w_delta |change of Delta| / max_delta_step`` (smoothness)
    ``- w_singular * sum of (0.4 - mu)_+ / 0.4`` over both measures
    (closeness to singularity) ``- w_limit * (legs out of limits)``.

    ## Starting State
    u = 0, Delta = 0.5, E at P0 (``info["scenario"]``: a frozen HybridScenario).

    ## Episode End
    Terminated after the step that reaches u = 1 (100 steps);
    ``info["is_success"]`` when every pose of the episode was
    singularity-free and within the limits (eq 14).

    ## Arguments
    ``scenario``: "random" (default), "paper" or a HybridScenario;
    ``max_delta_step``, ``j_bar`` (m), ``w_offset``, ``w_delta``,
    ``w_singular``, ``w_limit``, ``geometry``, ``render_mode``.
    ``fidelity``: "kinematic" (default: E goes where the action says and
    the legs are solved) or "dynamic" (:mod:`paragym.sim.hybrid_dynamic`:
    the nine prismatic actuators, position-controlled with a force limit,
    chase the commanded pose's strokes for ``control_period`` s (0.05 s: the
    path in 5 s) under gravity; the pose, the offset, the strokes and both
    measures are then read from the simulated platforms, so a leg that
    cannot follow or a platform that sags costs reward; a step whose E is
    more than ``track_tolerance`` (5 mm) from its command is not free, so
    the episode fails). ``dynamics``: a
    :class:`~paragym.sim.hybrid_dynamic.HybridDynamics` (default
    ``HybridDynamics.fast()``). ``info["tracking_error"]`` (m) is E's distance
    from its command (0 in kinematic fidelity). ``engine``: the dynamic
    fidelity's physics, "pybullet" (default) or "mujoco" (or a
    :class:`~paragym.sim.mujoco_sim.MuJoCoSettings`): the same model, rules
    and checks in MuJoCo (the ``mujoco`` extra; the conformance page
    compares the engines). ``engine=MuJoCoSettings(mirror=False)``: MuJoCo
    alone (no PyBullet scene; a ball joint's gap as MuJoCo's loop closures
    have it), each control period from a cold solver start; the native
    vector env runs it for N robots at once (``gym.make_vec(ID, N,
    vectorization_mode="vector_entry_point", fidelity="dynamic",
    engine="mujoco")``), and this env is its N = 1 case, bit for bit.

    ## Version History
    * v0: initial release (kinematic fidelity).
      Since paragym 0.6.0 ``fidelity="dynamic"`` is offered; the default,
      kinematic, is unchanged.
      Since paragym 0.2.0 a custom scenario that cannot run (NaN, outside
      the workspace, malformed) and non-dict ``options`` are refused at reset
      with a ValueError or TypeError naming them; every episode that ran
      before runs the same (tested against recorded rollouts).
    * v1 (paragym 0.5.0): :class:`HybridSingularityFreeV1Env`, the end of
      the path added to the observation; v0 is unchanged.
    * v2 (paragym 0.8.0): :class:`HybridSingularityFreeV2Env`, the dynamic
      fidelity tracks E's orientation and ends a broken mechanism. v0's and
      v1's holes, kept so that their episodes replay: a dynamic step is free
      whatever E's orientation; since 0.8.0 ``info["orientation_error"]``
      and ``info["failure"]`` report it, and a custom ``control_period``
      that the physics step does not divide warns.
    * paragym 0.10, every version: one lifecycle (a step after termination, before reset or after
      ``close`` is refused; unknown reset options too; no copy shares a PyBullet client) and the
      reward's terms in the info; every episode runs as before.
    * paragym 0.10, every version: the ``engine`` argument; "mujoco" runs the dynamic fidelity in
      MuJoCo; PyBullet's, the default, runs as before. MuJoCo alone
      (``MuJoCoSettings(mirror=False)``) and the native dynamic vector env.
    """

    task, rules = TASK, RULES[0]


class HybridSingularityFreeV1Env(HybridSingularityFreeEnv):
    """``paragym/HybridSingularityFree-v1``: v0's mechanism, scenarios,
    action, reward and success, with an observation that shows where the
    path ends.

    ## Observation Space
    ``Box(-10, 10, (48,), float32)``:

    ==========  ==========================================================
    0           u, the path parameter (0 to 1)
    1-6         the nominal pose of E at this step (x, y, z / 0.1 m, roll, pitch, yaw / 0.5 rad)
    7-12        the nominal pose at the next step, scaled the same
    13          Delta, the split between the stages (0 to 1)
    14-22       the nine strokes, mapped so that L_min -> -1 and L_max -> +1
    23-24       the singularity measures of the hexapod and the tripod (1 at home, singular below 0.2)
    25-27       the current offset of E from the nominal path / j_bar
    28-33       P1 (x, y, z / 0.1 m, angles / 0.5 rad)
    34-42       P1's nine strokes solved at the current Delta (L_min -> -1, L_max -> +1)
    43-44       P1's two singularity measures at the current Delta
    45          P1's stroke excess e(Delta) x 10: how far its strokes are beyond their limits,
                summed, in units of half the stroke range (0: within limits)
    46-47       e(Delta + max_delta_step) - e(Delta) and e(Delta - max_delta_step) - e(Delta), x 100
    ==========  ==========================================================

    (:mod:`paragym.tasks.hybrid_step`.)

    ## Rewards
    v0's. ``w_end`` > 0 adds a potential-based shaping toward a feasible end
    (it sums to ``w_end`` x e(0.5) over any episode); it is 0 by default,
    because with it PPO did worse.

    ## Action Space, Starting State, Episode End, Arguments
    As v0, plus ``w_end`` (default 0).

    ## Version History
    * v1 (paragym 0.5.0): the observation above; the scenarios, action,
      reward, success and end are v0's.
    """

    rules = RULES[1]


class HybridSingularityFreeV2Env(HybridSingularityFreeV1Env):
    """``paragym/HybridSingularityFree-v2``: v1's task, with a dynamic
    fidelity whose tracking covers E's orientation and whose mechanism can
    break.

    ## Episode End
    As v1 (u = 1; ``is_success`` when every step was free), and in dynamic
    fidelity a ball joint open by more than 5 mm (a broken mechanism) ends
    the episode as a failure. A step is free only if E is within
    ``track_tolerance`` (5 mm) of its commanded position and within
    ``track_angle_tolerance`` (1 deg) of its commanded orientation: the
    reference, planned 1 mm inside the stroke limits, stays within 2.2 mm
    and 0.44 deg over the paper's and 15 random paths. ``info["failure"]``
    names the first reason a step was not free ("broken", "tracking",
    "leg limit", "singular"); ``info["orientation_error"]`` is E's (rad).

    ## Arguments
    As v1, plus ``track_angle_tolerance`` (rad). A ``control_period`` that is
    not a whole number of the dynamics' physics steps is refused (v0 and v1
    simulate it rounded, and warn).

    ## Observation Space, Action Space, Rewards, Starting State
    As v1.

    ## Dynamic Fidelity
    At the leaderboard's setting (``HybridDynamics.fast``) PyBullet's path of E runs 1.03 mm from the same
    episodes at half the step and 1.09 mm at twice the solver iterations, just over the convergence study's
    1 mm bound, with no verdict changed; MuJoCo's is converged (``python benchmarks/convergence.py``, the
    conformance page).

    ## Version History
    * v2 (paragym 0.8.0): the dynamic fidelity's rules above; the kinematic
      fidelity is v1's.
    """

    rules = RULES[2]


class HybridSingularityFreeVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeEnv` stepped together:
    the same transition (:mod:`paragym.tasks.hybrid_step`) over N robots.
    Keyword arguments are the single env's (kinematic fidelity)."""

    task, rules = TASK, RULES[0]


class HybridSingularityFreeV1VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeV1Env` stepped together."""

    rules = RULES[1]


class HybridSingularityFreeV2VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeV2Env` stepped together (kinematic: v1's)."""

    rules = RULES[2]


class HybridSingularityFreeEasyEnv(HybridSingularityFreeV2Env):
    """``paragym/HybridSingularityFree-Easy-v0``: rung 0 of the hybrid's difficulty ladder: v2's task on paths
    that break a leg limit in their middle at the starting split.

    ## Description
    Each pair of poses is drawn by :func:`paragym.tasks.hybrid.ladder_scenarios` from the rung's knob
    (:data:`paragym.tasks.hybrid.LADDER`): from v2's box of poses, a pair whose ends are within the limits at
    0.5 and whose nominal path (every fourth sample) breaks one in its middle, where some of the 11 splits 0,
    0.1, ..., 1 keep every sample within them; the fewer of them at the hardest sample, the narrower the way
    through:

{knobs}

    ## Arguments
    As v2; ``scenario`` "random" (the default) is the rung's pair; "paper" and custom pairs are v2's.

    ## Action Space, Observation Space, Rewards, Starting State, Episode End
    As v2.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[0]


HybridSingularityFreeEasyEnv.__doc__ = (HybridSingularityFreeEasyEnv.__doc__ or "").format(knobs=knob_table("    "))


class HybridSingularityFreeMediumEnv(HybridSingularityFreeEasyEnv):
    """``paragym/HybridSingularityFree-Medium-v0``: rung 1 of the hybrid's difficulty ladder: the easy rung's
    paths where at most three splits get through the hardest sample.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of the easy rung (``paragym/HybridSingularityFree-Easy-v0``), with rung 1's knob.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[1]


class HybridSingularityFreeHardEnv(HybridSingularityFreeEasyEnv):
    """``paragym/HybridSingularityFree-Hard-v0``: rung 2 of the hybrid's difficulty ladder: the easy rung's
    paths where at most two splits get through the hardest sample.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of the easy rung (``paragym/HybridSingularityFree-Easy-v0``), with rung 2's knob.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[2]


class HybridSingularityFreeEasyVectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeEasyEnv` stepped together."""

    rules = LADDER_RULES[0]


class HybridSingularityFreeMediumVectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeMediumEnv` stepped together."""

    rules = LADDER_RULES[1]


class HybridSingularityFreeHardVectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeHardEnv` stepped together."""

    rules = LADDER_RULES[2]


class HybridSingularityFreeEasyV1Env(HybridSingularityFreeV2Env):
    """``paragym/HybridSingularityFree-Easy-v1``: rung 0 of the hybrid's ladder v1: v2's task on paths that break
    a leg limit midway at the starting split, with the split as the only lever, on pairs no constant action
    gets through.

    ## Description
    On the ladder v0 a constant action solves most pairs: E held up to 20 mm off its path clears the limit the
    pair was drawn to break (``benchmarks/hybrid_levers.py``: every such pair of v2's box is cleared by some
    constant; with an offset that must move at a bounded rate and come back, 5 mm of it still clear 94 % of
    the easy rung's pairs below, 2 mm 65 %). So
    on the ladder v1 E stays on its nominal path and the action is the split's rate alone, and each pair is
    drawn by :func:`paragym.tasks.hybrid.split_ladder_scenarios` from the rung's knob
    (:data:`paragym.tasks.hybrid.SPLIT_LADDER`): from v2's box of poses, a pair whose ends are within the
    limits at Delta = 0.5 and whose nominal path breaks one midway; that no constant split rate (-1, -0.9,
    ..., 1) gets through singularity-free within the limits; that a split schedule within the rate limit
    does, on the reference's grid (its certificate: the reference plans every drawn pair); and that the
    lookahead rule (:func:`paragym.tasks.hybrid.lookahead_split`: the split rate among -1, 0, +1 that keeps
    the next H samples furthest from eq 14's bounds) fails at each of the rung's horizons:

{knobs}

    ## Action Space
    ``Box(-1, 1, (1,), float32)``: the change of Delta, times ``max_delta_step`` = 0.05, Delta held in [0, 1].
    E stays on its nominal path. An action outside the Box is clipped to it; NaN/inf or a wrong shape raise
    ``ValueError``.

    ## Observation Space
    ``Box(-10, 10, (48,), float32)``, v2's:

    ==========  ==========================================================
    0           u, the path parameter (0 to 1)
    1-6         the nominal pose of E at this step (x, y, z / 0.1 m, roll, pitch, yaw / 0.5 rad)
    7-12        the nominal pose at the next step, scaled the same
    13          Delta, the split between the stages (0 to 1)
    14-22       the nine strokes, mapped so that L_min -> -1 and L_max -> +1 (hexapod 14-19, tripod 20-22)
    23-24       the singularity measures of the hexapod and the tripod (1 at home, singular below 0.2)
    25-27       the offset of E from the nominal path / j_bar: always 0 here
    28-33       the end pose P1, scaled as 1-6
    34-42       P1's strokes at the current Delta, mapped as 14-22
    43-44       P1's singularity measures at the current Delta
    45          P1's stroke excess (beyond the limits, in half stroke ranges) times 10
    46-47       the excess's change one Delta step up and one down, times 100
    ==========  ==========================================================

    ## Rewards, Starting State, Episode End
    v2's: per step ``- w_delta |change of Delta| / max_delta_step - w_singular * sum of (0.4 - mu)_+ / 0.4
    - w_limit * (legs out of limits)`` (the offset's term is 0), each term in the info as ``reward_<name>``;
    u = 0, Delta = 0.5, E at P0; terminated at u = 1 (100 steps), ``info["is_success"]`` when every pose was
    free (eq 14), in dynamic fidelity also tracked, the mechanism whole.

    ## Arguments
    v2's; ``scenario`` "random" (the default) is the rung's pair; "paper" and custom pairs are v2's.
    ``j_bar`` has no effect (there is no offset).

    ## Version History
    * v1 (paragym 0.10): the ladder v1, above; the ladder v0's ids (``-Easy-v0`` ...) are unchanged.
    """

    rules = SPLIT_LADDER_RULES[0]


HybridSingularityFreeEasyV1Env.__doc__ = (HybridSingularityFreeEasyV1Env.__doc__ or "").format(
    knobs=split_knob_table("    "))


class HybridSingularityFreeMediumV1Env(HybridSingularityFreeEasyV1Env):
    """``paragym/HybridSingularityFree-Medium-v1``: rung 1 of the hybrid's ladder v1: the easy rung's pairs where
    the lookahead rule with one sample of sight fails too.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v1 of the easy rung (``paragym/HybridSingularityFree-Easy-v1``), with rung 1's knob.

    ## Version History
    * v1 (paragym 0.10): the rung above.
    """

    rules = SPLIT_LADDER_RULES[1]


class HybridSingularityFreeHardV1Env(HybridSingularityFreeEasyV1Env):
    """``paragym/HybridSingularityFree-Hard-v1``: rung 2 of the hybrid's ladder v1: the easy rung's pairs where
    the lookahead rule fails with one and with five samples of sight.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v1 of the easy rung (``paragym/HybridSingularityFree-Easy-v1``), with rung 2's knob.

    ## Version History
    * v1 (paragym 0.10): the rung above.
    """

    rules = SPLIT_LADDER_RULES[2]


class HybridSingularityFreeEasyV1VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeEasyV1Env` stepped together."""

    rules = SPLIT_LADDER_RULES[0]


class HybridSingularityFreeMediumV1VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeMediumV1Env` stepped together."""

    rules = SPLIT_LADDER_RULES[1]


class HybridSingularityFreeHardV1VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeHardV1Env` stepped together."""

    rules = SPLIT_LADDER_RULES[2]


class HybridSingularityFreeEasyV2Env(HybridSingularityFreeEasyV1Env):
    """``paragym/HybridSingularityFree-Easy-v2``: rung 0 of the hybrid's ladder v2: the ladder v1's easy rung on
    pairs whose certificate keeps every stroke 1 mm inside its limits.

    ## Description
    As the ladder v1's easy rung (``paragym/HybridSingularityFree-Easy-v1``), with the rungs' knobs:

{knobs}

    ## Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v1 of the easy rung (``paragym/HybridSingularityFree-Easy-v1``).

    ## Version History
    * v2 (paragym 0.10): the ladder v2, above; the ladder v1's ids are unchanged, and their shipped models play
      these rungs.
    """

    rules = SPLIT_LADDER_RULES_V2[0]


HybridSingularityFreeEasyV2Env.__doc__ = (HybridSingularityFreeEasyV2Env.__doc__ or "").format(
    knobs=split_knob_table("    ", SPLIT_LADDER_V2))


class HybridSingularityFreeMediumV2Env(HybridSingularityFreeEasyV2Env):
    """``paragym/HybridSingularityFree-Medium-v2``: rung 1 of the hybrid's ladder v2: the ladder v1's medium rung
    on pairs whose certificate keeps every stroke 1 mm inside its limits.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v2 of the easy rung (``paragym/HybridSingularityFree-Easy-v2``), with rung 1's knobs.

    ## Version History
    * v2 (paragym 0.10): the rung above.
    """

    rules = SPLIT_LADDER_RULES_V2[1]


class HybridSingularityFreeHardV2Env(HybridSingularityFreeEasyV2Env):
    """``paragym/HybridSingularityFree-Hard-v2``: rung 2 of the hybrid's ladder v2: the ladder v1's hard rung on
    pairs whose certificate keeps every stroke 1 mm inside its limits.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v2 of the easy rung (``paragym/HybridSingularityFree-Easy-v2``), with rung 2's knobs.

    ## Version History
    * v2 (paragym 0.10): the rung above.
    """

    rules = SPLIT_LADDER_RULES_V2[2]


class HybridSingularityFreeEasyV2VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeEasyV2Env` stepped together."""

    rules = SPLIT_LADDER_RULES_V2[0]


class HybridSingularityFreeMediumV2VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeMediumV2Env` stepped together."""

    rules = SPLIT_LADDER_RULES_V2[1]


class HybridSingularityFreeHardV2VectorEnv(HybridSingularityFreeVectorEnv):
    """``num_envs`` copies of :class:`HybridSingularityFreeHardV2Env` stepped together."""

    rules = SPLIT_LADDER_RULES_V2[2]


#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = renamed(__name__, {
    "hybrid_paper_scenario": "paper_scenario",
    "hybrid_random_scenario": "random_scenario",
    "hybrid_random_scenarios": "random_scenarios",
})
