"""``paragym/MobileTripodOdometry-v0``: estimate a mobile tripod's drive units under slip (paper 004).

The single env and the native vector env are shells over one transition,
:mod:`paragym.tasks.tripod_step` (the single env is its N = 1 case),
whose drive physics is :mod:`paragym.sim.tripod_drive`; the scenarios come
from :mod:`paragym.tasks.tripod`.
"""

from __future__ import annotations

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.tasks.tripod import drive_scenario, knob_table
from paragym.tasks.tripod_task import LADDER_RULES, LADDER_RULES_V1, RULES, TASK

__all__ = ["MobileTripodOdometryEasyEnv", "MobileTripodOdometryEasyV1Env", "MobileTripodOdometryEasyV1VectorEnv",
           "MobileTripodOdometryEasyVectorEnv", "MobileTripodOdometryEnv", "MobileTripodOdometryHardEnv",
           "MobileTripodOdometryHardV1Env", "MobileTripodOdometryHardV1VectorEnv", "MobileTripodOdometryHardVectorEnv",
           "MobileTripodOdometryMediumEnv", "MobileTripodOdometryMediumV1Env",
           "MobileTripodOdometryMediumV1VectorEnv", "MobileTripodOdometryMediumVectorEnv",
           "MobileTripodOdometryV1Env", "MobileTripodOdometryV1VectorEnv", "MobileTripodOdometryV2Env",
           "MobileTripodOdometryV2VectorEnv", "MobileTripodOdometryV3Env", "MobileTripodOdometryV3VectorEnv",
           "MobileTripodOdometryVectorEnv", "drive_scenario"]


class MobileTripodOdometryEnv(ParagymEnv):
    """Keep track of where a mobile parallel robot's three drive units really are.

    ## Description
    Paper 004 (Shoval and Shoham): three drive units carry legs of fixed
    length to an upper plate; encoders at the upper revolute joints measure
    the legs' angles eta, which fix the distances between the units (eq 4),
    while odometry, blind to slip, pushes and bumps, drifts (eq 5). The
    robot drives its commanded path; the agent is the estimator.

    ## Action Space
    ``Box(-1, 1, (6,))``: a correction of the estimated horizontal unit
    positions, times ``max_correction`` (5 cm), added after the odometric
    prediction.
    An action outside the Box is clipped to it (the rule of every paragym env,
    :func:`paragym.envs.base.check_action`); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``.

    ## Observation Space
    ``Box(-100, 100, (21,), float32)``:

    ==========  ==========================================================
    0-8         the three units' odometric positions x, y, z (/ 10 m)
    9-11        the measured leg angles eta (rad, with encoder noise)
    12-14       the command: speed (m/s), cos and sin of the heading
    15-20       the previous estimate of the units' x, y (/ 10 m)
    ==========  ==========================================================

    ## Rewards
    Every step's info holds the reward's terms, ``reward_<name>`` for estimate, odometry
    (:data:`paragym.tasks.tripod_step.REWARD_TERMS`, since paragym 0.10); the reward is their sum.
    ``-10 (mean unit error + plate centre error)`` per step (m): the estimate's
    units against the true ones, and the plate's centre fitted to the
    estimate against the true centre.

    ## Starting State
    At rest, the legs at 40 deg, every estimate exact; ``info["scenario"]``.

    ## Episode End
    After the drive (20 m at 0.66 m/s: 606 samples at 20 Hz). ``is_success``:
    the final mean unit error under ``success_error`` (5 cm).

    ## Arguments
    ``scenario``: one of initial_heading, push, random_slip, rough_terrain,
    random (default); ``encoder_noise`` (rad, 1 deg); ``max_correction`` (m);
    ``success_error`` (m); ``geometry`` (r, p: 5 ft each by default).
    ``fidelity``: "kinematic" (default: the drive units are unicycles and
    the disturbances are added to their motion,
    :mod:`paragym.sim.tripod_drive`) or "dynamic"
    (:mod:`paragym.sim.tripod_dynamic`: the plate, its three legs on
    encoder joints and the three wheeled drive units on the terrain under
    PyBullet's dynamics; slip, pushes and bumps come from contact and
    forces, odometry from the wheel encoders, eta from the leg encoders;
    the estimate, the observation and the reward are the same functions of
    them). ``dynamics``: a :class:`~paragym.sim.tripod_dynamic.TripodDynamics`.
    ``engine``: "pybullet" only (the terrain's contacts and slip are not
    exported to MuJoCo).
    On rough terrain the fidelities differ most: the kinematic units roll
    over the bumps without slip, the dynamic ones bounce and slip, and
    their odometry drifts several times further (CHANGELOG.md, 0.8.0).

    ## Version History
    * v0: initial release.
      Since paragym 0.6.0 ``fidelity="dynamic"`` is offered; the default,
      kinematic, is unchanged.
      Since paragym 0.2.0 a custom scenario that cannot run (NaN, outside
      the workspace, malformed) and non-dict ``options`` are refused at reset
      with a ValueError or TypeError naming them; every episode that ran
      before runs the same (tested against recorded rollouts). Since paragym
      0.3.0 the native vector env runs every drive the single env runs (it
      refused drives of more than 8 terrain bumps, or longer than its first),
      and a custom drive of more than 10 million samples is refused at reset
      with a ValueError naming it (it could not run: it failed allocating).
      Its hole, kept so that its episodes replay: a drive that folds the
      tripod (a leg past horizontal) carries on; since paragym 0.8.0
      ``info["failure"]`` says "folded". v2 ends it.
    * v1 (paragym 0.4.0): :class:`MobileTripodOdometryV1Env`, a new action and
      observation; v0 is unchanged.
    * v2 (paragym 0.8.0): :class:`MobileTripodOdometryV2Env`, a folded
      tripod ends the episode as a failure.
    * paragym 0.10, every version: one lifecycle (a step after termination, before reset or after
      ``close`` is refused; unknown reset options too; no copy shares a PyBullet client) and the
      reward's terms in the info; every episode runs as before.
    """

    task, rules = TASK, RULES[0]


