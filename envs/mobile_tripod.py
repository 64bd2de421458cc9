"""``paragym/MobileTripodOdometry-v0``: estimate a mobile tripod's drive units under slip (paper 004).

The single env and the native vector env are shells over one transition,
:mod:`paragym.tasks.mobile_tripod_step` (the single env is its N = 1 case),
whose drive physics is :mod:`paragym.sim.tripod_drive`; the scenarios come
from :mod:`paragym.tasks.mobile_tripod`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from paragym.envs.base import ParagymEnv, check_control_period, pose6
from paragym.envs.vector import ParagymVectorEnv
from paragym.mechanisms import mobile_tripod as mt
from paragym.sim.client import physics_steps
from paragym.sim.tripod_dynamic import TripodDynamics
from paragym.tasks import mobile_tripod_step as task_step
from paragym.tasks.mobile_tripod import TripodScenario, draw_drive, drive_scenario, resolve_drive
from paragym.tasks.mobile_tripod_step import TripodParams, TripodState

__all__ = ["MobileTripodOdometryEnv", "MobileTripodOdometryV1Env", "MobileTripodOdometryV1VectorEnv",
           "MobileTripodOdometryV2Env", "MobileTripodOdometryV2VectorEnv", "MobileTripodOdometryVectorEnv",
           "drive_scenario"]


class _TripodTask:
    """The task's hooks, the same for the single env (N = 1) and the vector env."""

    state: TripodState
    params: TripodParams

    def new_state(self, n: int) -> TripodState:
        return TripodState.empty(n, self.params.obs_size)

    def _start(self, rows: np.ndarray, rngs: list[np.random.Generator], options: dict[str, Any]) -> list[Any]:
        choice = resolve_drive(options.get("scenario", self.scenario_arg))
        scenarios = [draw_drive(choice, rng) for rng in rngs]
        task_step.reset(self.state, self.params, rows, scenarios, rngs)
        if getattr(self, "world", None) is not None:
            self.world.reset(self.state)
        return scenarios

    def _transition(self, actions: np.ndarray, active: np.ndarray) -> None:
        task_step.step(self.state, self.params, actions, active, getattr(self, "world", None))


