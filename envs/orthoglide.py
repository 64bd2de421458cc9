"""``paragym/Orthoglide2PRRKappa-v0``: track a path with the 2PRR + table, keeping kappa(J) low (paper 003).

The single env and the native vector env are shells over one transition,
:mod:`paragym.tasks.orthoglide_step` (the single env is its N = 1 case); the
scenarios come from :mod:`paragym.tasks.orthoglide`.
"""

from __future__ import annotations

from paragym.envs.base import ParagymEnv
from paragym.envs.vector import ParagymVectorEnv
from paragym.tasks.base import renamed
from paragym.tasks.orthoglide import knob_table, random_scenario, random_scenarios
from paragym.tasks.orthoglide_step import KAPPA_LIMIT
from paragym.tasks.orthoglide_task import LADDER_RULES, LADDER_RULES_V1, RULES, TASK

__all__ = ["KAPPA_LIMIT", "Orthoglide2PRRKappaEasyEnv", "Orthoglide2PRRKappaEasyV1Env",
           "Orthoglide2PRRKappaEasyV1VectorEnv", "Orthoglide2PRRKappaEasyVectorEnv", "Orthoglide2PRRKappaEnv",
           "Orthoglide2PRRKappaHardEnv", "Orthoglide2PRRKappaHardV1Env", "Orthoglide2PRRKappaHardV1VectorEnv",
           "Orthoglide2PRRKappaHardVectorEnv", "Orthoglide2PRRKappaMediumEnv", "Orthoglide2PRRKappaMediumV1Env",
           "Orthoglide2PRRKappaMediumV1VectorEnv", "Orthoglide2PRRKappaMediumVectorEnv", "Orthoglide2PRRKappaV1Env",
           "Orthoglide2PRRKappaV1VectorEnv", "Orthoglide2PRRKappaV2Env", "Orthoglide2PRRKappaV2VectorEnv",
           "Orthoglide2PRRKappaVectorEnv", "random_scenario", "random_scenarios"]