class MobileTripodOdometryV1Env(MobileTripodOdometryEnv):
    """``paragym/MobileTripodOdometry-v1``: v0's drives, success and end, with
    an action, an observation and a reward under which learning beats
    odometry.

    ## Action Space
    ``Box(-1, 1, (3,))``: for each unit u, the fraction ``clip(a_u, 0, 1)``
    of the way its estimate moves, before the drive advances, toward where
    the paper's correction puts it (section 3: on the circles about the other
    two estimated units whose radii are the encoder distances of eq 4,
    exponentially smoothed with factor 0.1 per sample, as the reference
    smooths them; :func:`paragym.mechanisms.tripod.k_relocate`).
    Then all three move by the odometric increment. Zero or negative: odometry
    alone. What is learned is the paper's hard part: which unit is faulty,
    when, and how far to trust the noisy encoders.

    ## Observation Space
    ``Box(-100, 100, (16,), float32)``, in the robot's frame (x along the
    commanded heading):

    ==========  ==========================================================
    0-2         the estimate's inter-unit distances minus the smoothed encoder distances (/ 5 cm)
    3-5         the odometry's inter-unit distances minus the same (/ 5 cm)
    6-11        each unit's estimate minus its odometry, x and y (/ 10 cm)
    12          the drive's progress, step / steps
    13-15       the measured leg angles eta (rad)
    ==========  ==========================================================

    ## Rewards
    v0's reward minus what odometry alone earns at the same sample:
    ``-10 (unit error + plate error) + 10 (odometry's unit error + its plate
    error)``. Odometry's error does not depend on the actions, so the best
    policy is v0's; the drift that no estimator controls drops out of the
    reward, and the zero action (odometry) earns 0. Its variance made v0 hard
    to learn from (``baselines/ABLATION.md``).

    ## Starting State, Episode End
    As v0.

    ## Arguments
    As v0 (``max_correction`` is not used), and ``trust_rate`` (0.2: the
    fraction of the way a fully trusted unit moves per sample) and
    ``relative_reward`` (True; False gives v0's reward, for ablations). ``info["encoder_distances"]``
    holds the smoothed encoder distances (m).

    ## Version History
    * v1 (paragym 0.4.0): the action, the observation and the reward above;
      the drives, the success and the episode's end are v0's.
    """

    rules = RULES[1]


