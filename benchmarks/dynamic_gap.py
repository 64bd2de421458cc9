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

    python benchmarks/dynamic_gap.py [--plot report/dynamic_gap.png]

``--plot`` also draws, per env, the reference's episode in both fidelities:
the CaPaMan's first crank, the hybrid's E off its nominal path, the 2PRR's
tracking error, the tripod's odometry error, against time.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

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


#: per env: what the picture draws of an episode's infos, and its label
TRACES = {
    "CaPaMan": (lambda i: np.degrees(i["alpha"][0]), "crank 1 [deg]"),
    "Hybrid": (lambda i: np.linalg.norm(i["offset"]) * 1000, "E off the nominal path [mm]"),
    "Orthoglide": (lambda i: i["tracking_error"] * 1000, "tool tracking error [mm]"),
    "Tripod": (lambda i: np.linalg.norm(i["odometry"][:, :2] - i["true_units"][:, :2], axis=1).max() * 100,
               "odometry's largest unit error [cm]"),
}


def plot(traces: dict[str, dict[str, list[float]]], path: Path) -> Path:
    """One panel per env: the reference's trace in each fidelity against the step."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(traces), figsize=(4.2 * len(traces), 3.4))
    for ax, (title, by_fidelity) in zip(axes, traces.items(), strict=True):
        for fidelity, values in by_fidelity.items():
            ax.plot(values, label=fidelity, lw=1.4 if fidelity == "kinematic" else 1.0,
                    ls="-" if fidelity == "kinematic" else "--")
        key = next(k for k in TRACES if k in title)
        ax.set(title=title, xlabel="step", ylabel=TRACES[key][1])
        ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plot", type=Path, default=None, help="also draw the references' traces to this PNG")
    args = parser.parse_args()
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    traces: dict[str, dict[str, list[float]]] = {}
    print(f"{'environment, scenario':44s} {'policy':18s} {'fidelity':9s} {'success':>7s} {'return':>9s}  merit")
    for env_id, scenario, names in CASES:
        for name in names:
            for fidelity in ("kinematic", "dynamic"):
                env = gym.make(env_id, scenario=scenario, fidelity=fidelity)
                policy = get_policy(env_id, name).factory(env, 0)
                ep = run_episode(env, policy, seed=0)
                env.close()
                key = next(k for k in TRACES if k in env_id)
                if name == names[0] and (key != "Tripod" or scenario == "push"):
                    title = f"{env_id.split('/')[1]} {scenario}: {name}"
                    traces.setdefault(title, {})[fidelity] = [float(TRACES[key][0](i)) for i in ep.infos[1:]]
                print(f"{env_id.split('/')[1] + ' ' + scenario:44s} {name:18s} {fidelity:9s} {str(ep.success):>7s} "
                      f"{ep.episode_return:9.2f}  {merit(env_id, ep.infos)}")
    if args.plot is not None:
        print(f"wrote {plot(traces, args.plot)}")


if __name__ == "__main__":
    main()
