"""paragym/CaPaManCollisionFree-v0: the Gymnasium contract, determinism,
scenarios, rewards and bad input."""

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.utils.passive_env_checker import env_render_passive_checker

import paragym
from paragym.envs import CaPaManScenario
from paragym.mechanisms import capaman
from paragym.planners import GridPathPolicy
from paragym.rollout import run_episode
from paragym.sim.capaman_scene import CaPaManScene
from paragym.sim.obstacles import Cylinder
from paragym.tasks.capaman import paper_scenario

ENV_ID = "paragym/CaPaManCollisionFree-v0"
PARAGYM_IDS = sorted(i for i in gym.registry if i.startswith("paragym/"))


def test_every_paragym_id_is_registered():
    assert set(PARAGYM_IDS) == set(paragym.ENVIRONMENTS)


@pytest.mark.parametrize("env_id", PARAGYM_IDS)
@pytest.mark.slow
def test_check_env_passes_with_warnings_as_errors(env_id):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", message=".*is out of date.*")  # Gymnasium's note on v0: a newer id exists
        env = gym.make(env_id)
        # The render check would open every declared mode, "human" (a GUI window)
        # included; the headless rgb_array mode is checked on its own below.
        check_env(env.unwrapped, skip_render_check=True)
        env.close()
        env = gym.make(env_id, render_mode="rgb_array")
        env.reset(seed=0)
        env_render_passive_checker(env.unwrapped)
        env.close()


def _rollout(env, seed, n):
    obs, info = env.reset(seed=seed)
    env.action_space.seed(seed)
    out = [obs]
    for _ in range(n):
        obs, r, term, trunc, info = env.step(env.action_space.sample())
        out.append(np.concatenate([obs, [r, term, trunc, info["clearance"]]]))
        if term or trunc:
            obs, info = env.reset()
            out.append(obs)
    return np.concatenate(out)


@pytest.mark.parametrize("scenario", ["random", "paper"])
def test_same_seed_same_episodes(scenario):
    a, b = gym.make(ENV_ID, scenario=scenario), gym.make(ENV_ID, scenario=scenario)
    np.testing.assert_array_equal(_rollout(a, 7, 300), _rollout(b, 7, 300))
    obs1, info1 = a.reset(seed=11)  # after a random episode ...
    obs2, info2 = gym.make(ENV_ID, scenario=scenario).reset(seed=11)  # ... equals a fresh reset
    np.testing.assert_array_equal(obs1, obs2)
    assert info1["scenario"] == info2["scenario"]


def test_different_seeds_give_different_random_scenarios():
    env = gym.make(ENV_ID)
    scenarios = {env.reset(seed=s)[1]["scenario"].task_points for s in range(5)}
    assert len(scenarios) == 5


def test_render_rgb_array_and_close():
    env = gym.make(ENV_ID, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (360, 480, 3) and frame.dtype == np.uint8 and frame.std() > 10
    env.close()
    assert not env.unwrapped.scene.sim.connected


def test_paper_scenario_straight_joint_motion_collides():
    """Paper section 4: direct motion between the T.C.s collides with the obstacle."""
    scenario = paper_scenario()
    scene = CaPaManScene()
    scene.set_obstacles(scenario.obstacles)
    tp = scenario.alpha
    for i, j in ((0, 1), (1, 2), (2, 0)):
        line = tp[i] + np.linspace(0, 1, 60)[:, None] * (tp[j] - tp[i])
        dist = [(scene.set_configuration(a), scene.clearance()[0])[1] for a in line]
        assert min(dist) < 0, f"T.C.{i + 1} -> T.C.{j + 1} in a straight joint line should collide"
    for a in tp:
        scene.set_configuration(a)
        assert scene.clearance()[0] > 0
    tips = np.array(scenario.task_configs)
    assert np.all(np.hypot(tips[:, 0], tips[:, 1]) < 0.06)  # inside the paper's 6 cm circle
    scene.close()


@pytest.mark.parametrize("scenario", ["paper", "random"])
def test_a_collision_free_tour_exists(scenario):
    env = gym.make(ENV_ID, scenario=scenario)
    for seed in range(3 if scenario == "random" else 1):
        ep = run_episode(env, GridPathPolicy(env.unwrapped.max_joint_step), seed=seed)
        assert ep.success and not any(i["collision"] for i in ep.infos)
        assert ep.infos[-1]["reached"] == 3
        assert ep.rewards[-1] > 0  # the last T.C. reached pays the bonus


def test_collision_terminates_with_the_penalty():
    env = gym.make(ENV_ID, scenario="paper")
    env.reset(seed=0)
    target = paper_scenario().alpha[1]
    for _ in range(200):  # head straight for T.P.2: through the obstacle
        alpha = env.unwrapped.state.alpha[0]
        obs, r, term, trunc, info = env.step(np.clip((target - alpha) / np.radians(2), -1, 1))
        if term:
            break
    assert info["collision"] and term and not info["is_success"]
    assert r < -env.unwrapped.collision_penalty + 1


def test_actions_hold_at_the_joint_stops():
    env = gym.make(ENV_ID, scenario="paper")
    env.reset(seed=0)
    for _ in range(60):
        if env.step(np.ones(3, np.float32))[2]:
            break
    alpha = env.unwrapped.state.alpha[0]
    assert np.all(alpha <= capaman.DEFAULT_GEOMETRY.alpha_max + 1e-12)


@pytest.mark.parametrize("action, message", [
    (np.array([np.nan, 0, 0], np.float32), "finite"),
    (np.array([np.inf, 0, 0], np.float32), "finite"),
    (np.zeros(2, np.float32), "shape"),
])
def test_bad_actions_are_refused(action, message):
    env = gym.make(ENV_ID, scenario="paper", disable_env_checker=True)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="scenario must be"):
        gym.make(ENV_ID, scenario="nope")
    with pytest.raises(ValueError, match="fidelity"):
        gym.make(ENV_ID, fidelity="quantum")
    with pytest.raises(ValueError, match="max_joint_step"):
        gym.make(ENV_ID, max_joint_step=-1.0)
    with pytest.raises(ValueError, match="render_mode"), pytest.warns(UserWarning, match="render_mode"):
        gym.make(ENV_ID, render_mode="ascii")
    env = gym.make(ENV_ID)
    with pytest.raises(TypeError, match="scenario must be"):  # a wrong type: TypeError, as in every env
        env.reset(options={"scenario": 42})


