"""The documentation site's generated pages: one page per env id, and the index of them.

Each page is made from what the project already says, never written by hand: the env class's
docstring (its sections ``## Description``, ``## Action Space`` ... ``## Version History``, the
format Gymnasium's env pages use), the id's registry row (:mod:`paragym.registry`), the env's
spaces, and its task's bench (:mod:`paragym.baselines.tasks`: the reference, the built-in
policies, the leaderboard's metrics). A later version's docstring says what changed; where one
of its sections reads "As vN", the page shows that version's section below it.

``python docs/build.py`` writes the pages and builds the site; ``tests/test_docs.py`` fails when a
committed page is not what this module writes now.
"""

from __future__ import annotations

import importlib
import inspect
import re
import warnings
from functools import lru_cache
from pathlib import Path
from typing import Any

from paragym import registry
from paragym.baselines.leaderboard.summary import rung_verdict

__all__ = ["CONFORMANCE", "SECTIONS", "conformance_page", "env_class", "env_page", "index_page", "ladder_figure",
           "ladder_table", "ladders_page", "lineage", "readme_env_table", "readme_leaderboard_table", "render_frame",
           "sections", "speed_page", "status", "write_pages"]

#: the sections of an env page, in order (Gymnasium's env pages use the same)
#: and "Dynamic Fidelity": what is known of the env under PyBullet's dynamics, where it departs from the
#: kinematic model (measured)
SECTIONS = ("Description", "Action Space", "Observation Space", "Rewards", "Starting State", "Episode End",
            "Arguments", "Dynamic Fidelity", "Version History")


def env_class(env_id: str) -> type:
    """The single env's class of ``env_id`` (its registry row's entry point)."""
    module, name = registry.row(env_id).entry_point.split(":")
    return getattr(importlib.import_module(module), name)


def sections(cls: type) -> tuple[str, dict[str, str]]:
    """A class docstring's summary (the text before its first ``## `` heading) and its sections by
    heading; a heading that names several sections ("Starting State, Action Space") gives each of
    them the same text."""
    doc = inspect.cleandoc(cls.__dict__.get("__doc__") or "")
    parts = re.split(r"^## +(.+?)\s*$", doc, flags=re.M)
    found: dict[str, str] = {}
    for heading, body in zip(parts[1::2], parts[2::2], strict=True):
        for name in heading.split(","):
            found[name.strip()] = body.strip()
    return parts[0].strip(), found


def _parent_id(cls: type) -> str | None:
    """The env id of the nearest base class that is a registered env (the version ``cls`` extends)."""
    by_class = {r.entry_point: r.id for r in registry.rows()}
    for base in cls.__mro__[1:]:
        key = f"{base.__module__}:{base.__qualname__}"
        if key in by_class:
            return by_class[key]
    return None


#: a section's text that only points at the version it extends ("As v1.", "As v0 of the easy rung (``id``), with
#: rung 2's knobs."): the page shows the text pointed at instead
_POINTER = re.compile(r"As (v\d+|the [^(.]*?)( of (this|the easy) rung)?( \(``[^`]+``\))?(, with rung \d's knobs?)?\.")


def _section(env_id: str, name: str) -> list[tuple[str, str]]:
    """The text of section ``name`` for ``env_id``: (the id that says it, text), the id's own first; an
    own text that begins "As ..." (or none) is followed by the section of the version it extends, until a
    text that stands on its own. Texts that only point on (:data:`_POINTER`) are left out."""
    cls = env_class(env_id)
    _, own = sections(cls)
    parent = _parent_id(cls)
    out = [(env_id, own[name])] if name in own else []
    if parent is not None and (not out or out[0][1].startswith("As ")):
        out += _section(parent, name)
    return [(source, text) for source, text in out if not _POINTER.fullmatch(text)]


def lineage(env_id: str) -> list[str]:
    """The ids ``env_id`` extends, the oldest first, then ``env_id``: its line of history."""
    parent = _parent_id(env_class(env_id))
    return ([] if parent is None else lineage(parent)) + [env_id]


