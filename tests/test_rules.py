"""The rules of the benchmark, over every fidelity and dynamics preset: an obstacle stops motion, the loops stay
closed within their documented tolerance, and a push cannot force a mechanism through its joint stops.

Each test here guards a hole that an independent check once found (issue 26): a check that sees only part of a
mechanism, a fast preset that lets the mechanism come apart under contact, cranks forced round past their range.
"""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

import paragym
from paragym import registry
from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import quat_to_matrix
from paragym.sim.capaman_dynamic import CONTACT_PUSHES, CaPaManDynamics, CaPaManDynamicScene, push_into
from paragym.sim.obstacles import Box
from paragym.tasks.capaman import CaPaManScenario, paper_scenario
from paragym.units import DEG

G = capaman.DEFAULT_GEOMETRY
HOME = np.asarray(G.alpha_home, float).ravel()

#: the CaPaMan's fidelities and dynamics presets: (fidelity, dynamics or None for the fidelity's default)
CAPAMAN_WORLDS = {
    "kinematic": ("kinematic", None),
    "released": ("dynamic", None),
    "fast": ("dynamic", CaPaManDynamics.fast()),
    "split": ("dynamic", CaPaManDynamics.split()),
}
PRESETS = {"fast": CaPaManDynamics.fast(), "split": CaPaManDynamics.split()}

#: loops closed within this much (m) in free motion, and under a push at the motors' torque limit (the
#: contract of paragym.sim.capaman_dynamic)
FREE_CLOSURE, CONTACT_CLOSURE = 1e-4, 1e-3


