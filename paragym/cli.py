"""The ``paragym`` command: ``paragym envs``, ``paragym demo ENV_ID``."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym

import paragym
from paragym.baselines import RandomPolicy, ZeroPolicy
from paragym.rollout import Episode, run_episode

__all__ = ["main"]


def _capaman_best(env: gym.Env) -> Any:
    from paragym.planners import GridPathPolicy

    return GridPathPolicy(max_joint_step=env.unwrapped.max_joint_step)


def _capaman_plot(ep: Episode, path: Path) -> Path:
    from paragym.plots import plot_capaman_episode

    return plot_capaman_episode(ep, path)


#: env id -> (best available policy factory, name, picture writer)
DEMOS: dict[str, tuple[Callable[[gym.Env], Any], str, Callable[[Episode, Path], Path]]] = {
    "paragym/CaPaManCollisionFree-v0": (_capaman_best, "grid-path (Dijkstra on Theta)", _capaman_plot),
}


def _cmd_envs(args: argparse.Namespace) -> int:
    for env_id, (_, steps, doc) in paragym.ENVIRONMENTS.items():
        print(f"{env_id:40s} {doc} [max {steps} steps]")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    env_id = args.env_id if args.env_id.startswith("paragym/") else f"paragym/{args.env_id}"
    if env_id not in paragym.ENVIRONMENTS:
        print(f"unknown env id {args.env_id!r}; `paragym envs` lists them", file=sys.stderr)
        return 2
    env = gym.make(env_id, scenario=args.scenario, render_mode="rgb_array")
    best, best_name, plot = DEMOS[env_id]
    policy = {"best": lambda: best(env), "random": lambda: RandomPolicy(env.action_space, args.seed),
              "zero": lambda: ZeroPolicy(env.action_space)}[args.policy]()
    name = best_name if args.policy == "best" else args.policy
    print(f"{env_id}: {args.scenario} scenario, seed {args.seed}, policy {name}")
    ep = run_episode(env, policy, seed=args.seed, frame_every=args.frame_every if args.gif else 0)
    if not ep.frames:  # the picture's first panel
        ep.frames.append(env.render())
    env.close()
    out = Path(args.out)
    stem = env_id.split("/")[1] + f"_{args.scenario}_seed{args.seed}"
    png = plot(ep, out / f"{stem}.png")
    end = ep.infos[-1]
    print(f"steps {len(ep.actions)}  return {ep.episode_return:.3f}  success {end.get('is_success')}  "
          f"collision {end.get('collision')}  reset+plan {ep.reset_seconds:.2f} s  steps {ep.step_seconds:.2f} s")
    print(f"wrote {png}")
    if args.gif:
        from PIL import Image

        gif = out / f"{stem}.gif"
        frames = [Image.fromarray(f) for f in ep.frames]
        frames[0].save(gif, save_all=True, append_images=frames[1:], duration=80, loop=0)
        print(f"wrote {gif} ({len(frames)} frames)")
    return 0 if args.policy != "best" or end.get("is_success") else 1


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``paragym`` command."""
    parser = argparse.ArgumentParser(prog="paragym", description=paragym.__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"paragym {paragym.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("envs", help="list the registered environments")
    p.set_defaults(func=_cmd_envs)
    p = sub.add_parser("demo", help="run one episode with the best available policy and save a picture")
    p.add_argument("env_id", help="e.g. paragym/CaPaManCollisionFree-v0 (the 'paragym/' may be omitted)")
    p.add_argument("--scenario", default="paper", help="'paper' (default) or 'random'")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--policy", choices=("best", "random", "zero"), default="best")
    p.add_argument("--out", default="runs/demo", help="folder for the PNG (and GIF)")
    p.add_argument("--gif", action="store_true", help="also write an animated GIF of the episode")
    p.add_argument("--frame-every", type=int, default=4, help="GIF: keep a frame every N steps")
    p.set_defaults(func=_cmd_demo)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``paragym`` console script."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except ValueError as exc:  # bad input: say it plainly, no traceback
        print(f"paragym: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