class MobileTripodOdometryV2Env(MobileTripodOdometryV1Env):
    """``paragym/MobileTripodOdometry-v2``: v1's task, in which a folded
    mechanism ends the episode as a failure.

    ## Episode End
    As v1, and when a leg reaches the horizontal: the episode ends there,
    ``is_success`` is False and ``info["failure"]`` is "folded" (in v0 and v1
    it says so too, without ending the episode).

    ## Arguments
    As v1. A dynamics whose physics step does not divide the 0.05 s sample is
    refused (v0 and v1 round it, and warn).

    ## Action Space, Observation Space, Rewards, Starting State
    As v1.

    ## Dynamic Fidelity
    The default setting (a 5 ms step, 30 solver iterations, kept as released) is not converged. PyBullet's
    solver lets the drive units creep sideways while their wheels' friction is far below its limit: a unit
    loaded sideways by 100 N for 2 s slides 0.36 mm, and over a drive each unit creeps 5.7-10.7 cm. The
    reference's success then follows the setting, not the method: on the same ten drives it succeeded 5 times
    at the default and 9 times at a quarter of the step with four times the iterations
    (``python benchmarks/convergence.py``, the conformance page). This page blamed its failures on the paper's
    single-fault premise; what the simulation measures is creep. ``dynamics=TripodDynamics.converged()``
    (100 iterations; the leaderboard's) holds a loaded unit within 0.04 mm. ``engine="mujoco"`` runs the
    same drive in MuJoCo (the dynamics guide). The KF check judges the plate fitted to the policy's estimated
    units against the real plate, in either engine, through its tilt: gravity is removed at the commanded
    attitude, so a fitted plate tilted by theta against the real one reads as g theta of horizontal
    acceleration, and a heading error as nothing. It passes an estimate that is the truth one sample late, the
    truth shifted 10 cm as a whole or turned 3 deg about the vertical, and fails one whose single unit is 5 cm
    off; the paper's correction fails it on most drives, its fitted plate tilted 0.45-1.6 deg RMS against the
    real one (the dynamics guide).

    ## Version History
    * v2 (paragym 0.8.0): the folded end above; drives that do not fold are
      v1's, bit for bit, and so are v1's shipped models.
    """

    rules = RULES[2]


class MobileTripodOdometryV3Env(MobileTripodOdometryV2Env):
    """``paragym/MobileTripodOdometry-v3``: v2's task, its dynamic fidelity at converged physics by default, each
    unit starting on its wheels.

    ## Dynamic Fidelity
    The default is ``TripodDynamics.converged()``: the same 5 ms step with 100 solver iterations, at which a
    drive unit loaded sideways by 100 N for 2 s, its wheels held, stays within 0.1 mm (at v2's default it
    slides; ``tests/test_dynamic_fidelity.py``), and the leaderboard's setting for every tripod id.
    Each unit starts on its wheels: raised until none of its wheels and casters is inside the terrain, the legs
    and plate posed to match. ``engine="mujoco"`` runs the drive in MuJoCo. The KF check judges the plate
    fitted to the policy's estimated units against the real plate, through its tilt: an estimate whose
    inter-unit distances tilt the fitted plate by about 0.45 deg RMS or more fails, whatever its place and
    heading. It passes the truth one sample late and fails odometry alone, in either engine; the paper's
    correction fails it on most drives, and v1's shipped SAC, whose estimate keeps its shape while its heading
    drifts, passes it on all eight drives measured (the dynamics guide measures the tilt). Where several units slip
    at once the paper's single-fault test singles out none of them and the estimate's inter-unit distances drift
    from the true ones; the estimators that keep them (a fallback to the most discrepant unit, an unscented Kalman
    filter on v0) lose the place instead, and none tried holds both on most drives
    (``benchmarks/tripod_estimators.py``, the conformance page).

    ## Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v2; ``dynamics`` still takes any :class:`~paragym.sim.tripod_dynamic.TripodDynamics`.

    ## Version History
    * v3 (paragym 0.10): the converged dynamic default and the start on the wheels above; the kinematic fidelity
      is v2's bit for bit, and so are v1's shipped models.
    """

    rules = RULES[3]


class MobileTripodOdometryVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryEnv` stepped together:
    the same transition (:mod:`paragym.tasks.tripod_step`) over N
    robots. Keyword arguments are the single env's (kinematic fidelity)."""

    task, rules = TASK, RULES[0]


class MobileTripodOdometryV1VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryV1Env` stepped together."""

    rules = RULES[1]


class MobileTripodOdometryV2VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryV2Env` stepped together."""

    rules = RULES[2]


