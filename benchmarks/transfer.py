"""Transfer between fidelities: each learned policy's success where it was trained and where it was not.

For one env id, every learned policy the leaderboard would rank there (the shipped models, and with ``--models DIR``
the runs ``paragym train`` wrote under DIR, those trained under physics among them) plays the same validation
episodes (reset seeds 10000 + k, deterministic actions) in the kinematic fidelity and under each engine's dynamics
at the leaderboard's physics settings (``paragym.baselines.tasks.dynamic_kwargs``). Each row says where the policy
was trained (its run's JSON: the fidelity and engine), the first digits of its model file's SHA-256 (what the
leaderboard keys it by), and its success in each fidelity, k of n with a Wilson 95 % interval: trained without
physics and evaluated under it, and the reverse.

    python benchmarks/transfer.py --env CaPaManCollisionFree-Easy-v0 --models results/time_to_solve/models \\
        --episodes 50 [--policy NAME ...] [--record]
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path
from typing import Any

from results_file import add_record_option, paragraph, record  # this folder is on the path when the script runs

from paragym import check_env_id, registry
from paragym.baselines.policies import policies_for
from paragym.baselines.solve import SolveCheck
from paragym.baselines.stats import wilson
from paragym.baselines.tasks import Target, dynamic_kwargs


def trained_in(spec: Any) -> str:
    """Where a learned policy was trained: "kinematic", or "dynamic (<engine>)", from its run's JSON."""
    path = Path(spec.factory.path).with_suffix(".json")
    meta = json.loads(path.read_text()) if path.is_file() else {}
    return "kinematic" if meta.get("fidelity", "kinematic") == "kinematic" else f"dynamic ({meta.get('engine')})"


def fidelities(env_id: str) -> dict[str, dict[str, Any]]:
    """The env's arguments of each fidelity a policy is evaluated in, by its column's name."""
    out: dict[str, dict[str, Any]] = {"kinematic": {}}
    for engine in registry.row(env_id).engines:
        out[f"dynamic ({engine})"] = dynamic_kwargs(env_id, engine)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", required=True, help="the env id (the 'paragym/' may be omitted)")
    parser.add_argument("--models", type=Path, default=None, help="your runs (paragym train's models folder)")
    parser.add_argument("--policy", action="append", default=None, help="only this learned policy (repeatable)")
    parser.add_argument("--episodes", type=int, default=50, help="validation episodes per fidelity")
    add_record_option(parser)
    args = parser.parse_args()
    env_id = check_env_id(args.env)
    if args.episodes < 1:
        parser.error("--episodes must be positive")
    specs = {name: spec for name, spec in policies_for(env_id, args.models).items() if spec.kind == "learned"}
    if args.policy:
        unknown = sorted(set(args.policy) - set(specs))
        if unknown:
            parser.error(f"no learned policy {', '.join(unknown)} on {env_id}; have {', '.join(specs)}")
        specs = {name: specs[name] for name in args.policy}
    columns = fidelities(env_id)
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        success = (Target("success", +1, 0.0),)  # what each episode's success is, measured as the task's bench does
        checks = {column: SolveCheck(env_id, args.episodes, success, kwargs) for column, kwargs in columns.items()}
        for name, spec in specs.items():
            row = [name, trained_in(spec), str(spec.params["model_sha256"])[:12]]
            for check in checks.values():
                _, figures = check.check(spec.factory(check.env, 0))
                k = round(figures["success"] * args.episodes)
                low, high = wilson(k, args.episodes)
                row.append(f"{k}/{args.episodes} [{low:.2f}, {high:.2f}]")
            rows.append(row)
            print(" | ".join(row), flush=True)
        for check in checks.values():
            check.close()
    if args.record:
        record(f"transfer_{registry.row(env_id).name.replace('-', '_')}",
               f"Transfer between fidelities on {registry.row(env_id).name}", paragraph(__doc__, 1),
               ["policy", "trained in", "model (SHA-256)", *(f"success, {column}" for column in columns)], rows,
               folder=args.record)


if __name__ == "__main__":
    main()
