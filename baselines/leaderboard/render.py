"""The leaderboard's reports: the terminal table, LEADERBOARD.md, the CSV and a picture per env."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import paragym
from paragym import registry
from paragym.baselines.leaderboard.suite import FULL, EvalSuite
from paragym.baselines.leaderboard.summary import Summary, noise_floor
from paragym.baselines.store import producer_id
from paragym.baselines.tasks import bench_of
from paragym.baselines.training import env_name

__all__ = ["markdown", "smoke_note", "terminal_table", "write_csv", "write_reports"]


def _verdict(s: Summary) -> str:
    if s.validation is None:
        return ""
    return "PASS" if s.validation["passed"] else "FAIL"


def _columns(env: str, dynamic: bool = False, mujoco: bool = False) -> list[tuple[str, Callable[[Summary], str]]]:
    cols: list[tuple[str, Callable[[Summary], str]]] = [
        ("#", lambda s: str(s.rank)), ("policy", lambda s: s.policy), ("kind", lambda s: s.kind),
        ("success [95% CI]", lambda s: f"{s.success_rate:.2f} {_ci(s.success_ci, '.2f')}"),
        ("return [95% CI]", lambda s: f"{s.return_mean:.2f} {_ci(s.return_ci, '.2f')}"),
        ("apart from #1", _apart)]
    bench = bench_of(env)
    for c in bench.columns:
        cols.append((c.label, lambda s, key=c.key, fmt=c.fmt: format(s.metrics.get(key, math.nan), fmt)))
    cols.append(("s/episode", lambda s: f"{s.wall_seconds:.3f}"))
    if bench.validated_plan is not None:
        cols.append(("KF validation", _verdict))
    if dynamic:
        key = bench.primary[0]
        fmt = bench.fmt(key)
        cols += [("dynamic: success [95% CI]", lambda s: _dyn(s, lambda d: f"{d['success_rate']:.2f} "
                                                                      f"{_ci(d['success_ci'], '.2f')}")),
                 (f"dynamic: {bench.label(key)}", lambda s: _dyn(s, lambda d: format(
                     d["return_mean"] if key == "return" else d["metrics"].get(key, math.nan), fmt))),
                 ("dynamic: KF, own episode", lambda s: _dyn(s, lambda d: "" if d["kf"] is None else (
                     "PASS" if d["kf"]["passed"] else "FAIL")))]
    if mujoco:
        cols += [("MuJoCo: success [95% CI]", lambda s: _dyn(s, lambda d: f"{d['success_rate']:.2f} "
                                                                     f"{_ci(d['success_ci'], '.2f')}", "mujoco")),
                 ("MuJoCo: KF, own episode", lambda s: _dyn(s, lambda d: "" if d["kf"] is None else (
                     "PASS" if d["kf"]["passed"] else "FAIL"), "mujoco"))]
    return cols


def _ci(interval: tuple[float, float], fmt: str) -> str:
    lo, hi = interval
    return "" if not (math.isfinite(lo) and math.isfinite(hi)) else f"[{lo:{fmt}}, {hi:{fmt}}]"


def _apart(s: Summary) -> str:
    """Whether the leader is ahead of this row beyond doubt (:func:`~paragym.baselines.leaderboard.summary.
    mark_separable`)."""
    return "leader" if s.separable is None else ("yes" if s.separable else "no")


def smoke_note(suite: EvalSuite) -> str:
    """The warning a table of fewer episodes than the full suite's carries ('' otherwise)."""
    if not suite.smoke:
        return ""
    return (f"**A smoke test, not a ranking**: {len(suite.keys())} episodes per policy ({suite.name} suite), so the "
            f"intervals are wide and the order inside them is chance. Rank on the full suite's {len(FULL.keys())} "
            f"episodes per policy or more (no --quick, --episodes 10 or more).")


def _dyn(s: Summary, cell: Callable[[dict[str, Any]], str], engine: str = "pybullet") -> str:
    d = s.dynamic if engine == "pybullet" else s.dynamic_mujoco
    return "" if d is None else cell(d)


def _has(summaries: list[Summary]) -> tuple[bool, bool]:
    """Whether any of one env's summaries has dynamic episodes in PyBullet, and in MuJoCo."""
    return any(s.dynamic is not None for s in summaries), any(s.dynamic_mujoco is not None for s in summaries)


