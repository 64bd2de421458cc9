"""The sim-to-sim gap: each env's reference and a learned policy on the paper's scenarios, kinematic vs dynamic.

For every env with a dynamic fidelity, the reference policy and one shipped
learned policy run the paper's scenario (seed 0) in the kinematic fidelity
and in the dynamic one (PyBullet's dynamics under force-limited motors, the
env's default settings), and the table gives success, return and the env's
own figure of merit: the CaPaMan's joint path length (rad), the hybrid's
smallest singularity measure and E's largest distance from its command
(mm), the 2PRR's mean kappa and the tool's largest tracking error (mm), the
tripod's final estimate error (mean over the units) and odometry's largest
unit error (cm), on two of the paper's drives.

    python benchmarks/dynamic_gap.py
"""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np

import paragym  # noqa: F401
from paragym.baselines.policies import get_policy
from paragym.rollout import run_episode

CASES = (("paragym/CaPaManCollisionFree-v1", "paper", ("rrt-ga", "dagger-seed0")),
         ("paragym/HybridSingularityFree-v1", "paper", ("polynomial-detour", "ppo-seed0")),
         ("paragym/Orthoglide2PRRKappa-v0", "paper", ("gradient-c", "ppo-seed0")),
         ("paragym/MobileTripodOdometry-v1", "initial_heading", ("encoder-correction", "bc-seed1")),
         ("paragym/MobileTripodOdometry-v1", "push", ("encoder-correction", "bc-seed1")))


def merit(env_id: str, infos: list[dict]) -> str:
    """The env's figures of merit over an episode's infos."""
    last = infos[-1]
    if "CaPaMan" in env_id:
        return f"path {last['path_length']:.3f} rad, reached {last['reached']}/3"
    if "Hybrid" in env_id:
        mu = min(min(i["mu_hexapod"], i["mu_tripod"]) for i in infos[1:])
        track = max(i.get("tracking_error", 0.0) for i in infos[1:])
        return f"min mu {mu:.3f}, E off command {track * 1e3:.2f} mm"
    if "Tripod" in env_id:
        odometry = np.linalg.norm(last["odometry"][:, :2] - last["true_units"][:, :2], axis=1).max()
        return f"estimate off {last['unit_error'] * 100:.1f} cm, odometry off {odometry * 100:.1f} cm"
    kappa = np.mean([i["kappa"] for i in infos[1:]])
    track = max(i["tracking_error"] for i in infos[1:])
    return f"mean kappa {kappa:.4f}, tracking {track * 1e3:.2f} mm"


def main() -> None:
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    print(f"{'environment, scenario':44s} {'policy':18s} {'fidelity':9s} {'success':>7s} {'return':>9s}  merit")
    for env_id, scenario, names in CASES:
        for name in names:
            for fidelity in ("kinematic", "dynamic"):
                env = gym.make(env_id, scenario=scenario, fidelity=fidelity)
                policy = get_policy(env_id, name).factory(env, 0)
                ep = run_episode(env, policy, seed=0)
                env.close()
                print(f"{env_id.split('/')[1] + ' ' + scenario:44s} {name:18s} {fidelity:9s} {str(ep.success):>7s} "
                      f"{ep.episode_return:9.2f}  {merit(env_id, ep.infos)}")


if __name__ == "__main__":
    main()
