"""Results anyone can check: one self-describing file per run, the raw episodes as CSV, and ``paragym verify``.

The results file (:func:`write_results`, JSON, gzip-compressed when its name
ends in ``.gz``) holds everything a reader needs to trust or re-run a table:

* what wrote it: paragym's version, Python's, the platform, the versions of
  the packages that decide an episode's numbers, the machine as far as the
  numbers can depend on it (:func:`paragym.machine.describe`: the CPU and its
  instruction sets, the C library, each BLAS with the kernel it picked,
  numba's target) and the command;
* the tolerance a re-run on another machine is held to (:data:`TOLERANCE`, and
  each task's for its dynamic episodes);
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
one that made the row (another producer), re-runs the episode and compares
(:func:`compare`): the discrete outcomes exactly (success, length, and the
task's counts and flags, :meth:`paragym.baselines.tasks.Bench.exact_metrics`),
the return and the continuous metrics within the tolerance (:func:`tolerance_of`). Each episode
is *identical* (every bit), *within tolerance*, or *diverged*.

Why a tolerance at all: what paragym computes itself (its numba kernels, the
learned actors, the hybrid's eigenvalues, the tripod's rigid fit) gives the
same bits whatever the CPU's BLAS kernels or numba's target
(``tests/test_cpu_independence.py``), but glibc's libm computes sin, cos,
exp, atan2, ... with per-CPU variants (and differently between its
versions), and Python, numpy, numba and PyBullet all call it; numpy takes
its own AVX-512 loops for arctan2, arcsin and arccos; filterpy's UKF and a
user's own agent call BLAS. ``benchmarks/cpu_dependence.py``
measures what each source moves (``docs/reports/cpu.md``); the tolerance is
set above the largest deviation it found.
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
from paragym import machine
from paragym.baselines.leaderboard.suite import EvalSuite, episode_seed
from paragym.baselines.policies import PolicySpec
from paragym.baselines.store import DynamicRow, EpisodeRow, producer_id
from paragym.baselines.tasks import bench_of

__all__ = ["FORMAT", "TOLERANCE", "Comparison", "Verification", "compare", "describe", "read_results",
           "rows_of_results", "tolerance_of", "verify", "write_episodes_csv", "write_results"]

FORMAT = "paragym-results/1"
#: the packages whose versions decide an episode's numbers
PACKAGES = ("numpy", "scipy", "numba", "gymnasium", "pybullet", "mujoco", "torch", "stable_baselines3",
            "sb3_contrib", "filterpy")
#: how far a re-run of a kinematic-fidelity episode on another machine may move its return and each continuous
#: metric: ``|a - b| <= atol + rtol * max(|a|, |b|)``. Set above the largest deviation that
#: benchmarks/cpu_dependence.py measured on simulated CPUs (docs/reports/cpu.md); recorded in every results file.
#: The dynamic fidelity's is each task's (:attr:`paragym.baselines.tasks.Bench.dynamic_tolerance`).
TOLERANCE: dict[str, float] = {"rtol": 1e-6, "atol": 1e-9}


def tolerance_of(env_id: str, fidelity: str) -> dict[str, float]:
    """The tolerance of ``env_id``'s episodes in ``fidelity`` ("kinematic" or "dynamic") in this version."""
    from paragym.baselines.tasks import bench_of

    if fidelity == "kinematic":
        return dict(TOLERANCE)
    rtol, atol = bench_of(env_id).dynamic_tolerance
    return {"rtol": rtol, "atol": atol}


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
                       "machine": machine.describe(), "command": command,
                       "date": time.strftime("%Y-%m-%d", time.gmtime())},
        "tolerance": {"kinematic": dict(TOLERANCE),
                      "dynamic": {env: tolerance_of(env, "dynamic") for env in sorted({r.env for r in dynamic})},
                      "exact": ["success", "length", "each task's exact columns, and policy_failed"],
                      "measured_by": "benchmarks/cpu_dependence.py (docs/reports/cpu.md)"},
        "suite": {"name": suite.name, "seeds": list(suite.seeds), "episodes": suite.episodes,
                  "reset_seed": "100000 + 1000 * seed + episode", "dynamic": [list(d) for d in suite.dynamic]},
        "envs": {env: _env_spec(env) for env in sorted({k[0] for k in keys})},
        "policies": policies,
        "episodes": [{"policy": index[r.env, r.policy, r.producer], "seed": r.seed, "episode": r.episode,
                      "return": r.episode_return, "length": r.length, "success": r.success, "metrics": r.metrics,
                      "wall_seconds": round(r.wall_seconds, 4)} for r in rows],
        "dynamic": [{"policy": index[r.env, r.policy, _base(r.producer)], "scenario": r.scenario, "seed": r.seed,
                     "return": r.episode_return, "success": r.success, "metrics": r.metrics,
                     "kf_passed": r.kf_passed, "kf": r.kf, "physics": json.loads(r.producer).get("dynamics"),
                     **_settings_of(r.producer)} for r in dynamic],
    }
    text = json.dumps({**body, "sha256": _digest(body)}, sort_keys=True, separators=(",", ":"))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = text.encode()
    path.write_bytes(gzip.compress(data, mtime=0) if path.suffix == ".gz" else data)
    return path