def status(env_id: str) -> str:
    """"latest" for the newest version of its task, else "superseded by <id>"; "rung k of n" for a rung of its
    task's difficulty ladder; then the fidelities it has."""
    row = registry.row(env_id)
    fidelities = "kinematic + dynamic" if "fidelity" in inspect.signature(env_class(env_id)).parameters \
        else "kinematic"
    if row.rung is not None:
        rungs = len(registry.ladder(env_id))
        return f"rung {row.rung} of {rungs} (0 the easiest) of the ladder v{row.version}; {fidelities}"
    newest = registry.rows_of(row.task)[-1].id
    return f"{'latest' if newest == env_id else f'superseded by `{newest}`'}; {fidelities}"


#: the hand-written page of why each version and ladder was made, its sections labelled ``why-<name>-<what>``
VERSIONS_PAGE = Path(__file__).resolve().parent / "versions.md"


def _why_labels(name: str) -> list[str]:
    """The labels of :data:`VERSIONS_PAGE`'s sections on the id named ``name`` (its name without "paragym/")."""
    return [label for label in _versions_labels() if label.startswith(f"why-{name.lower()}-")]


@lru_cache(maxsize=1)
def _versions_labels() -> tuple[str, ...]:
    """Every section label of :data:`VERSIONS_PAGE`, read once."""
    return tuple(re.findall(r"^\((why-[a-z0-9-]+)\)=$", VERSIONS_PAGE.read_text(), flags=re.M))


def _rst(text: str) -> list[str]:
    """A docstring's text (reStructuredText) inside a MyST page."""
    return ["```{eval-rst}", text, "```"]


def _space(space: Any) -> str:
    return re.sub(r"\s+", " ", repr(space))


