"""What an episode's numbers depend on besides its seeds: each CPU-dependent library, measured alone.

Re-runs episodes of a results file on this machine made to compute as
another CPU would (:data:`paragym.machine.SIMULATED`: each library's
variable in a new process, so that it takes another CPU's code when it
loads), one library at a time and all together, and compares every figure
with the file's (:func:`paragym.baselines.leaderboard.results.compare`). The
episodes: ``--per-policy`` of every producer in the file (every policy of
every env id) and ``--dynamic`` dynamic-fidelity ones, drawn with ``--seed``,
and the episode first reported to differ between CPUs. Also times the two parts made
CPU-independent against what they replaced, measured in the same run: the
learned actor's kernel against numpy's BLAS products, and the hybrid's
Jacobi eigenvalues against LAPACK's ``eigvalsh``.

Prints the tables and writes them, with the date and this machine, to
``--report`` (default ``docs/reports/cpu.md``); the tolerance of
``paragym verify`` (:data:`paragym.baselines.leaderboard.results.TOLERANCE`)
must stay above the largest deviation it finds.

    python benchmarks/cpu_dependence.py [--per-policy 2] [--dynamic 6] [--report docs/reports/cpu.md]
"""

from __future__ import annotations

import argparse
import json
import random
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from paragym import machine
from paragym.baselines.leaderboard.results import TOLERANCE, compare, read_results, tolerance_of

ROOT = Path(__file__).resolve().parents[1]
#: the episode the issue was reported on (env, policy, evaluation seed, episode)
REPORTED = ("paragym/CaPaManCollisionFree-v1", "dagger-seed2", 0, 0)
SOURCES = ["blas-sandybridge", "avx512-blas", "numba-generic", "numpy-baseline-simd", "libm-without-fma",
           "older-blas-generic-numba", "older-x86-64"]


def pick(data: dict, per_policy: int, dynamic: int, seed: int) -> list[tuple[str, int]]:
    """The (kind, index) of the episodes to re-run: ``per_policy`` of each producer, the reported one, and
    ``dynamic`` dynamic-fidelity episodes."""
    rng = random.Random(seed)
    by: dict[int, list[int]] = {}
    for i, e in enumerate(data["episodes"]):
        by.setdefault(e["policy"], []).append(i)
    out = [("episode", i) for _, idx in sorted(by.items()) for i in rng.sample(idx, min(per_policy, len(idx)))]
    for i, e in enumerate(data["episodes"]):
        who = data["policies"][e["policy"]]
        if (who["env"], who["policy"], e["seed"], e["episode"]) == REPORTED and ("episode", i) not in out:
            out.append(("episode", i))
    out += [("dynamic", i) for i in rng.sample(range(len(data["dynamic"])), min(dynamic, len(data["dynamic"])))]
    return out


def worker(path: str, picks: list[tuple[str, int]]) -> list[dict]:
    """Re-run ``picks`` of the results file here; their figures as the file holds them."""
    from paragym.baselines.leaderboard.evaluate import evaluate_dynamic, evaluate_episode
    from paragym.baselines.policies import policies_for

    data = read_results(path)
    specs: dict[str, dict] = {}
    out = []
    for kind, i in picks:
        entry = data[("episodes" if kind == "episode" else "dynamic")][i]
        who = data["policies"][entry["policy"]]
        spec = specs.setdefault(who["env"], policies_for(who["env"]))[who["policy"]]
        if kind == "episode":
            row = evaluate_episode(spec, entry["seed"], entry["episode"])
            out.append({"return": row.episode_return, "length": row.length, "success": row.success,
                        "metrics": row.metrics})
        else:
            d = evaluate_dynamic(spec, entry["scenario"], entry["seed"])
            out.append({"return": d.episode_return, "success": d.success, "metrics": d.metrics})
    return out