class Orthoglide2PRRKappaEnv(ParagymEnv):
    """Track a path with the 2-dof Orthoglide assisted by a translating table,
    keeping the condition number of J low.

    ## Description
    Paper 003 (Moreno, Pamanes, Wenger, Chablat): the 2PRR and its table form
    a redundant 3-dof manipulator for a 2-D task in the table frame. With the
    default action the tool follows the path exactly (least-norm motion
    ``J^+ t_dot``) and the agent chooses the motion in the null space of J,
    where kappa(J) (eq 8) can be lowered without leaving the path (eqs 5, 9-10).
    Kinematics: :mod:`paragym.mechanisms.orthoglide`.

    ## Action Space
    ``action_mode="null_space"`` (default): ``Box(-1, 1, (1,))``, the null-space
    rate times ``max_null_rate`` (m/s along the unit null vector n).
    ``action_mode="joint_velocity"``: ``Box(-1, 1, (3,))``, joint rates times
    ``max_joint_rate`` (m/s); the tool then tracks only as well as the agent does.
    An action outside the Box is clipped to it (the rule of every paragym env,
    :func:`paragym.envs.base.check_action`); NaN/inf or a wrong shape raise
    ``ValueError``, strings and complex numbers ``TypeError``.

    ## Observation Space
    ``Box(-10, 10, (11,), float32)``, each component clipped to +-10:

    ==========  ==========================================================
    0-2         rho (the table and the two sliders), normalised to [-1, 1] over their limits
    3-4         the path point of this step (table frame, m)
    5-6         the path point of the next step (table frame, m)
    7           log kappa (10 from kappa = 2.2e4 on, and where J is singular)
    8-10        n, the null vector of J (zeros where J is singular)
    ==========  ==========================================================

    ## Rewards
    Every step's info holds the reward's terms, ``reward_<name>`` for kappa, tracking, failure
    (:data:`paragym.tasks.orthoglide_step.REWARD_TERMS`, since paragym 0.10); the reward is their sum.
    ``-log(kappa)`` per step (0 at an isotropic pose); in joint-velocity mode
    also ``- w_track * tracking error / 0.01 m``. Reaching a joint limit or a
    singularity (kappa > 100, or leaving the working mode) costs
    ``limit_penalty`` and ends the episode.

    ## Starting State
    The optimal initial configuration: the admissible table position with
    the lowest kappa at the first path point. ``info["scenario"]`` is the task.

    ## Episode End
    Terminated at the path's end (``is_success``: no limit or singularity on
    the way) or at a limit/singularity.

    ## Arguments
    ``scenario``: "paper" (the 0.8 m circle in 10 s) or "random" (default:
    seeded circles, ellipses, lines); ``action_mode``; ``max_null_rate`` (0.5
    m/s); ``max_joint_rate`` (0.5 m/s); ``w_track``; ``limit_penalty`` (10);
    ``geometry``; ``render_mode``. ``fidelity``: "kinematic" (default: the
    joints are set where the step puts them) or "dynamic"
    (:mod:`paragym.sim.orthoglide_dynamic`: the table and the two sliders
    are motors with force limits that chase those joints over the path's
    time step, the links and the tool's closure follow under PyBullet's
    dynamics; the encoders are the joints the env observes, kappa is taken
    where they put the tool, and the tracking error, charged by
    ``w_track`` in both action modes, is how far the tool is from the
    path). ``dynamics``: an
    :class:`~paragym.sim.orthoglide_dynamic.OrthoglideDynamics`. ``engine``:
    the dynamic fidelity's physics, "pybullet" (default) or "mujoco" (or a
    :class:`~paragym.sim.mujoco_sim.MuJoCoSettings`): the same model, rules
    and checks in MuJoCo (the ``mujoco`` extra; its servos correct an error
    at 100 /s as PyBullet's motors do, and the sliders ride their guides
    without touching them; the conformance page compares the engines).
    ``engine=MuJoCoSettings(mirror=False)``: MuJoCo alone (no PyBullet
    scene; the gap at C as MuJoCo's loop closure has it), each path step
    from a cold solver start; the native vector env runs it for N robots at
    once (``gym.make_vec(ID, N, vectorization_mode="vector_entry_point",
    fidelity="dynamic", engine="mujoco")``), and this env is its N = 1 case,
    bit for bit.

    ## Version History
    * v0: initial release (kinematic fidelity).
      Since paragym 0.6.0 ``fidelity="dynamic"`` is offered; the default,
      kinematic, is unchanged.
      Since paragym 0.2.0 a custom scenario that cannot run (NaN, outside
      the workspace, malformed) and non-dict ``options`` are refused at reset
      with a ValueError or TypeError naming them; every episode that ran
      before runs the same (tested against recorded rollouts).
      Its holes, kept so that its episodes replay: in joint-velocity mode
      success ignores tracking (doing nothing succeeds); kappa is taken at
      the path point in kinematic fidelity and at the tool in dynamic; the
      dynamic fidelity rounds each path step to whole physics steps (it
      warns where that is not the path's time). Since paragym 0.8.0
      ``info["failure"]`` names why an episode failed.
    * v1 (paragym 0.8.0): :class:`Orthoglide2PRRKappaV1Env` closes them.
    * paragym 0.10, every version: one lifecycle (a step after termination, before reset or after
      ``close`` is refused; unknown reset options too; no copy shares a PyBullet client) and the
      reward's terms in the info; every episode runs as before.
    * paragym 0.10, every version and rung: ``engine="mujoco"`` runs the dynamic fidelity in MuJoCo;
      PyBullet's, the default, runs as before. MuJoCo alone (``MuJoCoSettings(mirror=False)``) and the
      native dynamic vector env.
    """

    task, rules = TASK, RULES[0]


