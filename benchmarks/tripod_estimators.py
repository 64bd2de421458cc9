"""Which estimator holds both the place and the shape of the mobile tripod under physics.

The tripod's dynamic episodes judge an estimate twice: success asks for its units' place (mean error under 5 cm at
the end), the KF check for its shape, through the tilt of the plate fitted to it (inter-unit distances a few
centimetres off tilt it by a fraction of a degree, which accelerometers on the real plate read). The script plays
``--episodes`` dynamic episodes (reset seeds from ``--first-seed``, 300001, at the leaderboard's settings) of each
env with each estimator and prints success, KF PASS and both, each with Wilson's 95 % interval, the tilt (deg RMS,
median and range) and, per episode, the largest over the drive of the estimate's inter-unit distance error against
the true units' (cm, median and range) and the samples on which one is more than 5 cm off. On ids that act through
v1's trust: ``paper``, the paper's single-fault test (the reference); ``paper+worst-unit``, the same test and, where
it singles out no unit while a distance disagrees with the encoders by more than its threshold, full trust in the
unit whose two distances disagree most (not in the paper); ``paper+trust-<b>``, that fallback trusting every unit by
``b`` instead. On v0, whose action is any correction: the paper's correction and the unscented Kalman filter that
fuses odometry and encoders. Each plays at the env's trust rates ``--trust-rate`` gives (default: the env's own and
1, at which a unit moves all the way in one sample), since the estimate follows the encoders no faster. None of the
fallbacks is on the leaderboard; the table measures why the paper's method misses the KF check.

    python benchmarks/tripod_estimators.py [--env ID ...] [--episodes 12] [--trust-rate 1]
                                        [--first-seed 300001] [--workers 2] [--record]
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from results_file import add_record_option, engine_versions, paragraph, record

from paragym import registry
from paragym.baselines.stats import wilson
from paragym.tasks.tripod_step import TripodParams

#: the first reset seed (the leaderboard's dynamic episodes use 200001 onwards)
FIRST_SEED = 300_001
#: the ids measured by default: the newest id, a rung of its newest ladder, and v0 (whose action takes a UKF)
DEFAULT_IDS = ("paragym/MobileTripodOdometry-v3", "paragym/MobileTripodOdometry-Medium-v1",
               "paragym/MobileTripodOdometry-v0")
#: the estimators of ids that act through v1's trust, and of v0
TRUST_ESTIMATORS = ("paper", "paper+worst-unit", "paper+trust-0.3", "paper+trust-1")
#: the estimators measured by default on ids that act through v1's trust
DEFAULT_TRUST = ("paper", "paper+worst-unit", "paper+trust-1")
#: the env's trust rates measured by default (None: the env's own)
DEFAULT_RATES = (None, 1.0)
#: a distance error (m) that tilts the fitted plate by more than the KF check passes
FAR = 0.05
V0_ESTIMATORS = ("encoder-correction", "ukf-fusion")


def trust_policy(name: str):
    """A policy for the ids of v1's action: the paper's single-fault test (the reference's
    :class:`~paragym.planners.encoder_correction.EncoderTrustPolicy`) with the fallback ``name`` names."""
    from paragym.mechanisms import tripod as mt
    from paragym.planners.encoder_correction import EncoderTrustPolicy

    class Fallback(EncoderTrustPolicy):
        def act(self, obs: np.ndarray, info: dict) -> np.ndarray:
            action = super().act(obs, info)
            if name == "paper" or action.any():
                return action
            estimate, target = np.asarray(info["estimate"]), np.asarray(info["encoder_distances"])
            diff = np.abs(mt.distances(estimate[None])[0] - target)
            if diff.max() <= self.threshold:
                return action
            if name == "paper+worst-unit":  # unit k's distances are l_(k+1) and l_(k+2)
                action[int(np.argmax([diff[(k + 1) % 3] + diff[(k + 2) % 3] for k in range(3)]))] = 1.0
            else:  # paper+trust-<b>
                action[:] = float(name.rsplit("-", 1)[1])
            return action

    return Fallback()


def episode(env_id: str, estimator: str, trust_rate: float | None, seed: int
            ) -> tuple[bool, bool, float, float, int]:
    """One dynamic episode (``trust_rate``: the env's, None for its default): success, KF PASS, tilt (deg RMS),
    the largest distance error (cm) and the samples on which a distance is more than :data:`FAR` off."""
    from paragym.baselines.leaderboard.evaluate import run_dynamic
    from paragym.baselines.policies import PolicySpec, get_policy
    from paragym.baselines.tasks import dynamic_kwargs
    from paragym.mechanisms import tripod as mt

    if estimator in V0_ESTIMATORS:
        spec = get_policy(env_id, estimator)
    else:
        spec = PolicySpec(env_id, estimator, lambda env, s: trust_policy(estimator))
    rate_kwargs = {} if trust_rate is None else {"trust_rate": trust_rate}
    val, _ = run_dynamic(spec, "random", seed, {**dynamic_kwargs(env_id), **rate_kwargs})
    infos = val.episode.infos
    estimate = np.array([i["estimate"] for i in infos])
    true = np.array([i["true_units"] for i in infos])
    distance = np.abs(mt.distances(estimate) - mt.distances(true)).max(axis=1)
    return (bool(val.success), bool(val.passed), float(val.tilt_error), float(100 * distance.max()),
            int((distance > FAR).sum()))


def rate(k: int, n: int) -> str:
    low, high = wilson(k, n)
    return f"{k}/{n} [{low:.2f}, {high:.2f}]"


def spread(values: list[float], digits: int = 2) -> str:
    return f"{np.median(values):.{digits}f} ({min(values):.{digits}f}-{max(values):.{digits}f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", action="append", default=None, help="a tripod id (repeatable; default: "
                        + ", ".join(DEFAULT_IDS) + ")")
    parser.add_argument("--estimator", action="append", default=None,
                        help="an estimator's name (repeatable; default: all that the id's action takes)")
    parser.add_argument("--episodes", type=int, default=12, help="dynamic episodes per env and estimator")
    parser.add_argument("--trust-rate", action="append", type=float, default=None,
                        help="the env's trust_rate on ids that act through trust (repeatable; default: the env's own "
                        "and 1)")
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED, help="the first episode's reset seed")
    parser.add_argument("--workers", type=int, default=2, help="processes playing episodes")
    add_record_option(parser)
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be at least 1, got {args.episodes}")
    if args.workers < 1:
        parser.error(f"--workers must be at least 1, got {args.workers}")
    jobs = []
    for env_id in args.env or DEFAULT_IDS:
        env_id = registry.check_env_id(env_id)
        if registry.task_of(env_id) != registry.task_of(DEFAULT_IDS[0]):
            parser.error(f"--env {env_id} is not a mobile tripod id")
        v0 = registry.row(env_id).name == "MobileTripodOdometry-v0"
        names, default = (V0_ESTIMATORS, V0_ESTIMATORS) if v0 else (TRUST_ESTIMATORS, DEFAULT_TRUST)
        for name in args.estimator or default:
            if name not in names:
                parser.error(f"--estimator {name!r} does not act in {env_id}: one of {', '.join(names)}")
            jobs += [(env_id, name, r) for r in ((None,) if v0 else args.trust_rate or DEFAULT_RATES)]
    seeds = [args.first_seed + i for i in range(args.episodes)]
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {job: [pool.submit(episode, *job, s) for s in seeds] for job in jobs}
        rows = []
        for (env_id, name, trust_rate), fs in futures.items():
            out = [f.result() for f in fs]
            won, passed = sum(o[0] for o in out), sum(o[1] for o in out)
            both = sum(o[0] and o[1] for o in out)
            n = len(out)
            shown = "-" if registry.row(env_id).name == "MobileTripodOdometry-v0" else (
                f"{TripodParams.trust_rate:g} (the env's)" if trust_rate is None else f"{trust_rate:g}")
            rows.append([env_id, name, shown, rate(won, n), rate(passed, n), rate(both, n),
                         spread([o[2] for o in out]), spread([o[3] for o in out]), spread([o[4] for o in out], 0)])
            print(" | ".join(rows[-1]), flush=True)
    if args.record:
        record("tripod_estimators", "Which estimator holds both place and shape on the tripod", paragraph(__doc__, 1),
               ["env", "estimator", "trust rate", "success", "KF PASS", "both", "tilt (deg RMS)",
                "largest distance error (cm)", f"samples over {100 * FAR:g} cm off"],
               rows, order=61, folder=args.record, source=engine_versions())


if __name__ == "__main__":
    main()