class MobileTripodOdometryEnv(_TripodTask, ParagymEnv):
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
    """

    version = 0
    #: v2's rules: a folded mechanism ends the episode; a physics step that does not divide the sample is refused
    _v2_rules = False

    def __init__(self, scenario: str | TripodScenario = "random", render_mode: str | None = None,
                 encoder_noise: float = math.radians(1.0), max_correction: float = 0.05,
                 success_error: float = 0.05, geometry: mt.TripodGeometry = mt.DEFAULT_GEOMETRY,
                 trust_rate: float | None = None, relative_reward: bool | None = None, fidelity: str = "kinematic",
                 dynamics: TripodDynamics | None = None) -> None:
        super().__init__(render_mode)
        if fidelity not in ("kinematic", "dynamic"):
            raise ValueError(f"fidelity must be 'kinematic' or 'dynamic'; got {fidelity!r}")
        if dynamics is not None and not isinstance(dynamics, TripodDynamics):
            raise TypeError(f"dynamics must be a TripodDynamics or None; got {type(dynamics).__name__}")
        if self.version == 0 and (trust_rate is not None or relative_reward is not None):
            raise ValueError("trust_rate and relative_reward are v1 arguments: use paragym/MobileTripodOdometry-v1")
        trust_rate = 0.2 if trust_rate is None else trust_rate
        relative_reward = True if relative_reward is None else relative_reward
        if not (np.isfinite(trust_rate) and 0 < trust_rate <= 1):
            raise ValueError(f"trust_rate must be in (0, 1]; got {trust_rate!r}")
        if isinstance(scenario, str):  # a custom drive is checked at reset, as before
            resolve_drive(scenario)
        if not (np.isfinite(encoder_noise) and encoder_noise >= 0):
            raise ValueError(f"encoder_noise must be >= 0 rad; got {encoder_noise!r}")
        self.scenario_arg, self.geometry = scenario, geometry
        self.encoder_noise, self.max_correction, self.success_error = encoder_noise, max_correction, success_error
        self.trust_rate, self.relative_reward = float(trust_rate), bool(relative_reward)
        self.params = TripodParams(float(encoder_noise), float(max_correction), geometry, self.version,
                                   trust_rate=self.trust_rate, relative_reward=self.relative_reward,
                                   fold_ends=self._v2_rules)
        self.action_space = spaces.Box(-1.0, 1.0, (self.params.action_size,), np.float32)
        self.observation_space = spaces.Box(-100.0, 100.0, (self.params.obs_size,), np.float32)
        self.state = self.new_state(1)
        self.fidelity = fidelity
        self.world: task_step.DynamicWorld | None = None
        if fidelity == "dynamic":
            check_control_period(self.state.drive.dt, (dynamics or TripodDynamics()).time_step, refuse=self._v2_rules,
                                 later="paragym/MobileTripodOdometry-v2")
            self.world = task_step.DynamicWorld(geometry, dynamics, gui=render_mode == "human")

    def _detected_fault(self) -> tuple[int, str] | None:
        """The paper's reading of eq 4 against eq 5 for the current estimate:
        which unit looks faulty, and whether eta says it went inward or outward."""
        s = self.state
        if s.drive.k[0] == 0:
            return None
        target = mt.distances(mt.plate_frame_units(s.eta[0], self.geometry))[0]
        diff = np.abs(mt.distances(s.estimate[0])[0] - target)
        order = np.argsort(diff, kind="stable")
        if diff[order[1]] <= 0.03 or diff[order[0]] >= 0.03:
            return None
        k = int(order[0])  # eta grows when a unit moves inward (eta measured down from the plate)
        return k, "inward (bump or push)" if s.eta[0, k] > s.last_eta[0, k] else "outward (hole or slip)"

    def _info(self) -> dict[str, Any]:
        s, d = self.state, self.state.drive
        info = {"true_units": d.true[0].copy(), "estimate": s.estimate[0].copy(), "odometry": d.odometry[0].copy(),
                "eta": s.eta[0].copy(), "unit_error": float(s.unit_error[0]), "plate_error": float(s.plate_error[0]),
                "detected_fault": self._detected_fault(), "t": float(d.t[0]),
                "is_success": bool(s.terminated[0] and s.unit_error[0] < self.success_error
                                   and not (self._v2_rules and s.folded[0])),
                "failure": "folded" if s.folded[0] else None}
        if self.version == 1:  # the smoothed encoder distances that v1's correction steers to
            info["encoder_distances"] = s.smoothed[0].copy()
        return info

    # KF validation (dynamic fidelity): the upper plate, sampled at 100 Hz (a slow vehicle)
    sensor_layout: dict[str, float] = {"r": 0.3, "depth": 0.1, "rate": 100.0}
    _commanded_eta: np.ndarray | None = None

    def _body(self) -> tuple[Any, str, int, np.ndarray, float]:
        scene = self.world.scene
        return scene.sim, scene.ROBOT, scene.plate_link, np.zeros(3), self.world.dynamics.time_step

    def commanded_pose(self) -> np.ndarray:
        """The plate the policy claims: fitted to its estimated units, on the legs' angles they imply (paper
        004, eqs 4-5; least squares where no legs reach). The robot drives the commanded path whatever the
        policy does; the policy is the estimator."""
        s = self.state
        if s.drive.k[0] == 0 or self._commanded_eta is None:  # a new episode: the legs as they start
            self._commanded_eta = s.drive.eta[0].copy()
        units = s.estimate[0] + [0.0, 0.0, self.world.dynamics.unit_height]
        self._commanded_eta = mt.eta(units[None], self._commanded_eta[None], self.geometry)[0][0]
        rotation, centre = mt.plate_fit(units, self._commanded_eta, self.geometry)
        return pose6(centre[0], rotation[0])

    def step_duration(self) -> float:
        h = self._dynamic_body()[4]
        return h * physics_steps(self.state.drive.dt, h)

    def _show(self) -> None:
        if self.world is None:  # the dynamic scene's GUI shows the simulation as it runs
            self._render_rgb()

    def _close(self) -> None:
        self._close_render_scene()
        if self.world is not None:
            self.world.close()

    def _render_rgb(self) -> np.ndarray:
        from paragym.sim.tripod_scene import TripodScene

        if self.world is not None:  # the simulated robot, not the kinematic model
            return self.world.scene.render()
        d = self.state.drive
        _, rotation, centre = mt.forward(d.true[:1], eta0=d.eta[0], geometry=self.geometry)
        return self._drawn(lambda gui: TripodScene(self.scenario.terrain, gui=gui),
                           lambda scene: scene.set_state(d.true[0], centre[0], rotation[0], self.geometry))


class MobileTripodOdometryV1Env(MobileTripodOdometryEnv):
    """``paragym/MobileTripodOdometry-v1``: v0's drives, success and end, with
    an action, an observation and a reward under which learning beats
    odometry.

    ## Why v1
    In v0 the action is a correction added to the estimate, so every
    correction stays in it for the rest of the drive: exploration noise and
    any bias of a learned policy integrate, and in the directions the
    encoders cannot see (a rigid shift or turn of all three units) nothing
    pulls them back. v0's best learned agent ended 58.9 cm off, against
    12.1 cm for odometry alone and 3.0 cm for the paper's correction. The
    observation also gave absolute world coordinates, leaving the policy to
    compute the inter-unit distances itself. The ablation behind v1 is in
    ``baselines/ABLATION.md``.

    ## Action Space
    ``Box(-1, 1, (3,))``: for each unit u, the fraction ``clip(a_u, 0, 1)``
    of the way its estimate moves, before the drive advances, toward where
    the paper's correction puts it (section 3: on the circles about the other
    two estimated units whose radii are the encoder distances of eq 4,
    exponentially smoothed with factor 0.1 per sample, as the reference
    smooths them; :func:`paragym.mechanisms.mobile_tripod.k_relocate`).
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

    version = 1


