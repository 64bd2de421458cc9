"""One action rule for every env, single and native vector (issue 15, items 1 and 9).

An action outside the Box is clipped to it, as Gymnasium's own envs and SB3 expect; a
non-finite, non-numeric, complex or wrongly shaped action raises, naming ``action``. The
CaPaMan's motion between two checks is at most the grid's resolution, so no step can carry
the mechanism through an obstacle unchecked.
"""

import gymnasium as gym
import numpy as np
import pytest
from env_ids import KINEMATIC_IDS, STEP_IDS

from paragym.envs.capaman import SWEEP_STEP, CaPaManCollisionFreeEnv
from paragym.mechanisms import capaman
from paragym.mechanisms.geometry import quat_to_matrix
from paragym.sim import capaman_grid

IDS = KINEMATIC_IDS  # one id per kinematic fidelity (tests/env_ids.py)


def _rollout(env, actions, seed):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, r, te, tr, _ = env.step(a)
        out.append(np.append(obs, [r, te, tr]))
        if te or tr:
            break
    return np.concatenate(out)


@pytest.mark.parametrize("env_id", IDS)
def test_out_of_box_actions_are_clipped_to_the_box(env_id):
    """An action of 30 does what the action at the Box's bound does, in every env."""
    env = gym.make(env_id, disable_env_checker=True)
    rng = np.random.default_rng(0)
    shape = env.action_space.shape
    big = rng.choice([-30.0, 30.0], size=(40, *shape)) * rng.uniform(1.0, 2.0, size=(40, *shape))
    a = _rollout(env, big, seed=3)
    b = _rollout(env, np.clip(big, -1, 1), seed=3)
    env.close()
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("env_id", STEP_IDS)
def test_out_of_box_actions_are_clipped_in_the_native_vector_env(env_id):
    venv = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
    big = np.random.default_rng(1).uniform(-40, 40, (25, *venv.action_space.shape))

    def run(actions):
        venv.reset(seed=7)
        return np.concatenate([np.concatenate([o.ravel(), r, te, tr])
                               for o, r, te, tr, _ in (venv.step(a) for a in actions)])

    unclipped, clipped = run(big), run(np.clip(big, -1, 1))
    venv.close()
    np.testing.assert_array_equal(unclipped, clipped)


def test_the_observation_only_exploit_no_longer_wins_the_capaman():
    """The policy a = (target - alpha) * 45 / 2, unclipped, jumped through obstacles to the
    target in one step; clipped to the Box it is a proportional controller and collides as one."""
    env = gym.make("paragym/CaPaManCollisionFree-v0")
    successes = 0
    for seed in range(10):
        obs, _ = env.reset(seed=100 + seed)
        for _ in range(400):
            obs, r, te, tr, info = env.step((obs[6:9] - obs[0:3]) * 45 / 2)
            if te or tr:
                break
        successes += info["is_success"]
    env.close()
    assert successes <= 7


@pytest.mark.parametrize("env_id", STEP_IDS)
@pytest.mark.parametrize("bad, error", [
    ("0.5", TypeError), (np.array(["0.5", "0.1", "0.2"]), TypeError), (1 + 2j, TypeError),
    (10 ** 400, ValueError), (np.inf, ValueError), (None, TypeError), (object(), TypeError),
])
def test_bad_actions_get_a_clear_error_naming_the_action(env_id, bad, error):
    env = gym.make(env_id, disable_env_checker=True)
    env.reset(seed=0)
    shape = env.action_space.shape
    action = bad if isinstance(bad, np.ndarray | str) or bad is None or type(bad) is object else \
        np.full(shape, bad, dtype=object if isinstance(bad, int) else complex if isinstance(bad, complex) else float)
    if isinstance(bad, np.ndarray):
        action = np.resize(bad, shape)
    with pytest.raises(error, match="action"):
        env.step(action)
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    with pytest.raises(error, match="action"):
        venv.step(np.stack([action, action]) if not isinstance(action, str | type(None)) and type(bad) is not object
                  else action)
    venv.close()
    env.close()


def test_an_in_box_capaman_step_moves_no_point_further_than_the_grid_resolution():
    """The swept check: every point of the 17 parts moves at most 5 mm (the occupancy grid's
    cell) in a step of SWEEP_STEP per crank, so checking the end of each such step checks the
    motion at the grid's resolution. Worst case over the joint space, steps at the Box's corners."""
    g = capaman.DEFAULT_GEOMETRY
    clusters = capaman_grid.cluster_points(g, spacing=0.005)
    rng = np.random.default_rng(0)
    a0 = rng.uniform(g.alpha_min, g.alpha_max, (1500, 3))
    corner = np.sign(rng.uniform(-1, 1, (1500, 3)))
    a1 = np.clip(a0 + corner * SWEEP_STEP, g.alpha_min, g.alpha_max)

    def world(a):
        c, q = capaman.part_frames(a, g, validate=False)
        rot = quat_to_matrix(q.reshape(-1, 4)).reshape(len(a), -1, 3, 3)[:, clusters.part]
        return np.einsum("nmij,mj->nmi", rot, clusters.local) + c[:, clusters.part]

    worst = max(np.linalg.norm(world(a1[s:s + 100]) - world(a0[s:s + 100]), axis=-1).max()
                for s in range(0, len(a0), 100))
    assert 0.003 < worst <= 0.005


def test_a_large_max_joint_step_is_checked_along_the_motion():
    """With max_joint_step = 30 deg a step is checked every SWEEP_STEP: a step that would jump
    over an obstacle stops in it (a collision), where the end pose alone is clear."""
    env = CaPaManCollisionFreeEnv(scenario="paper", max_joint_step=np.radians(30))
    plain = CaPaManCollisionFreeEnv(scenario="paper", max_joint_step=np.radians(30))
    found = 0
    rng = np.random.default_rng(0)
    for _ in range(60):
        env.reset(seed=0)
        plain.reset(seed=0)
        a = rng.uniform(-1, 1, 3)
        _, _, _, _, info = env.step(a)
        g = plain.geometry
        end = np.clip(plain.state.alpha[0] + a * plain.max_joint_step, g.alpha_min, g.alpha_max)
        plain.scene.set_configuration(end)
        clear_at_end = plain.scene.clearance()[0] > 0
        if info["collision"] and clear_at_end:
            found += 1
            assert np.linalg.norm(info["alpha"] - end) > 1e-6  # it stopped on the way
    env.close()
    plain.close()
    assert found >= 1