def _make(fidelity: str, dynamics: CaPaManDynamics | None, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # v0 is out of date: it stays registered and reproducible
        extra = {} if dynamics is None else {"dynamics": dynamics}
        return gym.make("paragym/CaPaManCollisionFree-v1", fidelity=fidelity, **kwargs, **extra)


# --- an obstacle stops motion -------------------------------------------------------------------------------


def _plate_box_scenario() -> CaPaManScenario:
    """A box 20 mm beyond the movable plate's rim at the plate's height, between legs 1 and 2: moving crank 1
    down and crank 2 up carries the plate into it."""
    toward = np.array([0.5, np.sqrt(3) / 2])
    box = Box((*(0.225 * toward), G.a + G.h), (0.01, 0.01, 0.02))
    return CaPaManScenario("plate-box", (box,), ((90 * DEG,) * 3, (120 * DEG, 60 * DEG, 90 * DEG),
                                                 (100 * DEG, 100 * DEG, 80 * DEG)))


@pytest.mark.parametrize("world", CAPAMAN_WORLDS)
def test_an_obstacle_at_the_plate_ends_the_episode_in_every_fidelity_and_preset(world):
    """The plate is a part like the others in every body layout: driven into a box, every fidelity and preset
    ends the episode with a collision at the same step (the split layout's plate, a free body's base, was
    once never checked and drove on)."""
    env = _make(*CAPAMAN_WORLDS[world], scenario=_plate_box_scenario())
    env.reset(seed=0)
    ended_at = None
    for t in range(30):
        *_, terminated, _, info = env.step(np.array([-1, 1, 0], np.float32))
        if terminated:
            ended_at = t
            break
    env.close()
    assert ended_at == 3 and info["collision"] and info["nearest_part"] == "plate", (world, ended_at, info)


# --- the loops stay closed, and the tool stops, under contact ----------------------------------------------

PUSHES = CONTACT_PUSHES


def _push(dynamics: CaPaManDynamics, push: str) -> tuple[np.ndarray, float]:
    """The tool tip at every control period (0.02 s) of a 1 s ramp of the commands into the box and 1 s of
    pushing on, and the largest loop-closure gap (m) (:func:`paragym.sim.capaman_dynamic.push_into`)."""
    scene = CaPaManDynamicScene(G, dynamics)
    try:
        return push_into(scene, push)
    finally:
        scene.close()


@pytest.fixture(scope="module")
def released_pushes():
    return {push: _push(CaPaManDynamics(), push) for push in PUSHES}


@pytest.mark.parametrize("push", PUSHES)
@pytest.mark.parametrize("preset", ["released", *PRESETS])
def test_an_obstacle_stops_the_tool_and_the_loops_hold_under_the_push(preset, push, released_pushes):
    """Pushed into a box at their torque limit, the motors do not pull the mechanism apart: the loops stay
    closed within 1 mm and the tool tip stays within 1 mm of where the released settings put it (the split
    preset of paragym 0.7.0 opened its ball joints by 15-18 mm)."""
    tips, gap = released_pushes[push] if preset == "released" else _push(PRESETS[preset], push)
    assert gap < CONTACT_CLOSURE, f"{preset}: loops open by {gap * 1e3:.2f} mm"
    drift = np.abs(tips - released_pushes[push][0]).max()
    assert drift < 1e-3, f"{preset}: the tool {drift * 1e3:.2f} mm from the released settings' under the push"


@pytest.mark.parametrize("preset", PRESETS)
def test_loops_stay_closed_in_free_motion_over_the_whole_range(preset):
    """Random steps of 2 deg, then each crank swept from 45 to 135 deg and all back: loops within 0.1 mm."""
    scene = CaPaManDynamicScene(G, PRESETS[preset])
    scene.set_configuration(HOME)
    rng, alpha, gap = np.random.default_rng(0), HOME.copy(), 0.0
    for _ in range(100):
        alpha = np.clip(alpha + rng.uniform(-1, 1, 3) * 2 * DEG, G.alpha_min, G.alpha_max)
        scene.drive(alpha, 0.02)
        gap = max(gap, scene.closure_error())
    alpha = np.full(3, G.alpha_min)
    scene.set_configuration(alpha)
    for k in (0, 1, 2, None):  # each crank up in turn, then all three down
        for _ in range(45):
            if k is None:
                alpha = np.maximum(alpha - 2 * DEG, G.alpha_min)
            else:
                alpha[k] = min(alpha[k] + 2 * DEG, G.alpha_max)
            scene.drive(alpha.copy(), 0.02)
            gap = max(gap, scene.closure_error())
    scene.close()
    assert gap < FREE_CLOSURE, f"{preset}: loops open by {gap * 1e3:.3f} mm in free motion"


# --- joint stops ------------------------------------------------------------------------------------------


def _flipped(scene: CaPaManDynamicScene) -> bool:
    """Whether a parallelogram has flipped: crank b no longer parallel to crank a (the dot of their axes < 0)."""
    for (body, a), (_, b) in zip(scene.motors, scene.cranks_b, strict=True):
        za = quat_to_matrix(scene.sim.link_frame(body, a)[1])[:, 2]
        zb = quat_to_matrix(scene.sim.link_frame(body, b)[1])[:, 2]
        if za @ zb < 0:
            return True
    return False


@pytest.mark.parametrize("preset", PRESETS)
def test_joint_stops_hold_the_cranks_when_pushed_on_after_a_collision(preset):
    """Hammering into the paper's obstacle and pushing on past the episode's end, full actions both ways: the
    cranks stay at their stops (the released settings, which have none, were forced to 10 deg), no
    parallelogram flips and the loops hold. Past the end the env refuses a step, so the task's transition is
    driven directly."""
    d = PRESETS[preset]
    env = _make("dynamic", d, scenario=paper_scenario())
    env.reset(seed=0)
    u = env.unwrapped
    scene = u.scene
    rng, lo, hi, gap, ended = np.random.default_rng(0), np.inf, -np.inf, 0.0, False
    for t in range(200):
        action = (np.sign(rng.uniform(-1, 1, 3)) if t % 40 < 20 else -np.ones(3)).astype(np.float32)
        if not ended:
            *_, terminated, _, _ = env.step(action)
            ended |= terminated
        else:
            u.task.step(u.state, u.params, action[None].astype(np.float64), np.ones(1, bool), u.world)
        lo, hi = min(lo, scene.alpha.min()), max(hi, scene.alpha.max())
        gap = max(gap, scene.closure_error())
        assert not _flipped(scene), f"{preset}: a parallelogram flipped at step {t}"
    env.close()
    assert ended
    assert G.alpha_min - d.stop_margin - 1.5 * DEG < lo and hi < G.alpha_max + d.stop_margin + 1.5 * DEG, \
        (np.degrees(lo), np.degrees(hi))
    assert gap < CONTACT_CLOSURE, f"{preset}: loops open by {gap * 1e3:.2f} mm"


def test_the_released_settings_end_the_episode_before_a_crank_leaves_its_range():
    """The released settings keep no joint stops (their motion stays bit for bit): their hole is only past an
    episode's end. Up to the collision that ends it, the cranks stay in their range (to the servo's lag)."""
    env = _make("dynamic", None, scenario=paper_scenario())
    env.reset(seed=0)
    scene, rng = env.unwrapped.scene, np.random.default_rng(0)
    for t in range(200):
        action = np.sign(rng.uniform(-1, 1, 3)) if t % 40 < 20 else -np.ones(3)
        *_, terminated, _, _ = env.step(action.astype(np.float32))
        assert G.alpha_min - 0.5 * DEG < scene.alpha.min() and scene.alpha.max() < G.alpha_max + 0.5 * DEG
        if terminated:
            break
    env.close()
    assert terminated


# --- the 2PRR: success is tracking, kappa has one definition, time runs at the path's rate --------------------

FIDELITIES = ("kinematic", "dynamic")


def _trivial_actions(name: str, space: gym.spaces.Box, rng: np.random.Generator) -> np.ndarray:
    """A trivial policy's action: zeros, the Box's low or high corner, or a uniform draw."""
    return {"zeros": lambda: np.zeros(space.shape), "low": lambda: space.low, "high": lambda: space.high,
            "random": lambda: rng.uniform(space.low, space.high)}[name]().astype(np.float32)


@pytest.mark.parametrize("fidelity", FIDELITIES)
@pytest.mark.parametrize("policy", ["zeros", "low", "high", "random"])
def test_2prr_v1_joint_rates_succeed_only_by_tracking(policy, fidelity):
    """In joint-velocity mode the agent must track the path: a trivial policy never succeeds, and says why (in
    v0 doing nothing succeeded on every path with a tracking error of up to 0.73 m)."""
    rng = np.random.default_rng(0)
    for seed in range(3):
        env = gym.make("paragym/Orthoglide2PRRKappa-v1", action_mode="joint_velocity", fidelity=fidelity)
        env.reset(seed=seed)
        while True:
            *_, terminated, truncated, info = env.step(_trivial_actions(policy, env.action_space, rng))
            if terminated or truncated:
                break
        env.close()
        assert not info["is_success"] and info["failure"] is not None, (seed, info)


@pytest.mark.parametrize("fidelity", FIDELITIES)
@pytest.mark.parametrize("mode", ["null_space", "joint_velocity"])
def test_2prr_v1_kappa_is_taken_where_the_joints_put_the_tool(mode, fidelity):
    """One definition of kappa (eq 8) in every mode and fidelity: J at the joints the env reports (in v0's
    kinematic joint-velocity mode it was taken at the path point, up to 0.58 away from the dynamic one's)."""
    from paragym.mechanisms import orthoglide as og

    env = gym.make("paragym/Orthoglide2PRRKappa-v1", action_mode=mode, fidelity=fidelity)
    env.reset(seed=1)
    rng, checked = np.random.default_rng(1), 0
    for _ in range(40):
        action = 0.2 * rng.uniform(env.action_space.low, env.action_space.high).astype(np.float32)
        *_, terminated, truncated, info = env.step(action)
        if np.isfinite(info["kappa"]):
            np.testing.assert_allclose(info["kappa"], og.kappa(info["rho"][None])[0], rtol=1e-6)
            checked += 1
        if terminated or truncated:
            break
    env.close()
    assert checked >= 3


@pytest.mark.parametrize("duration", [1.25, 2.5, 7.0, 13.0])
def test_2prr_v1_dynamic_time_runs_at_the_path_rate(duration):
    """A path of 1,000 samples over any duration is simulated over exactly that time (v0 rounded each sample to
    whole 5 ms physics steps: 1.25 s took 5 s)."""
    from paragym.tasks.orthoglide import circle_task

    task = circle_task((0.1, 0.55), 0.4, duration, steps=1000, name="custom")
    env = gym.make("paragym/Orthoglide2PRRKappa-v1", scenario=task, fidelity="dynamic")
    env.reset(seed=0)
    sim = env.unwrapped.world.scene.sim
    start = sim.elapsed
    for _ in range(30):
        *_, terminated, _, info = env.step(np.zeros(1, np.float32))
        if terminated:
            break
    env.close()
    assert sim.elapsed - start == pytest.approx(task.t[info["step"]], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("fidelity", FIDELITIES)
def test_2prr_v1_default_mode_replays_v0_bit_for_bit(fidelity):
    """In null-space mode v1's rules change nothing v0 did on its own scenarios (the tool is on the path by
    construction, the paths' samples divide into physics steps): v0's shipped models are v1's."""

    def rollout(env_id: str, seed: int) -> np.ndarray:
        env = gym.make(env_id, fidelity=fidelity)
        env.action_space.seed(seed)
        obs, _ = env.reset(seed=seed)
        rows = [obs]
        for _ in range(300):
            obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
            rows.append(np.append(obs, reward))
            if terminated or truncated:
                break
        env.close()
        return np.concatenate(rows)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for seed in (0, 1):
            np.testing.assert_array_equal(rollout("paragym/Orthoglide2PRRKappa-v1", seed),
                                          rollout("paragym/Orthoglide2PRRKappa-v0", seed))


# --- trivial policies never succeed where the task says they cannot, in every id, fidelity and preset -----------

#: per task, the scenario on which no trivial policy may succeed, and why: the CaPaMan's paper case puts the
#: obstacle between the T.C.s (standing still reaches nothing, the straight joint-space line collides); the
#: hybrid's paper path is not free at the default split (64 % of its poses are), so the nominal path (the zero
#: action) fails; in the tripod's initial-heading drive odometry alone ends 70 cm off (the zero action and v1's
#: non-positive actions are odometry alone)
HARD = {"CaPaManCollisionFree": "paper", "HybridSingularityFree": "paper", "MobileTripodOdometry": "initial_heading"}


def _dynamics_presets(env_id: str) -> dict[str, object]:
    """Every dynamics preset a user can pick for ``env_id``: the env's default (None) and the named ones."""
    from paragym.sim.hybrid_dynamic import HybridDynamics

    task = env_id.split("/")[1].rsplit("-v", 1)[0]
    return {"CaPaManCollisionFree": {"default": None, **PRESETS},
            "HybridSingularityFree": {"default": None, "split": HybridDynamics.split()}}.get(task, {"default": None})


def _worlds(env_ids):
    for env_id in env_ids:
        yield pytest.param(env_id, "kinematic", None, id=f"{env_id.split('/')[1]}-kinematic")
        for name, dynamics in _dynamics_presets(env_id).items():
            yield pytest.param(env_id, "dynamic", dynamics, id=f"{env_id.split('/')[1]}-dynamic-{name}")


HARD_IDS = sorted(i for i in paragym.ENVIRONMENTS if i.split("/")[1].rsplit("-v", 1)[0] in HARD)


def _straight_to_goal(env, rng):
    """The CaPaMan's straight joint-space line to the current target T.P., clipped to the Box."""
    u = env.unwrapped
    target = u.state.tp[0, u.state.target[0]]
    return np.clip((target - u.state.alpha[0]) / u.max_joint_step, -1, 1).astype(np.float32)


@pytest.mark.parametrize(("env_id", "fidelity", "dynamics"), list(_worlds(HARD_IDS)))
@pytest.mark.slow
def test_trivial_policies_never_succeed_on_the_hard_scenario(env_id, fidelity, dynamics):
    """Zeros, both corners of the Box and uniform random actions (and for the CaPaMan the straight line to
    the goal) never succeed on the scenario where the task rules it out, in every fidelity and preset."""
    task = env_id.split("/")[1].rsplit("-v", 1)[0]
    policies = ["zeros", "low", "high", "random"] + (["straight"] if task == "CaPaManCollisionFree" else [])
    rng = np.random.default_rng(0)
    for policy in policies:
        env = _make_any(env_id, fidelity, dynamics, scenario=HARD[task])
        env.reset(seed=0)
        while True:
            action = (_straight_to_goal(env, rng) if policy == "straight"
                      else _trivial_actions(policy, env.action_space, rng))
            *_, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
        env.close()
        assert not info["is_success"], f"{policy} succeeded on {HARD[task]}"


def _make_any(env_id: str, fidelity: str, dynamics, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # older versions are out of date: they stay registered and reproducible
        extra = {} if dynamics is None else {"dynamics": dynamics}
        return gym.make(env_id, fidelity=fidelity, **kwargs, **extra)


# --- a broken or folded mechanism ends the episode as a failure, with its reason ---------------------------------


def test_a_capaman_that_comes_apart_ends_its_episode_as_broken():
    """A solver too weak to hold the loops (2 iterations at 20 ms) opens them by over 5 mm in one step: the
    episode ends there as a failure, "broken", not a collision."""
    env = _make_any("paragym/CaPaManCollisionFree-v1", "dynamic",
                    CaPaManDynamics(time_step=0.02, solver_iterations=2, erp=0.05), scenario="paper")
    env.reset(seed=0)
    *_, terminated, _, info = env.step(np.array([1, -1, 1], np.float32))
    env.close()
    assert terminated and info["failure"] == "broken" and not info["collision"] and not info["is_success"]


def _hybrid_reference(env_id: str, scenario: str, seed: int, **kwargs) -> dict:
    from paragym.baselines.policies import get_policy

    env = _make_any(env_id, "dynamic", None, scenario=scenario, **kwargs)
    policy = get_policy(env_id, "polynomial-detour").factory(env, seed)
    obs, info = env.reset(seed=seed)
    policy.reset(obs, info)
    worst = 0.0
    while True:
        obs, _, terminated, truncated, info = env.step(policy.act(obs, info))
        worst = max(worst, info["tracking_error"])
        if terminated or truncated:
            break
    env.close()
    return {**info, "worst_tracking_error": worst}


@pytest.mark.parametrize(("scenario", "seed"), [("paper", 0), ("random", 200_001), ("random", 200_002)])
def test_hybrid_v2_reference_plans_inside_the_limits_and_succeeds_in_dynamic_fidelity(scenario, seed):
    """The leaderboard's dynamic episodes: v2's reference, planned 1 mm inside the stroke limits, succeeds on all
    three (v1's, planned at the limits, fails the paper's and the first random one: its strokes overshoot)."""
    info = _hybrid_reference("paragym/HybridSingularityFree-v2", scenario, seed)
    assert info["is_success"] and info["failure"] is None, info["failure"]


def test_hybrid_v2_tracks_orientation_as_well_as_position():
    """With the orientation tolerance tightened below what the simulated E does (0.2 deg), v2 fails the step on
    its orientation although its position tracks within 5 mm: the check is real (v1 has none)."""
    info = _hybrid_reference("paragym/HybridSingularityFree-v2", "paper", 0, track_angle_tolerance=np.radians(0.05))
    assert info["failure"] == "tracking" and not info["is_success"]
    assert info["worst_tracking_error"] < 5e-3
    with pytest.raises(ValueError, match="track_angle_tolerance"):
        gym.make("paragym/HybridSingularityFree-v1", fidelity="dynamic", track_angle_tolerance=0.01)


def test_tripod_v2_ends_a_folded_drive_and_v1_says_it_folded():
    """Random drive 158 folds the tripod at sample 474 (a leg past horizontal) in kinematic fidelity: v2 ends
    there as a failure, "folded"; v1 carries on to the end as released, and says it folded."""
    ends = {}
    for env_id in ("paragym/MobileTripodOdometry-v1", "paragym/MobileTripodOdometry-v2"):
        env = _make_any(env_id, "kinematic", None)
        env.reset(seed=158)
        steps = 0
        while True:
            *_, terminated, truncated, info = env.step(np.zeros(3, np.float32))
            steps += 1
            if terminated or truncated:
                break
        env.close()
        ends[env_id] = (steps, info["failure"], info["is_success"])
    assert ends["paragym/MobileTripodOdometry-v1"] == (606, "folded", False)
    assert ends["paragym/MobileTripodOdometry-v2"] == (474, "folded", False)
    venv = gym.make_vec("paragym/MobileTripodOdometry-v2", num_envs=1, vectorization_mode="vector_entry_point")
    venv.reset(seed=158)
    ended = [venv.step(np.zeros((1, 3), np.float32))[2][0] for _ in range(474)]
    venv.close()
    assert ended.index(True) == 473  # the native vector env ends it at the same sample


# --- time runs at the task's rate, and the hybrid's loops hold, in every dynamic id and preset -----------------

DYNAMIC_IDS = sorted(paragym.ENVIRONMENTS)


def _scene_of(env):
    """The dynamic scene of an env in dynamic fidelity (the CaPaMan's is the env's own; the others' their
    world's)."""
    u = env.unwrapped
    return u.scene if getattr(u, "world", None) is None or not hasattr(u.world, "scene") else u.world.scene


@pytest.mark.parametrize(("env_id", "fidelity", "dynamics"),
                         [p for p in _worlds(DYNAMIC_IDS) if p.values[1] == "dynamic"])
def test_simulated_time_runs_at_the_control_rate(env_id, fidelity, dynamics):
    """Five steps (or those before the end) simulate exactly as many control periods (the CaPaMan's 0.02 s, the
    hybrid's and the tripod's 0.05 s, the 2PRR's path sample): the physics runs at the task's rate, not a rounded
    one."""
    env = _make_any(env_id, fidelity, dynamics)
    env.action_space.seed(0)
    env.reset(seed=0)
    u = env.unwrapped
    period = {"capaman": lambda: u.control_period,
              "hybrid": lambda: u.world.control_period,
              "orthoglide": lambda: float(u.state.dt[0, 0]),
              "tripod": lambda: u.state.drive.dt}[registry.task_of(env_id)]()
    sim = _scene_of(env).sim
    start, steps = sim.elapsed, 0
    while steps < 5:  # random actions may end an episode early (a rung that tracks through the joints)
        steps += 1
        if any(env.step(env.action_space.sample())[2:4]):
            break
    env.close()
    assert sim.elapsed - start == pytest.approx(steps * period, rel=1e-9)


@pytest.mark.parametrize("preset", ["default", "split"])
def test_hybrid_ball_joints_hold_under_any_in_box_actions(preset):
    """Random actions (the offset jumping by up to 20 mm a step): the nine ball joints stay within 4 mm, below
    the 5 mm of a broken mechanism (the split preset at 30 iterations opened them by 5.8 mm)."""
    from paragym.sim.hybrid_dynamic import HybridDynamics

    dynamics = None if preset == "default" else HybridDynamics.split()
    gap = 0.0
    for seed in range(2):
        env = _make_any("paragym/HybridSingularityFree-v2", "dynamic", dynamics)
        env.action_space.seed(seed)
        env.reset(seed=seed)
        while True:
            *_, terminated, truncated, info = env.step(env.action_space.sample())
            gap = max(gap, env.unwrapped.world.scene.closure_error())
            if terminated or truncated:
                break
        env.close()
        assert info["failure"] != "broken"
    assert gap < 4e-3, f"{preset}: ball joints open by {gap * 1e3:.2f} mm"


def test_a_hybrid_or_2prr_that_comes_apart_ends_its_v2_or_v1_episode_as_broken():
    """A solver too weak to hold the closures opens them by over 5 mm: the newest ids end the episode there as a
    failure, "broken" (the released ids carry on, as released)."""
    from paragym.sim.hybrid_dynamic import HybridDynamics
    from paragym.sim.orthoglide_dynamic import OrthoglideDynamics

    weak = {"paragym/HybridSingularityFree-v2": (HybridDynamics(time_step=0.01, solver_iterations=2, erp=0.1), {}),
            "paragym/Orthoglide2PRRKappa-v1": (OrthoglideDynamics(time_step=0.01, solver_iterations=1),
                                               {"action_mode": "joint_velocity", "track_tolerance": 10.0})}
    for env_id, (dynamics, kwargs) in weak.items():
        env = _make_any(env_id, "dynamic", dynamics, scenario="paper", **kwargs)
        env.action_space.seed(0)
        env.reset(seed=0)
        for _ in range(30):
            *_, terminated, _, info = env.step(env.action_space.sample())
            if terminated:
                break
        env.close()
        assert terminated and info["failure"] == "broken" and not info["is_success"], (env_id, info["failure"])


@pytest.mark.parametrize("mode", ["null_space", "joint_velocity"])
def test_2prr_closure_holds_under_any_in_box_actions(mode):
    """The tool's closure at C stays within 0.1 mm under random actions in either mode (the tracking rule
    loosened so that the episode runs on)."""
    env = _make_any("paragym/Orthoglide2PRRKappa-v1", "dynamic", None, action_mode=mode, track_tolerance=10.0)
    env.action_space.seed(0)
    env.reset(seed=0)
    gap = 0.0
    for _ in range(200):
        *_, terminated, _, _ = env.step(env.action_space.sample())
        gap = max(gap, env.unwrapped.world.scene.closure_error())
        if terminated:
            break
    env.close()
    assert gap < 1e-4, f"closure open by {gap * 1e3:.3f} mm"
