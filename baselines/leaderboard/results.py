"""Results anyone can check: one self-describing file per run, the raw episodes as CSV, and ``paragym verify``.

The results file (:func:`write_results`, JSON, gzip-compressed when its name
ends in ``.gz``) holds everything a reader needs to trust or re-run a table:

* what wrote it: paragym's version, Python's, the platform, the versions of
  the packages that decide an episode's numbers, and the command;
* the suite: evaluation seeds, episodes, the reset-seed rule and the dynamic
  episodes;
* every env id's registration (entry point, arguments, step limit);
* every policy: name, kind, description and producer (what made its rows:
  a model's SHA-256, a planner's parameters, an outside agent's source hash);
* every episode: its seeds and its return, length, success and the task's
  metrics; every dynamic-fidelity episode with its KF verdict;
* ``sha256``: the digest of all of the above, which tells an intact file
  from an edited or damaged one.

:func:`verify` reads such a file, checks its digest, builds each sampled
episode's policy here, refuses to compare when the policy here is not the
one that made the row (another producer), re-runs the episode and compares:
bit for bit in the kinematic fidelity (the episode is a pure function of its
seeds), to a relative 1e-6 in the dynamic one (PyBullet's solver may round
differently on another CPU).
"""

from __future__ import annotations

import csv
import gzip
import hashlib
import io
import json
import math
import platform
import random
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym

import paragym
from paragym.baselines.leaderboard.suite import EvalSuite, episode_seed
from paragym.baselines.policies import PolicySpec
from paragym.baselines.store import DynamicRow, EpisodeRow, producer_id

__all__ = ["FORMAT", "Verification", "describe", "read_results", "verify", "write_episodes_csv", "write_results"]

FORMAT = "paragym-results/1"
#: the packages whose versions decide an episode's numbers
PACKAGES = ("numpy", "scipy", "numba", "gymnasium", "pybullet", "torch", "stable_baselines3", "sb3_contrib",
            "filterpy")
#: the dynamic fidelity's tolerance across machines (relative, on the return and every metric)
DYNAMIC_RTOL = 1e-6


def _versions() -> dict[str, str]:
    from importlib import metadata

    found = {}
    for name in PACKAGES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            pass
    return found


def _env_spec(env_id: str) -> dict[str, Any]:
    spec = gym.spec(env_id)
    return {"entry_point": str(spec.entry_point), "kwargs": json.loads(json.dumps(spec.kwargs, default=repr)),
            "max_episode_steps": spec.max_episode_steps}