def env_page(env_id: str, image: str | None = None, board: str | Path | None = None) -> str:
    """The MyST page of ``env_id``; ``image``: the path of its rendered frame, relative to the page; ``board``:
    the committed run's ``leaderboard.csv``, whose :func:`rung_verdict` a rung's page shows under its status."""
    from paragym.baselines.tasks import bench_of

    row = registry.row(env_id)
    cls = env_class(env_id)
    summary, own = sections(cls)
    bench = bench_of(env_id)
    verdict = "-"
    if board is not None and row.rung is not None:
        verdict = rung_verdict(_ladder_rows(board).get(row.task, {}), env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import gymnasium as gym

        env = gym.make(env_id)
        action_space, observation_space = _space(env.action_space), _space(env.observation_space)
        env.close()
    lines = [f"# {row.name}", "", *_rst(summary), ""]
    case = "the paper's case" if row.rung is None else "a scene of the rung"
    paper_case = f"; the paper's case: `{row.paper_scenario}`" if row.rung is None else " (drawn from the rung's knobs)"
    if image is not None:
        lines += [f"```{{image}} {image}", f":alt: {row.name}, {case} after reset(seed=0)",
                  ":width: 420px", "```", ""]
    make, vector = f'`gym.make("{row.id}")`', "Gymnasium's `sync` and `async` modes"
    if row.vector_entry_point:
        vector = f'`gym.make_vec("{row.id}", num_envs=N, vectorization_mode="vector_entry_point")`'
    lines += ["| | |", "|---|---|",
              f"| id | `{row.id}` |",
              f"| make | {make} |",
              f"| vector env | {vector} |",
              f"| status | {status(env_id)} |",
              *([f"| verdict | {verdict} (the committed leaderboard: hard only where the reference's interval lies "
                 f"above every floor's and learner's; [the ladders](../ladders.md)) |"] if verdict != "-" else []),
              f"| action space | `{action_space}` |",
              f"| observation space | `{observation_space}` |",
              f"| episode length | at most {row.max_episode_steps} steps (`TimeLimit`) |",
              f"| scenarios | {', '.join(f'`{s}`' for s in row.scenario_names)}{paper_case} |",
              f"| lineage | {' -> '.join(f'`{registry.row(i).name}`' for i in lineage(env_id))} |",
              f"| task | `{row.task}` ({row.summary}) |",
              f"| reference | `{bench.reference}` (`paragym demo {row.name}`) |",
              *[f"| why it was made | {{ref}}`{label}` |" for label in _why_labels(row.name)],
              ""]
    for name in SECTIONS:
        texts = _section(env_id, name)
        if not texts:
            continue
        lines += [f"## {name}", ""]
        for source, text in texts:
            if source != env_id:
                lines += [f"*As `{source}` says it:*", ""]
            lines += [*_rst(text), ""]
    lines += ["## On the leaderboard", "",
              f"Ranked by success rate, then {bench.label(bench.primary[0])} "
              f"({'higher' if bench.primary[1] > 0 else 'lower'} is better). Built-in policies "
              f"(`paragym policies {row.name}` lists them with the shipped models):", "",
              "| policy | kind | what it is |", "|---|---|---|"]
    lines += [f"| `{p.name}` | {p.kind} | {p.description.replace('|', '/')} |"
              for p in bench.policies if p.plays(env_id)]
    lines += ["| `random` | floor | uniform random actions |", "",
              "Per-episode metrics: " + ", ".join(f"{c.label} (`{c.key}`)" for c in bench.columns) + ".", ""]
    return "\n".join(lines)


def index_page() -> str:
    """The env index: one row per registered id, with its status."""
    lines = ["# Environments", "",
             "One page per env id, generated from the env's docstring, its registry row and its task's bench "
             "(`python docs/build.py`). Every version stays registered and unchanged.", "",
             "| env id | status | what it is |", "|---|---|---|"]
    lines += [f"| [`{r.id}`]({r.name}.md) | {status(r.id)} | {r.summary} |" for r in registry.rows()]
    lines += ["", "```{toctree}", ":hidden:", "", *(r.name for r in registry.rows()), "```", ""]
    return "\n".join(lines)


def readme_env_table() -> str:
    """The README's table of env ids (its status column from :func:`status`), between its markers."""
    lines = ["| env id | status | what it is |", "|---|---|---|"]
    done: set[str] = set()
    for r in registry.rows():
        if r.rung is None:
            lines.append(f"| [`{r.id}`](docs/envs/{r.name}.md) | {status(r.id)} | {r.summary} |")
        elif r.id not in done:  # a ladder in one row: its rungs, easiest first
            rungs = registry.ladder(r.id)
            done.update(x.id for x in rungs)
            ids = ", ".join(f"[`{x.id}`](docs/envs/{x.name}.md)" for x in rungs)
            kind = status(r.id).split("; ", 1)[1]
            lines.append(f"| {ids} | ladder v{r.version}, rungs 0-{len(rungs) - 1} (0 the easiest); {kind} | "
                         f"{r.summary.rsplit(': rung', 1)[0]} |")
    return "\n".join(lines)


def readme_leaderboard_table(csv_path: str | Path) -> str:
    """The README's headline leaderboard, from the committed run's ``leaderboard.csv``: per env id, the
    leader, the reference, the best learned agent and the floors, each success rate with its 95 % interval
    and the env's ranking metric after it; "(apart)" where the leader is ahead beyond doubt; and the
    reference's episodes in dynamic fidelity (success with its interval, and the KF verdict on its own). The
    rungs of the ladders are left to :func:`ladder_table`."""
    import csv

    from paragym.baselines.tasks import bench_of

    rows: dict[str, list[dict[str, str]]] = {}
    with open(csv_path, newline="") as f:
        for row in csv.DictReader(f):
            rows.setdefault(row["env"], []).append(row)

    def cell(r: dict[str, str] | None, key: str, apart: bool = True) -> str:
        if r is None:
            return ""
        bench = bench_of(r["env"])
        value = float(r["return_mean"] if key == "return" else r[key])
        mark = " (apart)" if apart and r["apart_from_leader"] == "yes" else ""
        return (f"`{r['policy']}` {float(r['success_rate']):.2f} [{float(r['success_ci_low']):.2f}, "
                f"{float(r['success_ci_high']):.2f}], {bench.label(key)} {value:{bench.fmt(key)}}{mark}")

    def dynamic(r: dict[str, str] | None) -> str:
        counted = _dynamic_successes(r)
        return "" if counted is None else f"{counted}, KF {r['dynamic_kf_own_episode']}"

    lines = ["| env | 1st | reference | best learned | floors | reference, dynamic fidelity |",
             "|---|---|---|---|---|---|"]
    for env, rs in rows.items():
        if registry.row(env).rung is not None:  # the ladders have their own table (ladder_table)
            continue
        rs.sort(key=lambda r: int(r["rank"]))
        key = bench_of(env).primary[0]
        ref = next((r for r in rs if r["kind"] == "reference"), None)
        learned = next((r for r in rs if r["kind"] == "learned"), None)
        floors = "; ".join(cell(r, key, False) for r in rs if r["kind"] == "floor")
        lines.append(f"| {env.split('/')[-1]} | {cell(rs[0], key, False)} | "
                     f"{cell(ref, key) if ref is not rs[0] else 'the 1st'} | {cell(learned, key)} | {floors} | "
                     f"{dynamic(ref)} |")
    return "\n".join(lines)


def _dynamic_successes(r: dict[str, str] | None) -> str | None:
    """A CSV row's dynamic episodes as "k/n [low, high]" (Wilson's 95 %), or None where it ran none."""
    from paragym.baselines.stats import wilson

    if r is None or not r["dynamic_episodes"]:
        return None
    n = int(r["dynamic_episodes"])
    k = round(float(r["dynamic_success_rate"]) * n)
    lo, hi = wilson(k, n)
    return f"{k}/{n} [{lo:.2f}, {hi:.2f}]"


#: the learned rows of the ladders' table, by algorithm (a shipped model's policy name is ``<algo>-seed<N>``)
LEARNED_NAMES = {"ppo": "PPO", "sac": "SAC", "td3": "TD3", "bc": "BC", "dagger": "DAgger", "cem": "linear CEM"}


def _ladder_rows(csv_path: str | Path) -> dict[str, dict[str, dict[str, dict[str, str]]]]:
    """The committed run's rows of every rung: task -> method -> rung id -> its CSV row. A method is a row's
    role: "reference", the naive floor (its name), "zero", "random", and each learning algorithm by its name
    (:data:`LEARNED_NAMES`: its seed ranked highest on that rung)."""
    import csv

    rungs = {r.id: r for r in registry.rows() if r.rung is not None}
    out: dict[str, dict[str, dict[str, dict[str, str]]]] = {}
    with open(csv_path, newline="") as f:
        for row in sorted(csv.DictReader(f), key=lambda r: int(r["rank"])):
            rung = rungs.get(row["env"])
            if rung is None:
                continue
            kind, name = row["kind"], row["policy"]
            algo = name.split("-seed")[0]
            method = ("reference" if kind == "reference" else name if kind == "floor" else
                      LEARNED_NAMES.get(algo, algo) if kind == "learned" else None)
            if method is not None:
                out.setdefault(rung.task, {}).setdefault(method, {}).setdefault(rung.id, row)
    return out


def _ladders_found(found: dict[str, dict[str, dict[str, dict[str, str]]]], newest: bool = False
                   ) -> list[tuple[str, list[str], dict[str, dict[str, dict[str, str]]]]]:
    """Every ladder with rows in ``found`` (:func:`_ladder_rows`), or with ``newest`` each task's newest one: its
    label (the task, and the ladder's version where the task has more than one), its rung ids, easiest first,
    and the methods that ranked on it."""
    out = []
    for task, methods in found.items():
        ladders = registry.ladders(task)
        for rungs in ladders[-1:] if newest else ladders:
            ids = [r.id for r in rungs]
            mine = {m: {e: r for e, r in rows.items() if e in ids} for m, rows in methods.items()}
            mine = {m: rows for m, rows in mine.items() if rows}
            if mine:
                out.append((task if len(ladders) == 1 else f"{task} v{rungs[0].version}", ids, mine))
    return out


def ladder_table(csv_path: str | Path, newest: bool = False) -> str:
    """The headline of the difficulty ladders, from the committed run's ``leaderboard.csv``: per task (with
    ``newest``, its newest ladder only: the README's), each method's success on every rung with its 95 % interval
    (Wilson; kinematic fidelity, the leaderboard's episodes), the reference's in dynamic fidelity (its successes
    of the episodes run there), and each rung's :func:`rung_verdict`."""

    found = _ladder_rows(csv_path)
    lines = ["| task | method | " + " | ".join(registry.RUNG_NAMES) + " |",
             "|---|---|" + "---|" * len(registry.RUNG_NAMES)]
    for task, ids, methods in _ladders_found(found, newest):
        learned = [m for m in LEARNED_NAMES.values() if m in methods]
        order = ["reference", *sorted(m for m in methods if m not in ("reference", "zero", "random", *learned)),
                 "zero", "random", *learned]
        for method in order:
            cells = []
            for env_id in ids:
                r = methods.get(method, {}).get(env_id)
                cells.append("-" if r is None else f"{float(r['success_rate']):.2f} [{float(r['success_ci_low']):.2f}, "
                             f"{float(r['success_ci_high']):.2f}]")
            if method in methods:
                lines.append(f"| {task} | {method} | " + " | ".join(cells) + " |")
        cells = [_dynamic_successes(methods.get("reference", {}).get(env_id)) or "-" for env_id in ids]
        lines.append(f"| {task} | reference, dynamic | " + " | ".join(cells) + " |")
        lines.append(f"| {task} | **verdict** | " + " | ".join(rung_verdict(methods, e) for e in ids) + " |")
    return "\n".join(lines)


def ladder_figure(csv_path: str | Path, path: str | Path) -> Path:
    """The headline figure: success against rung, one panel per task, a line per method with its 95 %
    interval (the rows of :func:`ladder_table`), written to the PNG ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    found = _ladders_found(_ladder_rows(csv_path))
    fig, axes = plt.subplots(1, len(found), figsize=(4.0 * len(found), 3.4), squeeze=False)
    colours = {"reference": "tab:green", "zero": "tab:gray", "random": "tab:red", "PPO": "tab:blue",
               "SAC": "tab:cyan", "BC": "tab:purple", "DAgger": "tab:pink", "linear CEM": "tab:brown"}
    for ax, (task, ids, methods) in zip(axes[0], found, strict=True):
        for j, (method, rows) in enumerate(methods.items()):
            xs = [k + (j - (len(methods) - 1) / 2) * 0.06 for k, env_id in enumerate(ids) if env_id in rows]
            got = [rows[env_id] for env_id in ids if env_id in rows]
            ys = [float(r["success_rate"]) for r in got]
            err = [[y - float(r["success_ci_low"]) for y, r in zip(ys, got, strict=True)],
                   [float(r["success_ci_high"]) - y for y, r in zip(ys, got, strict=True)]]
            ax.errorbar(xs, ys, yerr=err, marker="o", ms=4, capsize=2, label=method,
                        color=colours.get(method, "tab:orange"))
        ax.set_xticks(range(len(ids)), registry.RUNG_NAMES[:len(ids)])
        ax.set_ylim(-0.05, 1.05)
        ax.set_title(task, fontsize=10)
        ax.axhline(0.9, color="tab:green", lw=0.6, ls=":")
        ax.axhline(0.1, color="tab:gray", lw=0.6, ls=":")
        ax.legend(fontsize=7, loc="center right")
    axes[0][0].set_ylabel("success (95 % CI)")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def ladders_page(csv_path: str | Path) -> str:
    """The docs' ladders page (``docs/ladders.md``): what a ladder is, its figure and :func:`ladder_table`."""
    rungs = ", ".join(f"[`{r.name}`](envs/{r.name}.md)" for r in registry.rows() if r.rung is not None)
    return "\n".join([
        "# Difficulty ladders", "",
        "Each task has three rung ids, `-Easy`, `-Medium` and `-Hard` (v0 each), whose scenarios a seeded "
        "generator draws from the rung's knobs (the table on each rung's page): the newest version's task on "
        "scenarios where doing nothing, random actions and the task's naive controller fail and the paper's "
        "method succeeds. A ladder has versions as a task has: the hybrid's ladder v1 (`-Easy-v1` ...) takes "
        "away the offset lever that let a constant action solve the ladder v0, and draws only pairs that no "
        "constant split rate gets through, that the reference provably plans, and, up the ladder, that a "
        "lookahead rule with one, then five samples of sight fails. Each rung is ranked as its own table of the "
        "leaderboard. How long PPO from scratch "
        "takes to solve a rung on 2 cores is measured by `python benchmarks/time_to_solve.py --env <rung>` "
        "(the CHANGELOG has the figures).", "",
        "Success per rung and method, over the leaderboard's 50 episodes (kinematic fidelity) with Wilson's "
        "95 % interval; the last row of each task is the reference's dynamic episodes. PPO is trained from "
        "scratch (seed 0, at most 30 minutes on 2 cores on the rungs); BC and DAgger learn from 200 of the "
        "reference's episodes, so they show how well the paper's method can be imitated, not learned anew; "
        "linear CEM is a five-minute cross-entropy search of linear policies (`paragym train ID --algo cem`); SAC "
        "is trained with its yml's settings (seed 0, `paragym train ID --algo sac --vectorized`); a "
        "dash is a rung without that learner shipped. Generated from the committed "
        "`leaderboard/leaderboard.csv` by `python docs/build.py`.", "",
        "The verdict row holds each rung to the rule a benchmark's hard rung must meet: it is **hard** only where "
        "the reference's interval lies above that of every other method ranked on it, floors and learners alike; "
        "elsewhere it is a **sanity** rung, and the row names the methods that reach the reference's interval. "
        "The floors besides zero and random are the cheap methods a reviewer tries first: each task's naive "
        "controller, the best constant action of a grid over the action box (where it is not zero), and rules "
        "read from the observation in two lines (the Orthoglide's `hill-climb`, the CaPaMan's `slide-rule`, the "
        "hybrid's `stroke-rule`), and on the hybrid's ladder v1 the model's `lookahead-H` rules; "
        "each floor's page entry says how it was chosen.", "",
        "![success against rung](reports/ladders.png)", "",
        ladder_table(csv_path), "",
        f"Rungs: {rungs}.", ""])


def render_frame(env_id: str, path: Path) -> Path:
    """The paper's case of ``env_id`` after ``reset(seed=0)``, rendered to the PNG ``path``."""
    import gymnasium as gym
    from PIL import Image

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, scenario=registry.row(env_id).paper_scenario, render_mode="rgb_array")
        env.reset(seed=0)
        frame = env.render()
        env.close()
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(frame).save(path)
    return path