def test_user_scenarios_are_validated():
    paper = paper_scenario()
    colliding = CaPaManScenario("mine", (Cylinder((0.0, 0.0, 0.05), 0.04, 0.10),), paper.task_points)
    env = gym.make(ENV_ID, scenario=colliding)
    with pytest.raises(ValueError, match="T.C.1 collides"):
        env.reset(seed=0)
    with pytest.raises(ValueError, match="not reachable"):
        CaPaManScenario.from_tool_tips([[0, 0, 0.0], [0.01, 0, 0.05], [0, 0.01, 0.05]], paper.obstacles)
    out_of_range = CaPaManScenario("mine", paper.obstacles, ((0.1, 1.5, 1.5),) + paper.task_points[1:])
    with pytest.raises(ValueError, match="joint range"):
        gym.make(ENV_ID, scenario=out_of_range).reset(seed=0)
    ok = CaPaManScenario.from_tool_tips(paper.task_configs, paper.obstacles, name="mine")
    obs, info = gym.make(ENV_ID, scenario=ok).reset(seed=0)
    assert info["scenario"].name == "mine"


def test_reward_follows_the_fitness_terms():
    env = gym.make(ENV_ID, scenario="paper", beta=0.0, w_progress=0.0)
    env.reset(seed=0)
    _, r, *_ , info = env.step(np.array([1.0, 0.0, 0.0], np.float32))
    assert r == pytest.approx(-np.radians(2.0))  # pure joint path length
    env = gym.make(ENV_ID, scenario="paper", beta=0.5, w_length=0.0, w_progress=0.0, delta=1.0)
    env.reset(seed=0)
    _, r, *_ = env.step(np.zeros(3, np.float32))
    assert r == pytest.approx(-0.5)  # within delta of an obstacle: the beta penalty


def test_dynamic_fidelity_passes_the_checker_and_tours_the_paper_scenario():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", message=".*is out of date.*")  # Gymnasium's note on v0: a newer id exists
        check_env(gym.make(ENV_ID, fidelity="dynamic").unwrapped, skip_render_check=True)
    env = gym.make(ENV_ID, scenario="paper", fidelity="dynamic")
    from paragym.planners import RrtGaPolicy

    ep = run_episode(env, RrtGaPolicy(env.unwrapped.max_joint_step), seed=0)
    assert ep.success and not any(i["collision"] for i in ep.infos)
    # the motors lag their commands: the measured joint path is not the commanded one
    commanded = env.unwrapped.state.command[0]
    assert np.abs(ep.infos[-1]["alpha"] - commanded).max() < np.radians(2)
    a = _rollout(gym.make(ENV_ID, scenario="paper", fidelity="dynamic"), 3, 40)
    b = _rollout(gym.make(ENV_ID, scenario="paper", fidelity="dynamic"), 3, 40)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("env_id", ["paragym/CaPaManCollisionFree-v0", "paragym/CaPaManCollisionFree-v1"])
def test_an_env_never_drawn_builds_no_visual_shapes_and_plays_as_a_drawn_one(env_id, monkeypatch):
    """Without a render mode, the scene that checks the scenarios builds collision shapes only (the obstacles
    at every reset took twice as long with their visual shapes); scenarios and episodes stay the same."""
    from paragym.sim import client

    made = []
    real = client.pb.createVisualShape
    monkeypatch.setattr(client.pb, "createVisualShape", lambda *a, **k: made.append(1) or real(*a, **k))
    plain = gym.make(env_id)
    runs = [run_episode(plain, GridPathPolicy(), seed=seed) for seed in range(3)]
    assert not made
    drawn = gym.make(env_id, render_mode="rgb_array")
    for seed, a in enumerate(runs):
        b = run_episode(drawn, GridPathPolicy(), seed=seed)
        assert a.infos[0]["scenario"] == b.infos[0]["scenario"]
        np.testing.assert_array_equal(a.observations, b.observations)
        assert a.episode_return == b.episode_return
    assert made and drawn.render().std() > 0
    plain.close()
    drawn.close()