def _digest(body: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(body, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def write_results(path: str | Path, rows: list[EpisodeRow], dynamic: list[DynamicRow],
                  specs: dict[tuple[str, str], PolicySpec], suite: EvalSuite, command: str = "") -> Path:
    """Write the results file of ``rows`` and ``dynamic`` (each row's policy
    in ``specs``) to ``path`` (a new folder is made; ``.gz``: compressed)."""
    keys = sorted({(r.env, r.policy, r.producer) for r in rows} | {(r.env, r.policy, _base(r.producer))
                                                                    for r in dynamic})
    index = {key: i for i, key in enumerate(keys)}
    policies = [{"env": env, "policy": name, "kind": specs[env, name].kind,
                 "description": specs[env, name].description, "producer": producer} for env, name, producer in keys]
    body = {
        "format": FORMAT,
        "written_by": {"paragym": paragym.__version__, "python": platform.python_version(),
                       "platform": f"{platform.system()} {platform.machine()}", "packages": _versions(),
                       "command": command, "date": time.strftime("%Y-%m-%d", time.gmtime())},
        "suite": {"name": suite.name, "seeds": list(suite.seeds), "episodes": suite.episodes,
                  "reset_seed": "100000 + 1000 * seed + episode", "dynamic": [list(d) for d in suite.dynamic]},
        "envs": {env: _env_spec(env) for env in sorted({k[0] for k in keys})},
        "policies": policies,
        "episodes": [{"policy": index[r.env, r.policy, r.producer], "seed": r.seed, "episode": r.episode,
                      "return": r.episode_return, "length": r.length, "success": r.success, "metrics": r.metrics,
                      "wall_seconds": round(r.wall_seconds, 4)} for r in rows],
        "dynamic": [{"policy": index[r.env, r.policy, _base(r.producer)], "scenario": r.scenario, "seed": r.seed,
                     "return": r.episode_return, "success": r.success, "metrics": r.metrics,
                     "kf_passed": r.kf_passed, "kf": r.kf, "physics": json.loads(r.producer).get("dynamics")}
                    for r in dynamic],
    }
    text = json.dumps({**body, "sha256": _digest(body)}, sort_keys=True, separators=(",", ":"))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = text.encode()
    path.write_bytes(gzip.compress(data, mtime=0) if path.suffix == ".gz" else data)
    return path


def _base(dynamic_producer: str) -> str:
    """A dynamic row's producer without its physics settings: the policy's own producer."""
    made = json.loads(dynamic_producer)
    made.pop("dynamics", None)
    return json.dumps(made, sort_keys=True)


def read_results(path: str | Path) -> dict[str, Any]:
    """The results file at ``path``, parsed; a ValueError when it is not one."""
    path = Path(path)
    try:
        raw = path.read_bytes()
        data = json.loads(gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw)
    except (OSError, ValueError, EOFError) as exc:
        raise ValueError(f"{path} is not a paragym results file: {exc}") from exc
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ValueError(f"{path} is not a paragym results file (format {FORMAT!r})")
    return data


def write_episodes_csv(path: str | Path, rows: list[EpisodeRow]) -> Path:
    """Every episode as a line: env, policy, seeds, return (all digits), length, success, the task's metrics
    and the first 16 hex digits of its producer's SHA-256 (the producers in full are in ``leaderboard.csv``'s
    last column and the results file)."""
    metrics = sorted({k for r in rows for k in r.metrics})
    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow(["env", "policy", "kind", "seed", "episode", "reset_seed", "return", "length", "success",
                     *metrics, "wall_seconds", "paragym", "producer_sha256"])
    for r in rows:
        writer.writerow([r.env, r.policy, r.kind, r.seed, r.episode, episode_seed(r.seed, r.episode),
                         repr(r.episode_return), r.length, int(r.success),
                         *(repr(r.metrics[k]) if k in r.metrics else "" for k in metrics), f"{r.wall_seconds:.4f}",
                         r.version, producer_id(r.producer)])
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(buf.getvalue())
    return path


@dataclass
class Verification:
    """What :func:`verify` found."""

    path: Path
    intact: bool
    checked: int = 0
    reproduced: int = 0
    #: one line per episode that did not reproduce, or could not be compared
    problems: list[str] = field(default_factory=list)
    written_by: str = ""

    @property
    def ok(self) -> bool:
        return self.intact and self.checked > 0 and self.reproduced == self.checked and not self.problems


def _same(a: Any, b: Any, rtol: float) -> bool:
    if isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, (int, float)):
        return a == b
    if rtol == 0.0:
        return a == b or (math.isnan(a) and math.isnan(b))
    return math.isclose(a, b, rel_tol=rtol, abs_tol=rtol) or (math.isnan(a) and math.isnan(b))


def _differences(stored: dict[str, Any], again: dict[str, Any], rtol: float) -> list[str]:
    out = [f"{k}: {stored[k]!r} -> {again[k]!r}" for k in ("return", "length", "success")
           if k in stored and not _same(stored[k], again[k], rtol)]
    for k in sorted(set(stored["metrics"]) | set(again["metrics"])):
        if not _same(stored["metrics"].get(k), again["metrics"].get(k), rtol):
            out.append(f"{k}: {stored['metrics'].get(k)!r} -> {again['metrics'].get(k)!r}")
    return out


def verify(path: str | Path, sample: int | None = 20, dynamic: int = 0, seed: int = 0,
           models_dir: str | Path | None = None, echo: Callable[[str], None] = print) -> Verification:
    """Re-run ``sample`` episodes of the results file at ``path`` (None: all
    of them) and ``dynamic`` of its dynamic-fidelity episodes, drawn with
    ``seed``, and compare them with the file's. Policies are found as the
    leaderboard finds them (``models_dir``: your models; register outside
    agents first, or pass ``--agent`` to ``paragym verify``)."""
    from paragym.baselines.leaderboard.evaluate import evaluate_dynamic, evaluate_episode
    from paragym.baselines.leaderboard.suite import dynamic_producer
    from paragym.baselines.policies import policies_for

    data = read_results(path)
    body = {k: v for k, v in data.items() if k != "sha256"}
    result = Verification(Path(path), _digest(body) == data.get("sha256"),
                          written_by=f"paragym {data['written_by'].get('paragym', '?')}")
    if not result.intact:
        result.problems.append("the file's digest does not match its contents: it was edited or damaged after "
                               "paragym wrote it")
    if data["written_by"].get("paragym") != paragym.__version__:
        echo(f"note: written by paragym {data['written_by'].get('paragym')}, this is {paragym.__version__}: "
             f"released env ids behave the same, so the episodes should still reproduce")
    rng = random.Random(seed)
    picks = [("episode", e) for e in (data["episodes"] if sample is None else
                                      rng.sample(data["episodes"], min(sample, len(data["episodes"]))))]
    picks += [("dynamic", d) for d in rng.sample(data["dynamic"], min(dynamic, len(data["dynamic"])))]
    found: dict[str, dict[str, PolicySpec]] = {}
    for kind, entry in picks:
        who = data["policies"][entry["policy"]]
        env, name = who["env"], who["policy"]
        what = (f"{env.split('/')[-1]} {name} seed {entry['seed']} episode {entry['episode']}" if kind == "episode"
                else f"{env.split('/')[-1]} {name} dynamic {entry['scenario']} {entry['seed']}")
        result.checked += 1
        try:
            specs = found.setdefault(env, policies_for(env, models_dir))
        except ValueError as exc:
            result.problems.append(f"{what}: {exc}")
            continue
        spec = specs.get(name)
        if spec is None:
            result.problems.append(f"{what}: no policy {name!r} here (a model folder: --models; an agent: --agent)")
            continue
        if spec.producer() != who["producer"]:
            result.problems.append(f"{what}: the policy here is not the one that made the row (its producer "
                                   f"differs), so its episodes cannot be compared")
            continue
        if kind == "episode":
            row = evaluate_episode(spec, entry["seed"], entry["episode"])
            again = {"return": row.episode_return, "length": row.length, "success": row.success,
                     "metrics": row.metrics}
            diff = _differences(entry, again, 0.0)
        else:
            if json.loads(dynamic_producer(spec)).get("dynamics") != entry["physics"]:
                result.problems.append(f"{what}: this version's physics settings differ from the file's")
                continue
            d = evaluate_dynamic(spec, entry["scenario"], entry["seed"])
            again = {"return": d.episode_return, "success": d.success, "metrics": d.metrics}
            diff = _differences(entry, again, DYNAMIC_RTOL)
        if diff:
            result.problems.append(f"{what}: does not reproduce: {'; '.join(diff[:4])}")
        else:
            result.reproduced += 1
    return result


def describe(result: Verification) -> str:
    """The verdict in a few lines."""
    lines = [f"{result.path}: {result.written_by}; digest {'intact' if result.intact else 'DOES NOT MATCH'}",
             f"{result.reproduced} of {result.checked} episodes reproduced (kinematic: bit for bit; dynamic: to a "
             f"relative {DYNAMIC_RTOL:g})"]
    lines += [f"  {p}" for p in result.problems]
    lines.append("VERIFIED" if result.ok else "NOT VERIFIED")
    return "\n".join(lines)