def write_pages(folder: str | Path, images: bool = True, env_ids: list[str] | None = None,
                board: str | Path | None = None) -> list[Path]:
    """Write ``folder/index.md`` and a page per env id (``env_ids``: those only; default all), and with
    ``images`` each id's frame to ``folder/images/<name>.png``; ``board``: the committed run's
    ``leaderboard.csv``, whose :func:`rung_verdict` each rung's page shows. Returns the files written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for r in registry.rows():
        if env_ids is not None and r.id not in env_ids:
            continue
        png = folder / "images" / f"{r.name}.png"
        if images:
            written.append(render_frame(r.id, png))
        page = folder / f"{r.name}.md"
        page.write_text(env_page(r.id, f"images/{r.name}.png", board))
        written.append(page)
    index = folder / "index.md"
    index.write_text(index_page())
    written.append(index)
    return written


#: the result files of the conformance page (:func:`conformance_page`), by their names' beginnings; the speed
#: page has the others
CONFORMANCE = ("conformance", "convergence", "reference_dynamic", "kf_attitude", "tripod_estimators")


def _result_sections(files: list[dict[str, Any]]) -> list[str]:
    """One section per result file: its title, its paragraph, what produced it (command, date, machine,
    commit, versions) and its table (and figure)."""
    out: list[str] = []
    for f in sorted(files, key=lambda f: (f.get("order", 50), f["name"])):
        out += [f"## {f['title']}", "", f["paragraph"], "",
                f"`{f['command']}`: {f['date']}, {f['machine']}, commit `{f['commit']}`"
                + (f"; {f['source']}" if f.get("source") else "") + ".", "",
                "| " + " | ".join(f["columns"]) + " |", "|" + "---|" * len(f["columns"])]
        out += ["| " + " | ".join(r) + " |" for r in f["rows"]]
        out.append("")
        if f.get("figure"):
            out += [f"![{f['title']}]({f['figure']})", ""]
    return out


def _result_files(results: str | Path, conformance: bool) -> list[dict[str, Any]]:
    import json

    files = [json.loads(p.read_text()) for p in sorted(Path(results).glob("*.json"))]
    return [f for f in files if f["name"].startswith(CONFORMANCE) == conformance]


def speed_page(results: str | Path) -> str:
    """``docs/speed.md``, made from the benchmarks' result files in ``results`` (``benchmarks/results/*.json``,
    written by ``benchmarks/results_file.record``) but the conformance page's: one section per file, in its
    ``order``, each a title, one paragraph, what produced it (command, date, machine, commit) and its table. No
    figure is typed in."""
    out = ["# Speed", "",
           "Every table below is a benchmark's result file (`benchmarks/results/`), written by the script that "
           "measured it, with the command, the date, the machine and the commit that produced it; "
           "`python docs/build.py` makes this page from them. Figures move with a machine's load: compare rows "
           "of one table, or re-run its command. How these figures were investigated in the past is in "
           "[the speed notes](notes/speed-history.md). Two engines on one mechanism are on "
           "[the conformance page](conformance.md).", ""]
    return "\n".join(out + _result_sections(_result_files(results, conformance=False)))


def conformance_page(results: str | Path) -> str:
    """``docs/conformance.md``: PyBullet and MuJoCo on the same mechanisms (``benchmarks/conformance.py`` and
    ``benchmarks/reference_dynamic.py``'s result files, :data:`CONFORMANCE`), as :func:`speed_page` makes its
    sections, under a guide to reading them. No figure is typed in."""
    out = ["# Conformance: two engines, one mechanism", "",
           "paragym's dynamic fidelity runs in PyBullet and, for every task whose ids accept it, in MuJoCo "
           "(`gym.make(id, fidelity=\"dynamic\", engine=\"mujoco\")`, [the dynamics guide](guides/dynamics.md)). "
           "Both engines simulate the same model: MuJoCo's is the MJCF that `paragym export` writes from the "
           "PyBullet scene, its loop closures as `connect` constraints. The tables below come from one run of "
           "`benchmarks/conformance.py` (and `benchmarks/convergence.py`, `benchmarks/reference_dynamic.py` for "
           "30 episodes per engine, `benchmarks/kf_attitude.py` for what the KF check judges, "
           "`benchmarks/tripod_estimators.py` for why the tripod's reference misses it), with the date, "
           "the machine, the commit and the engines' versions of that run.",
           "",
           "How to read them. *Holding*: where a loop mechanism's motors hold it under gravity, both engines must "
           "find the holding forces that virtual work on the mechanism gives by hand (`paragym.sim.statics`, "
           "which neither engine computes) and keep the loops closed; the MuJoCo rows with its default "
           "`solref`/`solimp` show the sag that closed chains meet there, the exported rows the settings that "
           "fix it (a loop time constant of two steps, a harder impedance). *Contact*: the CaPaMan pushed into "
           "a box at its torque limit stops at nearly the same place in both; MuJoCo's default contacts are soft "
           "and let the tool sink deeper, so the export gives the fixed parts the loops' stiffness. *The "
           "reference*: the paper's method, judged by success and the KF check in each engine on the same "
           "seeds; where the engines part, the episode's own measures (loop residual, distance from the "
           "command) say which engine drifted. *Convergence*: a verdict is the physics' only where it holds at "
           "half the step and twice the solver's iterations; each task's reference runs the same episodes at "
           "the shipped setting and ever finer ones of the same model, and the shipped row says whether its "
           "verdicts and path held, or what error it carries.", ""]
    return "\n".join(out + _result_sections(_result_files(results, conformance=True)))