class MobileTripodOdometryV2Env(MobileTripodOdometryV1Env):
    """``paragym/MobileTripodOdometry-v2``: v1's task, in which a folded
    mechanism ends the episode as a failure.

    ## Why v2
    Some drives fold the tripod: a leg reaches the horizontal (true eta <= 0)
    and the plate comes down. In v0 and v1 both fidelities carried on as if
    nothing happened (7 % of random drives fold in kinematic fidelity, 14 of
    200 seeds; the dynamic fidelity folds on others, since its units slip
    and bump differently). Ending those episodes changes what v1 did, so it
    is v2.

    ## Episode End
    As v1, and when a leg reaches the horizontal: the episode ends there,
    ``is_success`` is False and ``info["failure"]`` is "folded" (in v0 and v1
    it says so too, without ending the episode).

    ## Arguments
    As v1. A dynamics whose physics step does not divide the 0.05 s sample is
    refused (v0 and v1 round it, and warn).

    ## Action Space, Observation Space, Rewards, Starting State
    As v1.

    ## Version History
    * v2 (paragym 0.8.0): the folded end above; drives that do not fold are
      v1's, bit for bit, and so are v1's shipped models.
    """

    _v2_rules = True


class MobileTripodOdometryVectorEnv(_TripodTask, ParagymVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryEnv` stepped together:
    the same transition (:mod:`paragym.tasks.mobile_tripod_step`) over N
    robots. Keyword arguments are the single env's."""

    single_class = MobileTripodOdometryEnv

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, render_index: int = 0,
                 **kwargs: Any) -> None:
        if kwargs.get("fidelity", "kinematic") != "kinematic":
            raise ValueError("the native tripod vector env is kinematic: use gymnasium's sync/async vector modes "
                             "for the dynamic fidelity")
        super().__init__(num_envs, max_episode_steps, render_index, **kwargs)

    def _infos(self) -> dict[str, Any]:
        s = self.state
        folded_fails = s.folded & self.params.fold_ends
        return self._for_every_robot(unit_error=s.unit_error.copy(),
                                     is_success=s.terminated & (s.unit_error < self.single_env.success_error)
                                     & ~folded_fails)

    def _load_single(self, i: int) -> None:
        one, s = self.single_env.state, self.state
        one.drive.scenarios[0] = s.drive.scenarios[i]
        one.drive.true[0], one.drive.eta[0] = s.drive.true[i], s.drive.eta[i]


class MobileTripodOdometryV1VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryV1Env` stepped together."""

    single_class = MobileTripodOdometryV1Env


class MobileTripodOdometryV2VectorEnv(MobileTripodOdometryVectorEnv):
    """``num_envs`` copies of :class:`MobileTripodOdometryV2Env` stepped together."""

    single_class = MobileTripodOdometryV2Env
