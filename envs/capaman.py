"""``paragym/CaPaManCollisionFree-v0``: the CaPaMan tour around obstacles (paper 000).

The single env and the native vector env are shells over one transition,
:mod:`paragym.tasks.capaman_step` (the single env is its N = 1 case, with
PyBullet's or the grid's collision check, or the dynamics); the scenarios
come from :mod:`paragym.tasks.capaman`.
"""

from __future__ import annotations

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.tasks.capaman import knob_table
from paragym.tasks.capaman_step import SWEEP_STEP
from paragym.tasks.capaman_task import LADDER_RULES, RULES, TASK

__all__ = ["SWEEP_STEP", "CaPaManCollisionFreeEasyEnv", "CaPaManCollisionFreeEasyVectorEnv",
           "CaPaManCollisionFreeEnv", "CaPaManCollisionFreeHardEnv", "CaPaManCollisionFreeHardVectorEnv",
           "CaPaManCollisionFreeMediumEnv", "CaPaManCollisionFreeMediumVectorEnv", "CaPaManCollisionFreeV1Env",
           "CaPaManCollisionFreeV1VectorEnv", "CaPaManCollisionFreeVectorEnv"]


class CaPaManCollisionFreeEnv(ParagymEnv):
    """Move the CaPaMan's tool through T.C.1 -> T.C.2 -> T.C.3 -> T.C.1 with no
    part of the manipulator touching an obstacle.

    ## Description
    Paper 000 (Carbone, Gomez-Bravo, Selvi), sections 2 and 4: the 3-DOF
    Cassino Parallel Manipulator carries a tool rod under its movable plate and
    must visit task configurations placed around obstacles. Collision is
    checked for the whole manipulator (17 parts: cranks, couplers, bars,
    rails, plate, tool) by PyBullet; the kinematics is the closed-form model
    of :mod:`paragym.mechanisms.capaman`.

    ## Action Space
    ``Box(-1, 1, (3,), float32)``: crank-angle increments, scaled by
    ``max_joint_step`` (default 2 deg) per step. An action outside the Box is
    clipped to it (every paragym env does so); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``. The result is
    held inside the mechanical range 45-135 deg (a joint stop).
    Collision is checked along the motion, not only at its end: in kinematic
    fidelity a step is checked every :data:`SWEEP_STEP` (2 deg per crank, at
    most 4.7 mm of motion of any point of the manipulator, under the 5 mm
    occupancy grid), so a step of the default size is checked at its end and
    a larger ``max_joint_step`` is cut into sub-steps; the mechanism stops
    where a sub-step first collides. In dynamic fidelity the obstacles are
    rigid bodies and PyBullet's contact solver stops the parts at every
    physics step.

    ## Observation Space
    ``Box(-1, 1, (38,), float32)``:

    ==========  ==========================================================
    0-2         crank angles, normalised to [-1, 1] over 45-135 deg
    3-5         tool-tip position (m, fixed-plate frame)
    6-8         current target T.P., normalised like 0-2
    9-11        current target T.C., tool-tip position (m)
    12-35       three obstacles x [present, is_box, centre (3), half sizes (3)] (m; zeros when absent)
    36          clearance of the whole manipulator (m, signed, capped at +-``clearance_cap``)
    37          progress: T.C.s reached / 3
    ==========  ==========================================================

    ## Rewards
    Every step's info holds the reward's terms, ``reward_<name>`` for length, progress, time,
    proximity, reach, collision (:data:`paragym.tasks.capaman_step.REWARD_TERMS`, since paragym
    0.10); the reward is their sum.
    After the fitness of paper 000 (eqs 3-5), per step:
    ``-w_length * |d alpha|`` (joint-space path length, rad)
    ``- beta * [clearance < delta]`` (too close to an obstacle; the paper's
    k_i beta, here with the Cartesian clearance)
    ``+ w_progress * (d_before - d_after)`` (potential-based shaping on the
    joint distance to the current target: it telescopes, so it does not
    change which tour is optimal)
    ``+ reach_bonus`` per T.C. reached ``- collision_penalty`` on collision
    (the paper's Lambda = infinity, made finite and terminal).

    ## Starting State
    The manipulator at T.P.1. ``info["scenario"]`` (a frozen
    :class:`CaPaManScenario`) holds obstacles, T.C.s and T.P.s.

    ## Episode End
    Terminated on collision (clearance <= 0) or when the tour is complete
    (``is_success``). Truncated after 400 steps (registration).

    ## Arguments
    ``scenario``: "random" (default; seeded, generated feasible), "paper",
    or a :class:`CaPaManScenario`; ``reset(options={"scenario": ...})``
    overrides it for one episode. ``fidelity``: "kinematic" (default: the
    joints go where the action says, the analytic model places the parts)
    or "dynamic" (the closed chain under physics: the action moves the
    motors' commands, which the motors chase for ``control_period`` s of
    simulated time; observations report the encoders and the plate's
    simulated pose). ``collision``: "pybullet" (default: PyBullet's exact
    signed distance between the 17 parts and the obstacles) or "grid"
    (kinematic fidelity only: paper 000's own test, the occupancy grid Psi
    and the cluster points of eq 2, 10 mm apart; the clearance is the
    smallest signed distance on Psi at any cluster point, in 0.5 mm steps;
    PyBullet then only draws). The native vector env uses "grid", and with
    it gives this env's numbers. ``max_joint_step`` (rad), ``reach_tolerance`` (rad, joint-space
    norm), ``delta`` (m), ``beta``, ``w_length``, ``w_progress``,
    ``reach_bonus``, ``collision_penalty``, ``clearance_cap`` (m),
    ``geometry``, ``render_mode`` ("rgb_array" or "human"). ``dynamics``: a
    :class:`~paragym.sim.capaman_dynamic.CaPaManDynamics` for the dynamic
    fidelity (default ``CaPaManDynamics()``, the released settings: 1 ms,
    150 solver iterations, no joint stops); the presets
    ``CaPaManDynamics.fast()`` and ``.split()`` (the same motion in a
    cheaper layout) have joint stops and keep the loops closed within 1 mm
    under contact, several times faster than the released settings
    (:mod:`paragym.sim.capaman_dynamic`).
    ``engine``: the dynamic fidelity's physics, "pybullet" (default) or
    "mujoco" (or a :class:`~paragym.sim.mujoco_sim.MuJoCoSettings`): the same
    model, obstacles, rules and checks in MuJoCo (the ``mujoco`` extra; the
    conformance page compares the engines), with PyBullet's scene measuring
    the clearance. ``engine=MuJoCoSettings(mirror=False)``: MuJoCo alone, the
    clearance the kinematic fidelity's kernel at the encoders' angles
    (``collision`` "posts" on a rung, "grid" otherwise), each control period
    from a cold solver start; the native vector env runs it for N robots at
    once (``gym.make_vec(ID, N, vectorization_mode="vector_entry_point",
    fidelity="dynamic", engine="mujoco")``), and this env is its N = 1 case,
    bit for bit.

    ## Version History
    * v0: initial release (kinematic and dynamic fidelity). Since paragym 0.2.0
      an action outside the Box is clipped to it (before, an action of 30 moved
      a crank 60 deg in one step past obstacles); episodes of in-Box actions are
      unchanged, bit for bit (tested against recorded rollouts). Since
      paragym 0.3.0 a scenario argument of the wrong type is a TypeError (it
      was a ValueError), as in every paragym env; no episode changes. Since
      paragym 0.6.0 a ``dynamics`` argument chooses the dynamic fidelity's
      settings; its default is the released ones (episodes unchanged, bit for
      bit).
    * v1 (paragym 0.4.0): :class:`CaPaManCollisionFreeV1Env`, a new
      observation, reward and reach tolerance; v0 is unchanged.
    * paragym 0.8.0, v0 and v1: ``info["failure"]`` ("collision",
      "broken"); in dynamic fidelity a loop open by more than 5 mm ends the
      episode as "broken" (no released setting opens one that far before a
      collision ends the episode: their rollouts are unchanged); a
      ``control_period`` that the physics step does not divide warns.
    * paragym 0.10, every version: one lifecycle (a step after termination, before reset or after
      ``close`` is refused; unknown reset options too; no copy shares a PyBullet client) and the
      reward's terms in the info; every episode runs as before.
    * paragym 0.10, every version: the ``engine`` argument; "mujoco" runs the dynamic fidelity in
      MuJoCo; PyBullet's, the default, runs as before. MuJoCo alone
      (``MuJoCoSettings(mirror=False)``) and the native dynamic vector env.
    """

    task, rules = TASK, RULES[0]