def terminal_table(summaries: list[Summary]) -> str:
    """A plain-text table of one env's summaries."""
    cols = _columns(summaries[0].env, *_has(summaries))
    cells = [[label for label, _ in cols]] + [[f(s) for _, f in cols] for s in summaries]
    widths = [max(len(row[i]) for row in cells) for i in range(len(cols))]
    lines = ["  ".join(c.ljust(w) if i in (1, 2) else c.rjust(w)
                       for i, (c, w) in enumerate(zip(row, widths, strict=True))) for row in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def markdown(all_summaries: dict[str, list[Summary]], suite: EvalSuite, images: dict[str, str],
             header: str) -> str:
    """LEADERBOARD.md: one section per env (table, picture, notes)."""
    out = [header, ""]
    for env, summaries in all_summaries.items():
        cols = _columns(env, *_has(summaries))
        out += [f"## `{env}`", "", "| " + " | ".join(label for label, _ in cols) + " |",
                "|" + "|".join("---" for _ in cols) + "|"]
        out += ["| " + " | ".join(f(s).replace("|", "/") for _, f in cols) + " |" for s in summaries]
        key, sign = bench_of(env).primary
        out += ["", f"Ranked by success rate, then {bench_of(env).label(key)} "
                f"({'higher' if sign > 0 else 'lower'} is better). {summaries[0].episodes} episodes per policy. "
                "Intervals: 95 %, Wilson's for success rates, Student's t for mean returns. "
                "*apart from #1*: \"yes\" where the leader's success interval lies above the policy's, or, where "
                "those overlap, the leader's interval of the ranking's next metric lies beyond the policy's; \"no\": "
                "the two cannot be told apart on these episodes.", "", noise_floor(summaries).sentence(), ""]
        dyn = next((s.dynamic for s in summaries if s.dynamic is not None), None)
        if dyn is not None:
            out += [f"Dynamic: {dyn['episodes']} episodes per policy under PyBullet's dynamics "
                    f"({dyn['settings']}), the paper's case first; KF: the accelerometers and the Kalman filter on "
                    "the policy's own paper-case episode, what it executed against what it commanded "
                    "(`paragym validate ENV --policy NAME`). Beside the kinematic columns, the sim-to-sim gap.", ""]
        elif bench_of(env).dynamics is not None and not suite.runs_dynamic_on(env):
            out += [f"Dynamic: the {suite.name} suite runs the dynamic episodes on each task's newest id "
                    f"(`{registry.rows_of(registry.task_of(env))[-1].id}`); the full suite runs them here too.", ""]
        mj = next((s.dynamic_mujoco for s in summaries if s.dynamic_mujoco is not None), None)
        if mj is not None:
            out += [f"MuJoCo: the same {mj['episodes']} episodes per policy under MuJoCo's dynamics "
                    f"(`engine=\"mujoco\"`; {mj['settings']}), judged alike "
                    "(`paragym validate ENV --policy NAME --engine mujoco`); the engines compared: "
                    "docs/conformance.md.", ""]
        for s in summaries:
            if s.validation is not None:
                v = s.validation
                out.append(f"KF validation of `{s.policy}` (paper scenario, dynamic fidelity): "
                           f"**{'PASS' if v['passed'] else 'FAIL'}** — {v.get('text', '')}")
                out.append("")
        out += [_gap(summaries), ""]
        notes = [f"* `{s.policy}`: {s.description}" for s in summaries if s.description]
        out += notes + [""]
        if env in images:
            out += [f"![{env}]({images[env]})", ""]
    return "\n".join(out)


def _gap(summaries: list[Summary]) -> str:
    """One sentence on how the learned agents compare with the reference and the floor."""
    by_kind: dict[str, list[Summary]] = {}
    for s in summaries:
        by_kind.setdefault(s.kind, []).append(s)
    learned, ref = by_kind.get("learned", []), by_kind.get("reference", [])
    if not learned or not ref:
        return ""
    floor = {s.policy: s.return_mean for s in by_kind.get("floor", [])}
    best = min(learned, key=Summary.sort_key)
    counts = ", ".join(f"`{name}` by {sum(s.return_mean > value for s in learned)} of {len(learned)}"
                       for name, value in floor.items())
    text = (f"Learned agents: the best, `{best.policy}`, succeeds in {best.success_rate:.0%} of the episodes with "
            f"return {best.return_mean:.2f}, against the reference's {ref[0].success_rate:.0%} and "
            f"{ref[0].return_mean:.2f}. Beaten on return: {counts}.")
    if any(all(s.return_mean <= value for s in learned) for value in floor.values()):
        text += " **Some floor is beaten by no learned agent: the gap to the reference is this env's open problem.**"
    return text


def write_csv(all_summaries: dict[str, list[Summary]], path: Path) -> Path:
    """One line per (env, policy), every number of the summary."""
    buf = io.StringIO()
    writer = csv.writer(buf)
    keys = sorted({k for ss in all_summaries.values() for s in ss for k in s.metrics})
    writer.writerow(["env", "rank", "policy", "kind", "episodes", "success_rate", "success_ci_low", "success_ci_high",
                     "return_mean", "return_ci_low", "return_ci_high", "return_std", "apart_from_leader",
                     "noise_floor_success_drop", "noise_floor_metric", "noise_floor_metric_gap",
                     *keys, "wall_seconds_per_episode", "kf_validation", "dynamic_episodes", "dynamic_success_rate",
                     "dynamic_return_mean", *(f"dynamic_{k}" for k in keys), "dynamic_kf_own_episode",
                     "mujoco_dynamic_episodes", "mujoco_dynamic_success_rate", "mujoco_dynamic_kf_own_episode",
                     "producer_sha256", "producer"])
    for ss in all_summaries.values():
        floor = noise_floor(ss)
        floor_cells = ["" if floor.success_drop is None else f"{floor.success_drop:.4f}", floor.metric,
                       "" if floor.metric_gap is None else f"{floor.metric_gap:.6g}"]
        for s in ss:
            writer.writerow([s.env, s.rank, s.policy, s.kind, s.episodes, f"{s.success_rate:.4f}",
                             *(f"{v:.4f}" for v in s.success_ci), f"{s.return_mean:.6g}",
                             *(f"{v:.6g}" for v in s.return_ci), f"{s.return_std:.6g}", _apart(s), *floor_cells,
                             *(f"{s.metrics[k]:.6g}" if k in s.metrics else "" for k in keys),
                             f"{s.wall_seconds:.4f}", _verdict(s), *_dynamic_cells(s, keys),
                             *_mujoco_cells(s), producer_id(s.producer), s.producer])
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(buf.getvalue())
    return path


def _dynamic_cells(s: Summary, keys: list[str]) -> list[str]:
    d = s.dynamic
    if d is None:
        return [""] * (4 + len(keys))
    return [str(d["episodes"]), f"{d['success_rate']:.4f}", f"{d['return_mean']:.6g}",
            *(f"{d['metrics'][k]:.6g}" if k in d["metrics"] else "" for k in keys),
            "" if d["kf"] is None else ("PASS" if d["kf"]["passed"] else "FAIL")]


def _mujoco_cells(s: Summary) -> list[str]:
    d = s.dynamic_mujoco
    if d is None:
        return ["", "", ""]
    return [str(d["episodes"]), f"{d['success_rate']:.4f}",
            "" if d["kf"] is None else ("PASS" if d["kf"]["passed"] else "FAIL")]


def write_reports(all_summaries: dict[str, list[Summary]], suite: EvalSuite, out: str | Path,
                   markdown_path: str | Path | None, env_ids: list[str] | None = None,
                   policies: list[str] | None = None) -> list[Path]:
    """Write the leaderboard's reports to ``out``: a picture per env, the CSV and LEADERBOARD.md (at
    ``markdown_path``, default in ``out``); returns the files written."""
    import os
    import platform

    from paragym.plots import plot_leaderboard

    out = Path(out)
    md_path = Path(markdown_path) if markdown_path is not None else out / "LEADERBOARD.md"
    images = {}
    files = []
    for env, ss in all_summaries.items():
        key, sign = bench_of(env).primary
        png = plot_leaderboard(ss, key, bench_of(env).label(key), out / f"{env_name(env)}.png",
                               f"{env}: {ss[0].episodes} episodes per policy ({suite.name} suite"
                               f"{': a smoke test, not a ranking' if suite.smoke else ''})",
                               higher_is_better=sign > 0)
        files.append(png)
        images[env] = os.path.relpath(png, md_path.parent)
    files.append(write_csv(all_summaries, out / "leaderboard.csv"))
    header = (f"# paragym leaderboard\n\npackage version {paragym.__version__}; {suite.name} suite: evaluation "
              f"seeds {', '.join(map(str, suite.seeds))} x {suite.episodes} episodes per policy "
              f"(reset seed 100000 + 1000 seed + episode), random scenarios, kinematic fidelity; "
              f"wall times on {platform.machine()} with {os.cpu_count()} cores. Written by `paragym leaderboard"
              f"{suite.options()}`; every episode is a row of the SQLite results database.")
    if smoke_note(suite):
        header += "\n\n" + smoke_note(suite)
    if env_ids or policies:
        header += ("\n\n**A partial table**, not the full leaderboard: only "
                   + "; ".join(x for x in (f"envs {', '.join(env_name(e) for e in env_ids)}" if env_ids else "",
                                           f"policies {', '.join(policies)}" if policies else "") if x) + ".")
    md_path.parent.mkdir(parents=True, exist_ok=True)
    md_path.write_text(markdown(all_summaries, suite, images, header))
    files.append(md_path)
    return files

