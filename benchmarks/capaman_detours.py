"""Why RL stalls on the CaPaMan: success split by whether a tour needs a detour.

A CaPaMan tour visits T.P.1 -> T.P.2 -> T.P.3 -> T.P.1 in the joint space.
Where every leg's straight joint-space segment is collision-free (checked
on the env's own occupancy grid, every 0.5 deg), steering each crank
straight at its target completes the tour; elsewhere the robot must detour
around an obstacle, moving away from its target for a while, which the
progress term of the reward pays for negatively. This script plays policies
on ``--episodes`` validation episodes (reset seeds 10000 + k) and prints
each one's success on the two kinds of tours, with Wilson's 95 % interval:

* ``straight``: each crank steered at its target at full speed (no
  knowledge of the obstacles);
* the task's built-in policies named with ``--policy`` (default: the
  reference ``rrt-ga`` and the floor ``zero``);
* each ``--model PATH``, a saved Stable-Baselines3 model (e.g. the PPO runs
  of ``time_to_solve.py``), played deterministically.

A third column says how the progress term paid each policy's way on the
tours that need a detour: the steps whose progress (v1's, the decrease of
the straight joint-space distance to the current target) was negative, of
all its steps there, and their sum (rad).

    python benchmarks/capaman_detours.py --model results/time_to_solve/models/CaPaManCollisionFree-v1/ppo_seed0.zip
"""

from __future__ import annotations

import argparse
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
from results_file import add_record_option, record  # this folder is on the path when it runs

from paragym.baselines.policies import LearnedPolicy, policies_for
from paragym.baselines.stats import wilson
from paragym.baselines.training import EVAL_SEED, load_model
from paragym.mechanisms import capaman
from paragym.rollout import run_episode
from paragym.sim import capaman_clearance
from paragym.tasks.capaman import TOUR
from paragym.tasks.capaman_worlds import _clusters
from paragym.units import DEG

#: the speed page's paragraph above this script's table (``--record``)
PARAGRAPH = (
    "The validation scenarios of CaPaManCollisionFree-v1 sorted by whether every leg's straight joint-"
    "space segment is free on the env's occupancy grid, each policy's success on both kinds of tours (50 "
    "episodes, Wilson 95 % intervals), and on the tours that need a detour how many of its steps went "
    "against the target. "
)


class Straight:
    """Each crank steered straight at the current target T.P. (v1's observation holds target - crank / 45 deg)."""

    def __init__(self, env: gym.Env) -> None:
        u = env.unwrapped
        g = u.geometry
        self.scale = (g.alpha_max - g.alpha_min) / 2 / u.params.max_joint_step

    def reset(self, obs: np.ndarray, info: dict[str, Any]) -> None:
        pass

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return np.clip(obs[3:6] * self.scale, -1.0, 1.0).astype(np.float32)


def needs_detour(scenario: Any, geometry: capaman.CaPaManGeometry, step: float = 0.5 * DEG) -> bool:
    """Whether some leg's straight joint-space segment between consecutive T.P.s collides on the grid."""
    grids = capaman_clearance.DistanceGrids(1)
    grids.set(0, scenario.obstacles)
    tp = scenario.alpha
    order = [0, *TOUR]
    for a, b in zip(order[:-1], order[1:], strict=True):
        n = max(2, int(np.ceil(np.abs(tp[b] - tp[a]).max() / step)) + 1)
        line = tp[a] + np.linspace(0.0, 1.0, n)[:, None] * (tp[b] - tp[a])
        clearance, _ = capaman_clearance.grid_clearance(line, grids, _clusters(geometry), geometry,
                                                        np.zeros(n, np.int64))
        if (clearance <= 0.0).any():
            return True
    return False


def against_the_target(ep: Any, tp: np.ndarray) -> tuple[int, int, float]:
    """The steps of episode ``ep`` whose progress toward the current target T.P. (``tp`` (3, 3) rad; v1's term:
    straight joint-space distance before minus after) was negative, the episode's steps, and that progress's sum."""
    alpha = np.array([info["alpha"] for info in ep.infos])
    target = tp[[info["target_index"] for info in ep.infos[:-1]]]  # each step's target, as it was before the step
    progress = np.linalg.norm(alpha[:-1] - target, axis=1) - np.linalg.norm(alpha[1:] - target, axis=1)
    against = progress < -1e-9
    return int(against.sum()), len(progress), float(progress[against].sum())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="paragym/CaPaManCollisionFree-v1")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--policy", action="append", help="a built-in policy (repeatable; default rrt-ga and zero)")
    parser.add_argument("--model", action="append", default=[], help="a saved SB3 model (repeatable)")
    add_record_option(parser)
    args = parser.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(args.env)
    specs = policies_for(args.env)
    players: dict[str, Any] = {"straight": lambda e, s: Straight(e)}
    for name in args.policy or ["rrt-ga", "zero"]:
        players[name] = specs[name].factory
    for path in args.model:
        model = load_model(path)
        players[path.rsplit("/", 1)[-1]] = lambda e, s, m=model: LearnedPolicy(m)
    seeds = [EVAL_SEED + k for k in range(args.episodes)]
    detour = []
    for s in seeds:
        env.reset(seed=s)
        detour.append(needs_detour(env.unwrapped.state.scenarios[0], env.unwrapped.geometry))
    detour = np.array(detour)
    print(f"{args.env}: {args.episodes} validation episodes, {int(detour.sum())} need a detour, "
          f"{int((~detour).sum())} do not")
    print(f"{'policy':28s} {'straight tours':>24s} {'tours with a detour':>26s} "
          f"{'detours: steps against the target':>36s}")
    table = []
    for name, factory in players.items():
        success, against = [], []
        for s, needs in zip(seeds, detour, strict=True):
            ep = run_episode(env, factory(env, s), seed=s)
            success.append(ep.success)
            if needs:
                against.append(against_the_target(ep, env.unwrapped.state.tp[0]))
        success = np.array(success)
        steps, of, rad = np.sum(against, axis=0) if against else (0, 0, 0.0)
        cells = []
        for kind in (~detour, detour):
            k, n = int(success[kind].sum()), int(kind.sum())
            lo, hi = wilson(k, n) if n else (float("nan"), float("nan"))
            cells.append(f"{k}/{n} [{lo:.2f}, {hi:.2f}]")
        cells.append(f"{int(steps)}/{int(of)} ({rad:.3f} rad)")
        print(f"{name:28s} {cells[0]:>24s} {cells[1]:>26s} {cells[2]:>36s}", flush=True)
        table.append([name, *cells])
    env.close()
    if args.record:
        record("capaman_detours", "Why the CaPaMan is not solved from scratch: tours that need a detour", PARAGRAPH,
               ["policy", f"straight tours ({int((~detour).sum())})", f"tours with a detour ({int(detour.sum())})",
                "detours: steps against the target"], table, order=40, folder=args.record)


if __name__ == "__main__":
    main()