class Orthoglide2PRRKappaV1Env(Orthoglide2PRRKappaEnv):
    """``paragym/Orthoglide2PRRKappa-v1``: v0's mechanism, paths, spaces and
    reward, with success that requires the tracking the task asks for.

    ## Episode End
    As v0, and a step whose tool is more than ``track_tolerance`` (5 mm)
    from its path point is a failure: it costs ``limit_penalty`` and ends
    the episode. In null-space mode the kinematic tool is on the path by
    construction (eq 5); the dynamic fidelity's lag counts. In dynamic
    fidelity a loop open by more than 5 mm (a broken mechanism) is a
    failure too. ``info["failure"]`` names the reason ("joint limit",
    "working mode", "singular", "tracking", "broken"; None while none).

    ## Rewards
    As v0, with kappa (eq 8) taken where the joints put the tool, in every mode and fidelity (in kinematic
    null-space mode that is the path point).

    ## Observation Space
    ``Box(-10, 10, (11,), float32)``, each component clipped to +-10; kappa and n are taken where the joints
    put the tool, in every mode and fidelity (in kinematic null-space mode that is the path point):

    ==========  ==========================================================
    0-2         rho (the table and the two sliders), normalised to [-1, 1] over their limits
    3-4         the path point of this step (table frame, m)
    5-6         the path point of the next step (table frame, m)
    7           log kappa at the joints (10 from kappa = 2.2e4 on, and where J is singular)
    8-10        n, the null vector of J at the joints (zeros where J is singular)
    ==========  ==========================================================

    ## Arguments
    As v0, plus ``track_tolerance`` (m). In dynamic fidelity each path step
    is simulated over exactly its duration: where the physics step does not
    divide it, the step is shortened to the fewest equal steps that do.

    ## Starting State, Action Space
    As v0.

    ## Version History
    * v1 (paragym 0.8.0): the rules above; in null-space mode and kinematic
      fidelity its episodes are v0's, bit for bit.
    """

    rules = RULES[1]


class Orthoglide2PRRKappaV2Env(Orthoglide2PRRKappaV1Env):
    """``paragym/Orthoglide2PRRKappa-v2``: v1's task; in dynamic fidelity the table runs beneath the sliders'
    guides.

    ## Description, Action Space, Observation Space, Rewards, Starting State, Episode End, Arguments
    As v1. The kinematic fidelity is v1's, bit for bit.

    ## Dynamic Fidelity
    PyBullet's is converged at its setting; in MuJoCo (``engine="mujoco"``, a 1 ms step) the tool's path runs
    1.83 mm from the same episodes at half the step for half a second of one episode, with no verdict changed
    (``python benchmarks/convergence.py``, the conformance page).

    ## Version History
    * v2 (paragym 0.10): the table beneath the guides in dynamic fidelity.
    * v1 (paragym 0.8.0): success requires tracking in every action mode and fidelity.
    * v0: the task of paper 003.
    """

    rules = RULES[2]