class CaPaManCollisionFreeV1Env(CaPaManCollisionFreeEnv):
    """``paragym/CaPaManCollisionFree-v1``: v0's mechanism, scenarios, motion,
    collision test and episode end, with an observation, a reward and a reach
    tolerance under which learning beats standing still.

    ## Observation Space
    ``Box(-1, 1, (41,), float32)``:

    ==========  ==========================================================
    0-2         crank angles, normalised to [-1, 1] over 45-135 deg
    3-5         current target T.P. minus the cranks (/ 45 deg)
    6-8         the next target T.P. minus the cranks (/ 45 deg)
    9-11        current target T.C. minus the tool tip (x 5 /m)
    12-35       three obstacles x [present, is_box, centre minus tool tip (3), half sizes (3)] (x 5 /m)
    36          clearance / ``clearance_cap`` (signed)
    37-39       look-ahead: the clearance's change if crank k alone moved 3 deg further, / cap
                (:data:`paragym.tasks.capaman_step.LOOKAHEAD`; 0 away from obstacles)
    40          progress: T.C.s reached / 3
    ==========  ==========================================================

    ## Rewards
    v0's terms plus ``-time_penalty`` (0.01) per step; ``collision_penalty``
    is 4, the whole time budget of 400 steps, so that ending an episode by a
    collision never pays, and standing still (-4) scores below any attempt
    that makes progress.

    ## Starting State, Episode End, Action Space
    As v0. ``reach_tolerance`` is 3 deg (joint-space norm): one and a half
    action steps.

    ## Arguments
    As v0, plus ``time_penalty``. In dynamic fidelity the look-ahead is
    computed in the kinematic scene at the encoders' angles.

    ## Version History
    * v1 (paragym 0.4.0): the observation, reward and reach tolerance above;
      the motion, the collision test, the scenarios and the end are v0's.
    """

    rules = RULES[1]


class CaPaManCollisionFreeVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeEnv` with
    ``collision="grid"`` stepped together: the same transition
    (:mod:`paragym.tasks.capaman_step`) over N robots, with paper 000's grid
    test (Psi as signed distances, the cluster points of eq 2) for all of
    them at once. Scenarios are generated (and checked) by a kinematic
    PyBullet scene of its own, robot by robot, at reset; the same scene draws
    robot ``render_index``. Keyword arguments are the single env's
    (``collision`` is "grid"; ``fidelity`` is "kinematic"), which checks them
    and derives the parameters (built with the grid, it builds no PyBullet
    scene)."""

    task, rules = TASK, RULES[0]


class CaPaManCollisionFreeV1VectorEnv(CaPaManCollisionFreeVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeV1Env` stepped together on the grid."""

    rules = RULES[1]


class CaPaManCollisionFreeEasyEnv(CaPaManCollisionFreeV1Env):
    """``paragym/CaPaManCollisionFree-Easy-v0``: rung 0 of the CaPaMan's difficulty ladder: v1's tour among
    posts, one of which stands on a leg's straight line.

    ## Description
    Each scene is drawn by :func:`paragym.tasks.capaman.ladder_scenarios` from the rung's knobs
    (:data:`paragym.tasks.capaman.LADDER`): three T.P.s at least ``spread`` apart, 5 deg inside the joint
    range; a post on the straight joint-space line of ``blocked_legs`` of the tour's legs (where the tool is
    40-60 % along it) and ``clutter`` posts anywhere within 65 mm of the centre; every two posts at least
    ``gap`` apart or overlapping, every T.P. 9 mm clear (in the capsule model; so that the planners on paper
    000's grid, which may grow an obstacle by 8 mm, see it free). The posts are vertical capsules
    (:class:`~paragym.sim.obstacles.Capsule`) standing on the fixed plate, 75-90 mm tall, the clearance cap
    below the plate's lowest reach:

{knobs}

    That a collision-free tour exists is checked over 1,000 seeds per rung on a 2 deg (else 1.5 deg) grid of
    the joint range (:func:`paragym.tasks.capaman.solvable`; ``benchmarks/capaman_solvable.py``, and 100 seeds in
    the tests).

    ## Collision
    ``collision`` "posts" (the default in kinematic fidelity, and the native vector env's): every part but the
    plate as the capsule that holds it (a link of 12 mm square section as a capsule of radius 8.5 mm, the tool
    rod as its own), the distance to each post exact and in closed form
    (:mod:`paragym.sim.capaman_posts`); conservative: where it says free, PyBullet's parts are free. The plate
    stays farther than the clearance cap from every post in every pose, so it is left out. ``collision``
    "pybullet": PyBullet's exact distance between the 17 parts and the same posts (the dynamic fidelity's).

    ## Observation Space
    v1's, with a slot for each of the rung's K = ``blocked_legs + clutter`` posts: ``Box(-1, 1, (17 + 8 K,),
    float32)``, (33,) on the easy rung and (49,) on the medium and hard ones:

    ===============  ==========================================================
    0-2              crank angles, normalised to [-1, 1] over 45-135 deg
    3-5              current target T.P. minus the cranks (/ 45 deg)
    6-8              the next target T.P. minus the cranks (/ 45 deg)
    9-11             current target T.C. minus the tool tip (x 5 /m)
    12 to 11 + 8 K   K posts x [present, kind (0.5: a capsule), centre minus tool tip (3), half sizes (3)]
                     (x 5 /m)
    12 + 8 K         clearance / ``clearance_cap`` (signed)
    13-15 + 8 K      look-ahead: the clearance's change if crank k alone moved 3 deg further, / cap
    16 + 8 K         progress: T.C.s reached / 3
    ===============  ==========================================================

    ## Arguments
    As v1; ``scenario`` "random" (the default) is the rung's scene, or a :class:`CaPaManScenario` of capsule
    posts that :func:`paragym.tasks.capaman.validate_scenario` accepts on the rung.

    ## Action Space, Rewards, Starting State, Episode End
    As v1.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[0]


CaPaManCollisionFreeEasyEnv.__doc__ = (CaPaManCollisionFreeEasyEnv.__doc__ or "").format(knobs=knob_table("    "))


class CaPaManCollisionFreeMediumEnv(CaPaManCollisionFreeEasyEnv):
    """``paragym/CaPaManCollisionFree-Medium-v0``: rung 1 of the CaPaMan's difficulty ladder: posts on two of
    the tour's three legs, two more of clutter, wider and closer together.

    ## Description, Collision, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of the easy rung (``paragym/CaPaManCollisionFree-Easy-v0``), with rung 1's knobs.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[1]


class CaPaManCollisionFreeHardEnv(CaPaManCollisionFreeEasyEnv):
    """``paragym/CaPaManCollisionFree-Hard-v0``: rung 2 of the CaPaMan's difficulty ladder: a post on every leg
    of the tour, one more of clutter, the narrowest passages.

    ## Description, Collision, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of the easy rung (``paragym/CaPaManCollisionFree-Easy-v0``), with rung 2's knobs.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[2]


class CaPaManCollisionFreeEasyVectorEnv(CaPaManCollisionFreeVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeEasyEnv` stepped together with the capsule model."""

    rules = LADDER_RULES[0]


class CaPaManCollisionFreeMediumVectorEnv(CaPaManCollisionFreeVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeMediumEnv` stepped together with the capsule model."""

    rules = LADDER_RULES[1]


class CaPaManCollisionFreeHardVectorEnv(CaPaManCollisionFreeVectorEnv):
    """``num_envs`` copies of :class:`CaPaManCollisionFreeHardEnv` stepped together with the capsule model."""

    rules = LADDER_RULES[2]