class MobileTripodOdometryV3VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryV3Env` stepped together."""

    rules = RULES[3]


class MobileTripodOdometryEasyEnv(MobileTripodOdometryV2Env):
    """``paragym/MobileTripodOdometry-Easy-v0``: rung 0 of the tripod's difficulty ladder: v2's task on drives
    where odometry alone always fails.

    ## Description
    Each drive is drawn by :func:`paragym.tasks.tripod.ladder_scenario` from the rung's knobs
    (:data:`paragym.tasks.tripod.LADDER`): a random heading; ``bumps`` bumps and holes of height
    ``height`` / 2 to ``height`` across the path (3.5-19 m along it, +-2.2 m across, radius 0.3-0.6 m);
    ``pushes`` pushes, each on a unit drawn at random, inward by a distance drawn in ``push``, one in each
    equal window of 3-25 s and 4 s clear of the next; random slip up to ``slip`` m/s per unit.

{knobs}

    In dynamic fidelity a push is the force that moves a unit its distance on flat ground
    (:func:`paragym.tasks.tripod_worlds.calibrated_push_force`): v2's force, linear in the distance, holds only
    near the paper's 2.5 cm and folds the tripod at 20 cm.

    ## Arguments
    As v2; ``scenario`` "random" (the default) is the rung's drive; the paper's named drives and custom ones
    are v2's.

    ## Action Space, Observation Space, Rewards, Starting State, Episode End
    As v2.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[0]


MobileTripodOdometryEasyEnv.__doc__ = (MobileTripodOdometryEasyEnv.__doc__ or "").format(knobs=knob_table("    "))


class MobileTripodOdometryMediumEnv(MobileTripodOdometryEasyEnv):
    """``paragym/MobileTripodOdometry-Medium-v0``: rung 1 of the tripod's difficulty ladder: the easy rung's
    drives with one push more, on rougher and slipping ground.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of the easy rung (``paragym/MobileTripodOdometry-Easy-v0``), with rung 1's knobs.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[1]


class MobileTripodOdometryHardEnv(MobileTripodOdometryEasyEnv):
    """``paragym/MobileTripodOdometry-Hard-v0``: rung 2 of the tripod's difficulty ladder: the medium rung's
    drives with one push more, smaller ones among them, on the roughest and most slipping ground.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of the easy rung (``paragym/MobileTripodOdometry-Easy-v0``), with rung 2's knobs.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[2]


class MobileTripodOdometryEasyVectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryEasyEnv` stepped together."""

    rules = LADDER_RULES[0]


class MobileTripodOdometryMediumVectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryMediumEnv` stepped together."""

    rules = LADDER_RULES[1]


class MobileTripodOdometryHardVectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryHardEnv` stepped together."""

    rules = LADDER_RULES[2]


class MobileTripodOdometryEasyV1Env(MobileTripodOdometryEasyEnv):
    """``paragym/MobileTripodOdometry-Easy-v1``: rung 0 of the tripod's ladder v1: the easy rung's drives, its
    dynamic fidelity at v3's converged physics by default.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of this rung (``paragym/MobileTripodOdometry-Easy-v0``): the same drives, bit for bit in the kinematic
    fidelity.

    ## Dynamic Fidelity
    As v3 (``paragym/MobileTripodOdometry-v3``): ``TripodDynamics.converged()`` by default and each unit starting
    on its wheels, where the ladder v0 keeps v2's 30 iterations, at which the units creep, and v2's start. The KF
    check fails every estimator the action can express on these rungs: a push moves a unit 15-50 cm, and the
    estimate follows the encoders' distances no faster than their smoothing (0.1 per sample, against their +-1 deg
    noise) lets it, its shape centimetres off for seconds after each push at any trust rate
    (``benchmarks/tripod_estimators.py``).

    ## Version History
    * v1 (paragym 0.10): the ladder v1, above; the ladder v0's ids (``-Easy-v0`` ...) are unchanged, and their
      shipped models play these rungs.
    """

    rules = LADDER_RULES_V1[0]


class MobileTripodOdometryMediumV1Env(MobileTripodOdometryMediumEnv):
    """``paragym/MobileTripodOdometry-Medium-v1``: rung 1 of the tripod's ladder v1: the medium rung's drives at
    v3's converged physics by default.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of this rung (``paragym/MobileTripodOdometry-Medium-v0``), bit for bit in the kinematic fidelity.

    ## Dynamic Fidelity
    As ``paragym/MobileTripodOdometry-Easy-v1``.

    ## Version History
    * v1 (paragym 0.10): the ladder v1, above.
    """

    rules = LADDER_RULES_V1[1]


class MobileTripodOdometryHardV1Env(MobileTripodOdometryHardEnv):
    """``paragym/MobileTripodOdometry-Hard-v1``: rung 2 of the tripod's ladder v1: the hard rung's drives at v3's
    converged physics by default.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of this rung (``paragym/MobileTripodOdometry-Hard-v0``), bit for bit in the kinematic fidelity.

    ## Dynamic Fidelity
    As ``paragym/MobileTripodOdometry-Easy-v1``.

    ## Version History
    * v1 (paragym 0.10): the ladder v1, above.
    """

    rules = LADDER_RULES_V1[2]


class MobileTripodOdometryEasyV1VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryEasyV1Env` stepped together."""

    rules = LADDER_RULES_V1[0]


class MobileTripodOdometryMediumV1VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryMediumV1Env` stepped together."""

    rules = LADDER_RULES_V1[1]


class MobileTripodOdometryHardV1VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryHardV1Env` stepped together."""

    rules = LADDER_RULES_V1[2]