#: what a dynamic row's producer holds beyond its policy's, each kept in its entry of the results file when the
#: producer has it: the MuJoCo engine's settings (a PyBullet row has none) and the KF recorder
#: (:data:`paragym.validation.episode.RECORDER`; a file written before it was named has none)
_DYNAMIC_KEYS = ("engine", "recorder")


def _base(dynamic_producer: str) -> str:
    """A dynamic row's producer without its physics settings, engine and recorder: the policy's own producer."""
    made = json.loads(dynamic_producer)
    for key in ("dynamics", *_DYNAMIC_KEYS):
        made.pop(key, None)
    return json.dumps(made, sort_keys=True)


def _settings_of(dynamic_producer: str) -> dict[str, str]:
    """A dynamic row's engine settings and recorder as its entry in the results file holds them (:data:
    `_DYNAMIC_KEYS`): ``{"engine": settings}`` in MuJoCo, nothing in PyBullet."""
    made = json.loads(dynamic_producer)
    return {key: made[key] for key in _DYNAMIC_KEYS if key in made}


def read_results(path: str | Path) -> dict[str, Any]:
    """The results file at ``path``, parsed; a ValueError when it is not one."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except IsADirectoryError:
        raise ValueError(f"{path} is a folder, not a paragym results file (results.json.gz)") from None
    except OSError as exc:
        raise ValueError(f"cannot read {path}: {exc.strerror or exc}") from None
    try:
        text = gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw
    except (OSError, EOFError):
        raise ValueError(f"{path} is not a paragym results file: a damaged gzip file") from None
    try:
        data = json.loads(text)
    except (ValueError, UnicodeDecodeError):
        raise ValueError(f"{path} is not a paragym results file: not JSON (paragym leaderboard writes "
                         f"results.json.gz)") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ValueError(f"{path} is not a paragym results file: JSON without \"format\": {FORMAT!r}")
    return data


def rows_of_results(path: str | Path) -> tuple[list[EpisodeRow], list[DynamicRow]]:
    """The episode and dynamic-fidelity rows of the results file at ``path``, as the run that wrote it stored
    them (policy, seeds, producer, paragym version): what ``paragym leaderboard --resume-from`` puts into a
    fresh results database so that only what the file lacks runs again. A ValueError for a file whose digest
    does not match its contents (edited or damaged rows are never taken in). A dynamic row's wall time is not
    in the file (0)."""
    data = read_results(path)
    if _digest({k: v for k, v in data.items() if k != "sha256"}) != data.get("sha256"):
        raise ValueError(f"{path}: the file's digest does not match its contents (edited or damaged after paragym "
                         f"wrote it); its rows are not taken")
    version, who = data["written_by"]["paragym"], data["policies"]
    episodes = [EpisodeRow(who[e["policy"]]["env"], who[e["policy"]]["policy"], e["seed"], e["episode"],
                           who[e["policy"]]["kind"], e["return"], e["length"], e["success"], e["metrics"],
                           e["wall_seconds"], version, who[e["policy"]]["producer"]) for e in data["episodes"]]
    dynamic = [DynamicRow(who[d["policy"]]["env"], who[d["policy"]]["policy"], d["scenario"], d["seed"], d["return"],
                          d["success"], d["metrics"], d["kf_passed"], d["kf"], 0.0, version,
                          json.dumps({**json.loads(who[d["policy"]]["producer"]), "dynamics": d["physics"],
                                      **{key: d[key] for key in _DYNAMIC_KEYS if key in d}},
                                     sort_keys=True)) for d in data["dynamic"]]
    return episodes, dynamic


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
        kind = bench_of(r.env).kind_of(r.env, r.policy, r.kind)
        writer.writerow([r.env, r.policy, kind, r.seed, r.episode, episode_seed(r.seed, r.episode),
                         repr(r.episode_return), r.length, int(r.success),
                         *(repr(r.metrics[k]) if k in r.metrics else "" for k in metrics), f"{r.wall_seconds:.4f}",
                         r.version, producer_id(r.producer)])
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(buf.getvalue())
    return path


@dataclass(frozen=True)
class Comparison:
    """One re-run episode against the file's: ``verdict`` "identical" (every bit), "within tolerance" or
    "diverged"; ``worst``: the figure that moved most and ``deviation`` its relative change (0: none);
    ``differences``: the figures that broke the rule, as "key: stored -> again"."""

    verdict: str
    worst: str = ""
    deviation: float = 0.0
    differences: tuple[str, ...] = ()


def _relative(a: float, b: float) -> float:
    if a == b or (math.isnan(a) and math.isnan(b)):
        return 0.0
    if math.isnan(a) or math.isnan(b) or math.isinf(a) or math.isinf(b):
        return math.inf
    return abs(a - b) / max(abs(a), abs(b))


def compare(stored: dict[str, Any], again: dict[str, Any], exact: tuple[str, ...] | list[str], rtol: float,
            atol: float) -> Comparison:
    """Compare a re-run episode (``again``: its return, success, length if it has one, and its ``metrics``) with
    the file's (``stored``): success, length and the metrics named in ``exact`` must be equal; the return and
    every other metric may differ by ``atol + rtol * max(|a|, |b|)``."""
    figures = [(k, stored[k], again[k]) for k in ("return", "length", "success") if k in stored]
    figures += [(k, stored["metrics"].get(k), again["metrics"].get(k))
                for k in sorted(set(stored["metrics"]) | set(again["metrics"]))]
    identical, worst, deviation, broken = True, "", 0.0, []
    for key, a, b in figures:
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (a, b))
        if a == b or (numbers and math.isnan(a) and math.isnan(b)):
            continue
        identical = False
        if key in ("length", "success") or key in exact or not numbers:
            broken.append(f"{key}: {a!r} -> {b!r}")
            worst, deviation = key, math.inf
            continue
        moved = _relative(float(a), float(b))
        if moved > deviation:
            worst, deviation = key, moved
        if not abs(a - b) <= atol + rtol * max(abs(a), abs(b)):
            broken.append(f"{key}: {a!r} -> {b!r}")
    verdict = "identical" if identical else "diverged" if broken else "within tolerance"
    return Comparison(verdict, worst, deviation, tuple(broken))


@dataclass
class Verification:
    """What :func:`verify` found: per compared episode a line (what, :class:`Comparison`), and the problems
    (an episode that did not reproduce, or could not be compared)."""

    path: Path
    intact: bool
    checked: int = 0
    episodes: list[tuple[str, Comparison]] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    written_by: str = ""
    #: the tolerance each (env, fidelity) was held to (the stricter of the file's and this version's)
    tolerance: dict[tuple[str, str], dict[str, float]] = field(default_factory=dict)
    machines: str = ""

    def count(self, verdict: str) -> int:
        return sum(c.verdict == verdict for _, c in self.episodes)

    @property
    def reproduced(self) -> int:
        """Episodes identical or within tolerance."""
        return self.count("identical") + self.count("within tolerance")

    @property
    def ok(self) -> bool:
        return self.intact and self.checked > 0 and self.reproduced == self.checked and not self.problems


def _rule(data: dict[str, Any], env: str, fidelity: str) -> dict[str, float]:
    """The stricter of the file's recorded tolerance for ``env``'s ``fidelity`` and this version's
    (:func:`tolerance_of`): a file cannot loosen the rule it is checked by."""
    recorded = (data.get("tolerance") or {}).get(fidelity) or {}
    if fidelity == "dynamic" and "rtol" not in recorded:  # per env id
        recorded = recorded.get(env) or {}
    ours = tolerance_of(env, fidelity)
    return {k: min(float(recorded.get(k, v)), v) for k, v in ours.items()}


def _machine_line(facts: dict[str, Any] | None) -> str:
    if not facts:
        return "not recorded"
    blas = ", ".join(f"{b.get('internal_api')} {b.get('architecture')}" for b in facts.get("blas", []))
    return f"{facts['cpu']['model']} ({blas}; numba for {facts['numba']['cpu_name']}; {facts.get('libc', '')})"


def verify(path: str | Path, sample: int | None = 20, dynamic: int = 0, seed: int = 0,
           models_dir: str | Path | None = None, echo: Callable[[str], None] = print) -> Verification:
    """Re-run ``sample`` episodes of the results file at ``path`` (None: all
    of them) and ``dynamic`` of its dynamic-fidelity episodes, drawn with
    ``seed``, and compare them with the file's (:func:`compare`, under the file's tolerance or this
    version's, the stricter). Policies are found as the
    leaderboard finds them (``models_dir``: your models; register outside
    agents first, or pass ``--agent`` to ``paragym verify``)."""
    from paragym.baselines.leaderboard.evaluate import evaluate_dynamic, evaluate_episode
    from paragym.baselines.leaderboard.suite import dynamic_producer
    from paragym.baselines.policies import policies_for
    from paragym.baselines.tasks import bench_of

    data = read_results(path)
    body = {k: v for k, v in data.items() if k != "sha256"}
    result = Verification(Path(path), _digest(body) == data.get("sha256"),
                          written_by=f"paragym {data['written_by'].get('paragym', '?')}",
                          machines=f"written on {_machine_line(data['written_by'].get('machine'))}; "
                                   f"re-run on {_machine_line(machine.describe())}")
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
                else f"{env.split('/')[-1]} {name} dynamic{' in MuJoCo' if 'engine' in entry else ''} "
                     f"{entry['scenario']} {entry['seed']}")
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
            fidelity = "kinematic"
        else:
            engine = "mujoco" if "engine" in entry else "pybullet"
            here = json.loads(dynamic_producer(spec, engine))
            if here.get("dynamics") != entry["physics"] or here.get("engine") != entry.get("engine"):
                result.problems.append(f"{what}: this version's physics settings differ from the file's")
                continue
            if here.get("recorder") != entry.get("recorder"):
                result.problems.append(f"{what}: this version's KF recorder ({here.get('recorder')}) differs from "
                                       f"the file's ({entry.get('recorder', 'unnamed')}): its verdicts cannot be "
                                       f"compared")
                continue
            try:
                d = evaluate_dynamic(spec, entry["scenario"], entry["seed"], engine=engine)
            except ImportError as exc:  # a MuJoCo row where MuJoCo is not installed
                result.problems.append(f"{what}: {exc}")
                continue
            again = {"return": d.episode_return, "success": d.success, "metrics": d.metrics}
            fidelity = "dynamic"
        rule = result.tolerance.setdefault((env, fidelity), _rule(data, env, fidelity))
        found_cmp = compare(entry, again, bench_of(env).exact_metrics(), rule["rtol"], rule["atol"])
        result.episodes.append((what, found_cmp))
        if found_cmp.verdict == "diverged":
            result.problems.append(f"{what}: does not reproduce: {'; '.join(found_cmp.differences[:4])}")
    return result


def describe(result: Verification) -> str:
    """The verdict: each compared episode on a line (identical, within tolerance with its largest deviation,
    or diverged), then the counts, the rule and the verdict."""
    lines = [f"{result.path}: {result.written_by}; digest {'intact' if result.intact else 'DOES NOT MATCH'}",
             result.machines]
    for what, c in result.episodes:
        if c.verdict == "identical":
            lines.append(f"  identical         {what}")
        elif c.verdict == "within tolerance":
            lines.append(f"  within tolerance  {what}: largest deviation {c.deviation:.1e} relative ({c.worst})")
        else:
            lines.append(f"  DIVERGED          {what}: {'; '.join(c.differences[:4])}")
    lines += [f"  {p}" for p in result.problems if "does not reproduce" not in p]
    rules: dict[str, dict[str, list[str]]] = {}
    for (env, fidelity), r in sorted(result.tolerance.items()):
        rules.setdefault(fidelity, {}).setdefault(f"rtol {r['rtol']:g}, atol {r['atol']:g}", []).append(
            env.split("/")[-1])
    rule = "; ".join(f"{fidelity}: " + ", ".join(k if len(by) == 1 else f"{k} ({', '.join(v)})" for k, v in by.items())
                     for fidelity, by in rules.items()) or "none applied"
    worst = max((c for _, c in result.episodes if c.verdict == "within tolerance"), key=lambda c: c.deviation,
                default=None)
    lines.append(f"{result.reproduced} of {result.checked} episodes reproduced: {result.count('identical')} identical, "
                 f"{result.count('within tolerance')} within tolerance"
                 + (f" (largest deviation {worst.deviation:.1e} relative, {worst.worst})" if worst else "")
                 + f", {result.count('diverged')} diverged")
    lines.append(f"the rule: success, length and counts exactly; the return and continuous metrics within {rule}")
    lines.append("VERIFIED" if result.ok else "NOT VERIFIED")
    return "\n".join(lines)