class Orthoglide2PRRKappaVectorEnv(ParagymVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaEnv` stepped together:
    the same transition (:mod:`paragym.tasks.orthoglide_step`) over N robots.
    Keyword arguments are the single env's (kinematic fidelity)."""

    task, rules = TASK, RULES[0]


class Orthoglide2PRRKappaV1VectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaV1Env` stepped together."""

    rules = RULES[1]


class Orthoglide2PRRKappaV2VectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaV2Env` stepped together."""

    rules = RULES[2]


class Orthoglide2PRRKappaEasyEnv(Orthoglide2PRRKappaV1Env):
    """``paragym/Orthoglide2PRRKappa-Easy-v0``: rung 0 of the Orthoglide's difficulty ladder: v1's task, where
    success asks for a mean kappa that the least-norm motion never reaches.

    ## Description
    Each path is drawn by :func:`paragym.tasks.orthoglide.ladder_scenarios` from the rung's knobs
    (:data:`paragym.tasks.orthoglide.LADDER`): a circle or an ellipse (closed paths, where the table's
    null-space choice matters: on v1's random lines the paper's gradient cannot beat the least-norm motion on
    one in five) with its centre in v1's region, radii in ``radius`` and one lap in ``period`` s. At reset the
    least-norm motion (the zero action in null-space mode, paper 003's case b, kinematic) is run along it by
    the task's own transition; success asks for a mean kappa over the path points of at most
    ``1 + share (kappa_least_norm - 1)`` (:func:`paragym.tasks.orthoglide_step.kappa_bounds`):

{knobs}

    ## Episode End
    As v1 (the path's end, or a failure); ``is_success`` also asks for the mean kappa above.
    ``info["mean_kappa"]`` is the mean so far, ``info["kappa_bound"]`` the bound.

    ## Arguments
    As v1; ``scenario`` "random" (the default) is the rung's path; "paper" and custom paths are v1's, with
    their own bound.

    ## Action Space, Observation Space, Rewards, Starting State
    As v1.

    ## Dynamic Fidelity
    The rungs were released with v1's dynamic scene, whose table runs at the height of the sliders' guides
    (``paragym/Orthoglide2PRRKappa-v2`` lowers it). On a lap that carries the table to the x guide's end it
    strikes the guide and the tool leaves the path whatever the policy. Measured over 10 dynamic episodes
    (reset seeds 0 and 300001-300009) the reference ``gradient-c-limited`` succeeds on 9, 8 and 7 of them on
    the easy, medium and hard rungs, and on 10 of 10 on each once the table runs beneath the guides. The KF
    check passes the reference's three leaderboard episodes on each rung, and 29 of 33, 29 of 33 and 15 of 36
    of all the rungs' leaderboard rows (every policy; on the hard rung 7 end before the sensors can judge
    them). It once failed the medium and hard rungs for every policy on the table's y acceleration ``a_Hy``:
    the recorder took PyBullet's velocity of link AC's centre of mass, 0.5 m beyond C, for C's; it now takes
    the link frame's origin in both engines (:data:`paragym.validation.episode.RECORDER`).

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[0]


Orthoglide2PRRKappaEasyEnv.__doc__ = (Orthoglide2PRRKappaEasyEnv.__doc__ or "").format(knobs=knob_table("    "))


class Orthoglide2PRRKappaMediumEnv(Orthoglide2PRRKappaEasyEnv):
    """``paragym/Orthoglide2PRRKappa-Medium-v0``: rung 1 of the Orthoglide's difficulty ladder: the easy rung's
    paths under a tighter bound on the mean kappa.

    ## Description, Episode End, Arguments, Action Space, Observation Space, Rewards, Starting State
    As v0 of the easy rung (``paragym/Orthoglide2PRRKappa-Easy-v0``), with rung 1's knobs.

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[1]


class Orthoglide2PRRKappaHardEnv(Orthoglide2PRRKappaEasyEnv):
    """``paragym/Orthoglide2PRRKappa-Hard-v0``: rung 2 of the Orthoglide's difficulty ladder: faster laps under
    the tightest bound on the mean kappa, with the policy driving the three joints itself.

    ## Description, Starting State
    As v0 of the easy rung (``paragym/Orthoglide2PRRKappa-Easy-v0``), with rung 2's knobs (its page's table).

    ## Action Space
    ``Box(-1, 1, (3,))``: joint rates (table, slider 2, slider 3) times ``max_joint_rate`` (0.5 m/s), clipped
    to the Box. The rung fixes ``action_mode="joint_velocity"``; another raises ``ValueError``.

    ## Observation Space
    ``Box(-10, 10, (13,), float32)``, each component clipped to +-10: v1's eleven (kappa and n where the joints
    put the tool), then the offset:

    ==========  ==========================================================
    0-2         rho (the table and the two sliders), normalised to [-1, 1] over their limits
    3-4         the path point of this step (table frame, m)
    5-6         the path point of the next step (table frame, m)
    7           log kappa (10 from kappa = 2.2e4 on, and where J is singular)
    8-10        n, the null vector of J (zeros where J is singular)
    11-12       the tool's offset from this step's path point (x, y, table frame, cm)
    ==========  ==========================================================

    ## Rewards
    v1's in joint-velocity mode: ``-log(kappa) - w_track * tracking error / 0.01 m`` per step; a failure costs
    ``limit_penalty`` plus 1 per path point left (the rung's ``left_penalty``), so that leaving the path early
    never pays better than tracking it (a step that tracks costs log kappa, about 0.1, plus at most 0.5).

    ## Episode End
    As the easy rung: the path's end, or a failure, a tracking error beyond ``track_tolerance`` (5 mm) among
    them; ``is_success`` asks for the mean kappa under ``info["kappa_bound"]``.

    ## Arguments
    As the easy rung, without ``action_mode`` (fixed).

    ## Version History
    * v0 (paragym 0.10): the rung above.
    """

    rules = LADDER_RULES[2]


class Orthoglide2PRRKappaEasyVectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaEasyEnv` stepped together."""

    rules = LADDER_RULES[0]


class Orthoglide2PRRKappaMediumVectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaMediumEnv` stepped together."""

    rules = LADDER_RULES[1]


class Orthoglide2PRRKappaHardVectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaHardEnv` stepped together."""

    rules = LADDER_RULES[2]


class Orthoglide2PRRKappaEasyV1Env(Orthoglide2PRRKappaEasyEnv):
    """``paragym/Orthoglide2PRRKappa-Easy-v1``: rung 0 of the Orthoglide's ladder v1: the easy rung's paths, its
    dynamic fidelity with v2's table beneath the sliders' guides.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of this rung (``paragym/Orthoglide2PRRKappa-Easy-v0``): the same paths and bound, bit for bit in the
    kinematic fidelity.

    ## Dynamic Fidelity
    As v2 (``paragym/Orthoglide2PRRKappa-v2``): the table runs beneath the guides, in PyBullet and in MuJoCo.
    The ladder v0 keeps v1's table at the guides' height, where it strikes the x guide's end on laps that carry
    it there, and where MuJoCo holds the table against the guide from the first step, so that the tool starts
    off the path and the episode fails within its first steps whatever the policy.

    ## Version History
    * v1 (paragym 0.10): the ladder v1, above; the ladder v0's ids (``-Easy-v0`` ...) are unchanged, and their
      shipped models play these rungs.
    """

    rules = LADDER_RULES_V1[0]


class Orthoglide2PRRKappaMediumV1Env(Orthoglide2PRRKappaMediumEnv):
    """``paragym/Orthoglide2PRRKappa-Medium-v1``: rung 1 of the Orthoglide's ladder v1: the medium rung's paths,
    its dynamic fidelity with v2's table beneath the guides.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of this rung (``paragym/Orthoglide2PRRKappa-Medium-v0``), bit for bit in the kinematic fidelity.

    ## Dynamic Fidelity
    As ``paragym/Orthoglide2PRRKappa-Easy-v1``.

    ## Version History
    * v1 (paragym 0.10): the ladder v1, above.
    """

    rules = LADDER_RULES_V1[1]


class Orthoglide2PRRKappaHardV1Env(Orthoglide2PRRKappaHardEnv):
    """``paragym/Orthoglide2PRRKappa-Hard-v1``: rung 2 of the Orthoglide's ladder v1: the hard rung's laps, its
    dynamic fidelity with v2's table beneath the guides.

    ## Description, Arguments, Action Space, Observation Space, Rewards, Starting State, Episode End
    As v0 of this rung (``paragym/Orthoglide2PRRKappa-Hard-v0``), bit for bit in the kinematic fidelity: the
    policy drives the joints.

    ## Dynamic Fidelity
    As ``paragym/Orthoglide2PRRKappa-Easy-v1``.

    ## Version History
    * v1 (paragym 0.10): the ladder v1, above.
    """

    rules = LADDER_RULES_V1[2]


class Orthoglide2PRRKappaEasyV1VectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaEasyV1Env` stepped together."""

    rules = LADDER_RULES_V1[0]


class Orthoglide2PRRKappaMediumV1VectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaMediumV1Env` stepped together."""

    rules = LADDER_RULES_V1[1]


class Orthoglide2PRRKappaHardV1VectorEnv(Orthoglide2PRRKappaVectorEnv):
    """``num_envs`` copies of :class:`Orthoglide2PRRKappaHardV1Env` stepped together."""

    rules = LADDER_RULES_V1[2]


#: the names of before paragym 0.9, answered with a DeprecationWarning
__getattr__ = renamed(__name__, {"orthoglide_random_task": "random_scenario"})