def run_as(cpu: str, path: str, picks: list[tuple[str, int]]) -> list[dict]:
    done = subprocess.run([sys.executable, __file__, "--worker", path, json.dumps(picks)], capture_output=True,
                          text=True, env=machine.simulated_environment(cpu))
    if done.returncode != 0:
        raise RuntimeError(f"the worker as {cpu} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def speed() -> list[tuple[str, float, float]]:
    """(what, us with the CPU-independent code, us with the BLAS/LAPACK code it replaced), same run."""
    import gymnasium as gym

    from paragym.baselines.policies import policies_for
    from paragym.mechanisms import hybrid
    from paragym.mechanisms.geometry import k_jacobi

    rows = []
    for env_id, name in (("paragym/CaPaManCollisionFree-v1", "ppo-seed0"), ("paragym/Orthoglide2PRRKappa-v0",
                                                                              "sac-seed0")):
        env = gym.make(env_id)
        actor = policies_for(env_id)[name].factory(env, 0).actor
        env.close()
        obs = np.random.default_rng(0).normal(size=(2000, actor.layers[0][0].shape[1])).astype(np.float32)

        def blas(o, a=actor):
            x = o
            for w, b, f in a.layers:
                x = w @ x + b
                x = np.tanh(x) if f == "Tanh" else np.maximum(x, np.float32(0)) if f == "ReLU" else x
            if a.squash:
                x = a.low + 0.5 * (np.tanh(x) + 1.0) * (a.high - a.low)
            return np.clip(x, a.low, a.high).astype(np.float32)

        times = []
        for f in (actor.act, blas):
            f(obs[0])
            t0 = time.perf_counter()
            for o in obs:
                f(o)
            times.append((time.perf_counter() - t0) / len(obs) * 1e6)
        rows.append((f"{name} actor on {env_id.split('/')[1]}, one action", *times))
    rng = np.random.default_rng(0)
    grams = [m.T @ m for m in rng.normal(size=(5000, 6, 6))]
    times = []
    no_vectors = np.empty((0, 0))

    def jacobi(g: np.ndarray) -> float:
        a = g.copy()
        k_jacobi(a, no_vectors)
        return float(a.diagonal().min())

    for f in (jacobi, lambda g: np.linalg.eigvalsh(g)[0]):
        f(grams[0])
        t0 = time.perf_counter()
        for g in grams:
            f(g)
        times.append((time.perf_counter() - t0) / len(grams) * 1e6)
    rows.append(("hybrid: smallest eigenvalue of a 6x6 M^T M (Jacobi / eigvalsh)", *times))
    p = rng.normal(0, [0.03, 0.03, 0.03, 0.15, 0.15, 0.15], (4096, 6))
    d = rng.uniform(0, 1, 4096)
    hybrid.solve_rows(p[:2], d[:2])
    t0 = time.perf_counter()
    for _ in range(5):
        hybrid.solve_rows(p, d)
    rows.append(("hybrid: solve_rows of 4096 poses, per pose (Jacobi, no anchor)",
                 (time.perf_counter() - t0) / 5 / 4096 * 1e6, float("nan")))
    return rows


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        print(json.dumps(worker(sys.argv[2], [tuple(p) for p in json.loads(sys.argv[3])])))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--results", default=str(ROOT / "leaderboard" / "results.json.gz"))
    ap.add_argument("--per-policy", type=int, default=1)
    ap.add_argument("--dynamic", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cpu", action="append", choices=SOURCES, help="only these simulated CPUs (repeatable)")
    ap.add_argument("--report", default=str(ROOT / "docs" / "reports" / "cpu.md"))
    args = ap.parse_args()
    data = read_results(args.results)
    picks = pick(data, args.per_policy, args.dynamic, args.seed)
    entries = [data["episodes" if k == "episode" else "dynamic"][i] for k, i in picks]
    label = []
    for (kind, _), e in zip(picks, entries, strict=True):
        who = data["policies"][e["policy"]]
        label.append((kind, who["env"], who["policy"], who["kind"], e))
    print(f"{len(picks)} episodes ({sum(k == 'dynamic' for k, _ in picks)} dynamic) of {args.results}")
    host = run_as("host", args.results, picks)
    table, reported = [], []
    for cpu in ["host", *(args.cpu or SOURCES)]:
        t0 = time.perf_counter()
        got = host if cpu == "host" else run_as(cpu, args.results, picks)
        versus_file = [compare(e, g, (), 0.0, 0.0) for e, g in zip(entries, got, strict=True)]
        versus_host = [compare(h, g, (), 0.0, 0.0) for h, g in zip(host, got, strict=True)]
        moved = [(c, lab) for c, lab in zip(versus_host, label, strict=True) if c.verdict != "identical"]
        discrete = [lab for c, lab in moved if c.deviation == float("inf")]
        worst = {k: max((c.deviation for c, lab in moved if lab[0] == k), default=0.0) for k in ("episode", "dynamic")}
        which = sorted({f"{lab[3]}" + ("" if lab[0] == "episode" else " (dynamic)") for c, lab in moved})
        per_task: dict[str, float] = {}
        for c, lab in moved:
            if lab[0] == "dynamic":
                task = lab[1].split("/")[1].split("-")[0]
                per_task[task] = max(per_task.get(task, 0.0), c.deviation)
        dyn = ", ".join(f"{t} {v:.1e}" for t, v in sorted(per_task.items())) or "-"
        table.append((cpu, sum(c.verdict == "identical" for c in versus_file), len(picks), len(moved), worst["episode"],
                      worst["dynamic"], len(discrete), ", ".join(which) or "-", dyn))
        i = next(j for j, lab in enumerate(label) if lab[0] == "episode" and (lab[1], lab[2], lab[4]["seed"],
                                                                             lab[4]["episode"]) == REPORTED)
        reported.append((cpu, got[i]["return"], versus_file[i].deviation))
        print(f"{cpu:24s} as the file {table[-1][1]}/{len(picks)}; moved from this machine's {len(moved)}, "
              f"largest {worst['episode']:.1e} kinematic, {worst['dynamic']:.1e} dynamic, {len(discrete)} discrete "
              f"({time.perf_counter() - t0:.0f} s)")
    timing = speed()
    for what, new, old in timing:
        print(f"{what}: {new:.2f} us" + (f" against {old:.2f} us ({new / old:.2f}x)" if old == old else ""))
    write_report(Path(args.report), args, table, reported, timing)
    print(f"wrote {args.report}")
    return 0


def write_report(path: Path, args: argparse.Namespace, table: list, reported: list, timing: list) -> None:
    facts = machine.describe()
    blas = ", ".join(f"{b['internal_api']} {b['version']} ({b['architecture']})" for b in facts["blas"])
    lines = [
        "# What results depend on: the CPU, measured",
        "",
        f"Generated by `python benchmarks/cpu_dependence.py --per-policy {args.per_policy} --dynamic {args.dynamic} "
        f"--seed {args.seed}` on {time.strftime('%Y-%m-%d')}, on {facts['cpu']['model']} "
        f"({len(facts['cpu']['isa']['found'])} SIMD extensions found by numpy, highest "
        f"{facts['cpu']['isa']['found'][-1] if facts['cpu']['isa']['found'] else '-'}; {blas}; numba for "
        f"{facts['numba']['cpu_name']}; {facts['libc']}). Do not edit by hand.",
        "",
        "Each row re-runs the same episodes of the committed results file in a new process made to compute as "
        "another CPU would (`paragym.machine.SIMULATED`), and compares each figure with this machine's run "
        "(moved) and with the file's. *Largest* is the largest relative change of a return or metric; "
        "*discrete* counts episodes whose success, length or a count changed.",
        "",
        "| simulated CPU | as the file | moved | largest, kinematic | largest, dynamic | discrete | which "
        "policies moved | largest dynamic, per task |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for cpu, same, n, moved, wk, wd, disc, which, who in table:
        lines.append(f"| `{cpu}` | {same}/{n} | {moved} | {wk:.1e} | {wd:.1e} | {disc} | {which} | {who} |")
    lines += ["", "The simulated CPUs: " + "; ".join(f"`{k}`: " + (", ".join(f"{a}={b}" for a, b in v.items())
                                                                  if v else "this machine as it is")
                                                   for k, v in machine.SIMULATED.items()) + ".", "",
              f"The episode first reported to differ between CPUs, {REPORTED[0].split('/')[1]} {REPORTED[1]} "
              f"seed {REPORTED[2]} episode {REPORTED[3]}: its return as each simulated CPU computes it.", "",
              "| simulated CPU | return | against the file |", "|---|---|---|"]
    lines += [f"| `{cpu}` | {ret!r} | {dev:.1e} |" for cpu, ret, dev in reported]
    from paragym import registry

    dyn = {}
    for env in (r.id for r in registry.rows()):
        r = tolerance_of(env, "dynamic")
        dyn.setdefault(f"rtol {r['rtol']:g}, atol {r['atol']:g}", []).append(env.split("/")[1])
    lines += ["", f"The tolerance of `paragym verify`: kinematic (`TOLERANCE`) rtol {TOLERANCE['rtol']:g}, atol "
              f"{TOLERANCE['atol']:g}; dynamic (each task's `Bench.dynamic_tolerance`): "
              + "; ".join(f"{k} ({', '.join(v)})" for k, v in dyn.items()) + ".", "",
        "The cost of the CPU-independent code, against what it replaced, in the same run:", "",
        "| what | CPU-independent [us] | BLAS / LAPACK [us] | ratio |", "|---|---|---|---|"]
    lines += [f"| {w} | {a:.2f} | " + (f"{b:.2f} | {a / b:.2f} |" if b == b else "- | - |") for w, a, b in timing]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
