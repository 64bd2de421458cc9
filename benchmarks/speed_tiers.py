"""Speed in three tiers, as Isaac Lab and EnvPool report it, each beside the anchor measured in the same run.

For the newest version of every task (or ``--env ID``, repeatable):

* **env alone**: steps/s of the single env (``gym.make``, random actions drawn
  before the clock, resets included; ``env_speed.py``) and robot-steps/s of
  the native vector env at ``--robots`` N with autoresets (``native_speed.py``);
* **with policy inference**: env steps/s while Stable-Baselines3's PPO
  collects its rollouts on the native env with 64 robots (``--ppo-robots``; the policy's
  forward pass on every batch of observations, the rollout buffer);
* **during training**: env steps/s of PPO's ``model.learn`` end to end, the
  same run (``learner_speed.py``: the env's ``ppo.yml`` settings);

and PandaReach-v3's steps/s (panda-gym) as the anchor, measured before each
env's row, with every figure's ratio to it. The time to solve each task is
``time_to_solve.py``'s.

    python benchmarks/speed_tiers.py [--env ID ...] [--seconds 4] [--robots 1024] [--timesteps 32768]
"""

from __future__ import annotations

import argparse
import warnings

import gymnasium as gym
from env_speed import steps_per_second  # this folder is on the path when the script runs
from learner_speed import learner
from learner_speed import steps_per_second as learning_rate
from native_speed import anchor_steps_per_second, robot_steps_per_second
from results_file import add_record_option, record

from paragym.registry import check_env_id, newest

#: the speed page's paragraph above this script's table (``--record``)
PARAGRAPH = (
    "For the newest version of every task, the three figures Isaac Lab and EnvPool report, each with its "
    "ratio to PandaReach-v3 measured before the row: the single env and the native vector env at N = 1024 "
    "with its autoresets; Stable-Baselines3's PPO collecting its rollouts on the native env with 64 "
    "robots (the policy's forward pass on every batch); and PPO's model.learn end to end with the env's "
    "ppo.yml settings (steps/s, in brackets the ratio to PandaReach-v3). "
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", help="only this env id (repeatable; the 'paragym/' may be omitted)")
    parser.add_argument("--seconds", type=float, default=4.0, help="duration of each env measurement")
    parser.add_argument("--robots", type=int, default=1024, help="N of the native env alone (default %(default)s)")
    parser.add_argument("--timesteps", type=int, default=32_768, help="PPO's timed steps (default %(default)s)")
    parser.add_argument("--ppo-robots", type=int, default=64, help="PPO's robots (default %(default)s)")
    add_record_option(parser)
    args = parser.parse_args()
    ids = [check_env_id(e) for e in args.env] if args.env else list(newest())
    ppo = learner("sb3", 2)
    rows = []
    for env_id in ids:
        anchor = anchor_steps_per_second(args.seconds)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            env = gym.make(env_id)
            single = steps_per_second(env, args.seconds)
            env.close()
        native = robot_steps_per_second(env_id, args.robots, args.seconds)
        training, _, collecting = learning_rate(ppo, env_id, args.ppo_robots, args.timesteps)
        rows.append((env_id, anchor, single, native, collecting, training))
        print(f"{env_id}: anchor {anchor or 0:,.0f}, single {single:,.0f}, native {native:,.0f}, "
              f"with inference {collecting:,.0f}, training {training:,.0f}", flush=True)

    def cell(rate: float, anchor: float | None) -> str:
        return f"{rate:,.0f}" + (f" ({rate / anchor:,.0f}x)" if anchor else "")

    print(f"\n| environment | single env | native, N = {args.robots} | with policy inference (PPO, N = "
          f"{args.ppo_robots}) | during training (PPO, N = {args.ppo_robots}) | anchor (PandaReach-v3) |")
    print("|---|---|---|---|---|---|")
    table = [[env_id.split("/")[-1], cell(single, anchor), cell(native, anchor), cell(collecting, anchor),
              cell(training, anchor), f"{anchor:,.0f}" if anchor else "-"]
             for env_id, anchor, single, native, collecting, training in rows]
    for r in table:
        print("| " + " | ".join(r) + " |")
    if args.record:
        record("speed_tiers", "Three tiers: the env alone, with policy inference, during training",
               PARAGRAPH,
               ["environment", "single env", f"native, N = {args.robots}",
                f"with policy inference (PPO, N = {args.ppo_robots})", f"during training (PPO, N = {args.ppo_robots})",
                "anchor (PandaReach-v3)"], table, order=20, folder=args.record)


if __name__ == "__main__":
    main()
