"""Released env ids keep their behaviour: seeded in-Box rollouts against a recording.

``tests/data/released_v0.npz`` was recorded from the released code (before the action rule
of paragym 0.2.0 clipped out-of-Box actions): every released id, three seeds, 200 steps of
in-Box actions (uniform, and at the Box's corners, where a clip would show first), resetting
without a seed when an episode ends. A change of any number is a new version (-v1), not an
edit of a released one. ``python tests/test_released.py --record`` rewrites the recording,
only for a new release.
"""

import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import paragym

RELEASED = ["paragym/CaPaManCollisionFree-v0", "paragym/HybridSingularityFree-v0",
            "paragym/Orthoglide2PRRKappa-v0", "paragym/MobileTripodOdometry-v0"]
FILE = Path(__file__).with_name("data") / "released_v0.npz"
SEEDS, STEPS = (0, 1, 2), 200


def rollout(env_id: str, seed: int) -> np.ndarray:
    env = gym.make(env_id)
    rng = np.random.default_rng(2000 + seed)
    sp = env.action_space
    obs, _ = env.reset(seed=seed)
    rows = [np.append(np.asarray(obs, float), [0.0, 0.0, 0.0])]
    for t in range(STEPS):
        a = rng.uniform(sp.low, sp.high) if t % 2 else rng.choice([-1.0, 1.0], sp.shape)
        obs, r, te, tr, _ = env.step(a.astype(np.float32))
        rows.append(np.append(np.asarray(obs, float), [r, te, tr]))
        if te or tr:
            obs, _ = env.reset()
            rows.append(np.append(np.asarray(obs, float), [0.0, 0.0, 0.0]))
    env.close()
    return np.array(rows)


@pytest.mark.parametrize("env_id", RELEASED)
def test_released_ids_replay_their_recorded_in_box_episodes(env_id):
    assert env_id in paragym.ENVIRONMENTS
    recorded = np.load(FILE)
    for seed in SEEDS:
        want = recorded[f"{env_id.split('/')[1]}_seed{seed}"]
        got = rollout(env_id, seed)
        assert got.shape == want.shape
        np.testing.assert_array_equal(got[:, -2:], want[:, -2:])  # flags exactly
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


if __name__ == "__main__" and "--record" in sys.argv:
    FILE.parent.mkdir(exist_ok=True)
    np.savez_compressed(FILE, **{f"{e.split('/')[1]}_seed{s}": rollout(e, s) for e in RELEASED for s in SEEDS})
    print(f"wrote {FILE}")
