"""What the KF check judges: each policy's verdict beside how far its commanded body's attitude and place lie
from the executed body's.

The check reads accelerometers on the moving body and removes gravity at the commanded attitude (paper 000, eq
12), so an execution whose attitude departs from the command by theta leaves g sin(theta) in the readings. For
each policy (default: the bench's reference and the zero action) the script plays ``--episodes`` dynamic episodes
of ``--env`` at the leaderboard's settings (reset seeds 300001, ...) and prints, per policy, the KF verdicts, the
tightest component's error over its tolerance, and the RMS attitude error (deg) and largest distance (cm) between
the commanded and the executed body, each as median and range over the episodes, and the part of the attitude
error gravity shows: the tilt, the angle between the vertical as each body sees it (a heading error has none).

    python benchmarks/kf_attitude.py --env paragym/MobileTripodOdometry-v3 [--policy NAME ...] [--episodes 8]
                                     [--engine mujoco] [--record]
"""

from __future__ import annotations

import argparse

import numpy as np
from results_file import add_record_option, engine_versions, paragraph, record

from paragym import registry
from paragym.baselines.leaderboard.evaluate import run_dynamic
from paragym.baselines.policies import get_policy
from paragym.baselines.tasks import bench_of, dynamic_kwargs

#: the first reset seed (the leaderboard's dynamic episodes use 200001 onwards)
FIRST_SEED = 300_001


def spread(values: list[float], digits: int = 2) -> str:
    """The median and the range of ``values``."""
    return f"{np.median(values):.{digits}f} ({min(values):.{digits}f}-{max(values):.{digits}f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", required=True, help="an env id with a dynamic fidelity")
    parser.add_argument("--policy", action="append", default=None,
                        help="a policy name (repeatable; default: the bench's reference and zero)")
    parser.add_argument("--episodes", type=int, default=8, help="dynamic episodes per policy")
    parser.add_argument("--engine", default="pybullet", choices=("pybullet", "mujoco"))
    add_record_option(parser)
    args = parser.parse_args()
    env_id = registry.check_env_id(args.env)
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    names = args.policy or [bench_of(env_id).reference, "zero"]
    rows = []
    for name in names:
        spec = get_policy(env_id, name)
        passed, ratio, attitude, tilt, place = 0, [], [], [], []
        for i in range(args.episodes):
            val, _ = run_dynamic(spec, "random", FIRST_SEED + i, dynamic_kwargs(env_id, args.engine))
            worst = max(val.report.components, key=lambda c: c.error_judged / c.tolerance) if val.report else None
            passed += val.passed
            ratio.append(np.inf if worst is None else worst.error_judged / worst.tolerance)
            attitude.append(val.attitude_error)
            tilt.append(val.tilt_error)
            place.append(100 * val.position_error)
            print(f"  {name} seed {FIRST_SEED + i}: KF {'PASS' if val.passed else 'FAIL'} "
                  f"({worst.name if worst else 'not judged'} at {ratio[-1]:.2f} of its tolerance), attitude "
                  f"{attitude[-1]:.2f} deg RMS (tilt {tilt[-1]:.2f}), place {place[-1]:.1f} cm", flush=True)
        rows.append([env_id, args.engine, name, f"{passed}/{args.episodes}", spread(ratio), spread(attitude),
                     spread(tilt), spread(place, 1)])
        print(" | ".join(rows[-1]), flush=True)
    if args.record:
        record(f"kf_attitude_{registry.row(env_id).name}", f"What the KF check judges on {env_id}",
               paragraph(__doc__), ["env", "engine", "policy", "KF PASS", "error / tolerance", "attitude (deg RMS)",
                                    "tilt (deg RMS)", "place (cm, largest)"], rows, order=61, folder=args.record,
               source=engine_versions())


if __name__ == "__main__":
    main()
