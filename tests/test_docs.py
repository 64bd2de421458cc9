"""The documentation site: every generated page is current, complete on its own, and every snippet runs.

The env pages are generated (``python docs/build.py``, ``docs/pages.py``) and committed, so that
the site builds from a clean clone and a reviewer sees them in the diff; a page that is not what the
generator writes now fails here. Every ```python block of the README and the docs runs, each on its
own (a snippet that needs another's names fails), in a scratch folder; the leaderboard's full suite is
made one episode for them (``FULL`` patched), since a snippet that ranks an agent runs it.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest
from pages import env_page, index_page

from paragym import registry

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _pages() -> list[Path]:
    return [ROOT / "README.md", *sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)]


def _snippets() -> list[tuple[str, str]]:
    out = []
    for page in _pages():
        for i, block in enumerate(re.findall(r"^```python\n(.*?)^```", page.read_text(), re.S | re.M)):
            out.append((f"{page.relative_to(ROOT)}#{i + 1}", block))
    return out


@pytest.mark.parametrize("row", registry.ROWS, ids=lambda r: r.name)
def test_each_env_page_is_what_the_generator_writes(row):
    page = DOCS / "envs" / f"{row.name}.md"
    assert page.is_file(), f"{page} is missing: run python docs/build.py"
    board = ROOT / "leaderboard" / "leaderboard.csv"
    assert page.read_text() == env_page(row.id, f"images/{row.name}.png", board), \
        f"{page} is stale: run python docs/build.py"
    assert (DOCS / "envs" / "images" / f"{row.name}.png").is_file()


def _page_section(page: str, name: str) -> str:
    return page.split(f"\n## {name}\n", 1)[1].split("\n## ", 1)[0]


@pytest.mark.parametrize("row", registry.ROWS, ids=lambda r: r.name)
def test_each_env_page_writes_out_its_action_and_observation_tables(row):
    """A reader of one page learns what an action does and what each observation entry is, without chasing the
    versions it extends: each section holds the Box and the table itself, in its own words and at most one
    other id's, and the
    observation table's rows cover the observation's entries, 0 to its last."""
    page = env_page(row.id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import gymnasium as gym

        env = gym.make(row.id)
        size = env.observation_space.shape[0]
        env.close()
    for name in ("Action Space", "Observation Space"):
        text = _page_section(page, name)
        assert "Box(" in text, (row.id, name)
        assert text.count("```{eval-rst}") <= 2, f"{row.id}'s {name} sends the reader along a chain of versions"
    table = _page_section(page, "Observation Space")
    indices = re.findall(r"^(\d+)(?:-(\d+))?\s", table, re.M)
    assert indices and indices[0][0] == "0", f"{row.id}'s observation table is not written out"
    if re.search(r"^\d+ \+ \d+ K|^\d+ to ", table, re.M):  # a table in the number of posts K: no numbers to add
        return
    covered = sorted(i for lo, hi in indices for i in range(int(lo), int(hi or lo) + 1))
    assert covered == list(range(size)), f"{row.id}'s observation table covers {covered}, the space has {size}"


def test_the_speed_page_is_made_from_the_benchmarks_result_files():
    """docs/speed.md is generated (no figure typed in): each table is a result file saying what produced it."""
    import json

    from pages import conformance_page, speed_page

    results = ROOT / "benchmarks" / "results"
    assert (DOCS / "speed.md").read_text() == speed_page(results), "docs/speed.md is stale: run python docs/build.py"
    conformance = (DOCS / "conformance.md").read_text()
    assert conformance == conformance_page(results), "docs/conformance.md is stale: run python docs/build.py"
    for name in ("conformance", "conformance_contact", "conformance_reference", "reference_dynamic_mujoco"):
        assert (results / f"{name}.json").is_file() and "MuJoCo" in conformance, name
    files = [json.loads(p.read_text()) for p in results.glob("*.json")]
    assert files
    for f in files:
        assert f["command"].startswith("python benchmarks/") and f["date"] and f["machine"] and f["commit"], f["name"]
        assert f["rows"] and all(len(r) == len(f["columns"]) for r in f["rows"]), f["name"]
        assert "\n\n" not in f["paragraph"], f"{f['name']}: one paragraph"


def test_the_env_index_is_what_the_generator_writes():
    assert (DOCS / "envs" / "index.md").read_text() == index_page(), "docs/envs/index.md is stale"


def test_every_env_page_has_the_eight_sections_and_an_observation_table():
    for row in registry.ROWS:
        page = env_page(row.id)
        for section in ("Description", "Action Space", "Observation Space", "Rewards", "Starting State",
                        "Episode End", "Arguments", "Version History"):
            assert f"\n## {section}\n" in page, f"{row.id}: no {section}"
        observation = page.split("\n## Observation Space\n")[1].split("\n## ")[0]
        assert "====" in observation or "---" in observation, f"{row.id}: no table of the observation"


def test_every_page_of_the_site_is_in_a_toctree():
    text = "\n".join(p.read_text() for p in _pages())
    for page in _pages()[1:]:
        rel = page.relative_to(DOCS).with_suffix("").as_posix()
        if rel in ("index", "envs/index") or rel.startswith("envs/"):
            continue
        assert rel in text, f"docs/{rel}.md is in no toctree"


SNIPPETS = _snippets()


@pytest.mark.parametrize("name,code", SNIPPETS, ids=[n for n, _ in SNIPPETS])
def test_the_snippet_runs_on_its_own(name, code, tmp_path, monkeypatch):
    from paragym.baselines import leaderboard

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(leaderboard, "FULL", leaderboard.EvalSuite("snippet", (0,), 1))
    code = code.replace('description="my method")', 'description="my method", replace=True)')  # may run twice
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(code, name, "exec"), {"__name__": "__snippet__"})


def test_no_source_of_the_site_is_ignored_by_git():
    """A page git ignores builds here and is missing from every clone (docs/results/ once was, under the
    leaderboard's 'results/' rule)."""
    import shutil
    import subprocess

    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    files = [str(p.relative_to(ROOT)) for p in DOCS.rglob("*") if p.is_file() and "_build" not in p.parts
             and "__pycache__" not in p.parts]
    ignored = subprocess.run(["git", "check-ignore", *files], cwd=ROOT, capture_output=True, text=True).stdout
    assert ignored.split() == []


def test_the_ladders_page_is_made_from_the_committed_leaderboard():
    from pages import ladders_page

    board = ROOT / "leaderboard" / "leaderboard.csv"
    assert (DOCS / "ladders.md").read_text() == ladders_page(board), \
        "docs/ladders.md is stale: run python docs/build.py"
    assert (DOCS / "reports" / "ladders.png").is_file()


def test_the_ladder_table_puts_each_method_under_its_rung(tmp_path):
    """Each cell is that rung's row of the CSV: the success with its interval, the reference's dynamic episodes
    counted; a method a rung lacks shows a dash."""
    import csv

    from pages import ladder_table

    from paragym import registry

    easy, medium, hard = (r.id for r in registry.ladders("hybrid")[0])
    fields = ["env", "rank", "policy", "kind", "success_rate", "success_ci_low", "success_ci_high",
              "dynamic_episodes", "dynamic_success_rate"]
    rows = [(easy, 1, "polynomial-detour", "reference", 0.98, 0.90, 1.0, 3, 2 / 3),
            (easy, 2, "greedy-split", "floor", 0.02, 0.0, 0.1, "", ""),
            (medium, 1, "polynomial-detour", "reference", 0.94, 0.84, 0.98, 3, 1.0),
            (hard, 1, "polynomial-detour", "reference", 0.9, 0.79, 0.96, "", ""),
            (easy, 3, "ppo-seed1", "learned", 0.9, 0.79, 0.96, "", ""),
            (easy, 4, "ppo-seed0", "learned", 0.8, 0.67, 0.89, "", ""),
            (hard, 2, "bc-seed0", "learned", 0.1, 0.04, 0.21, "", ""),
            ("paragym/HybridSingularityFree-v2", 1, "zero", "floor", 1.0, 1.0, 1.0, "", ""),
            ("paragym/HybridSingularityFree-Hard-v1", 1, "polynomial-detour", "reference", 1.0, 0.93, 1.0, "", ""),
            ("paragym/HybridSingularityFree-Easy-v2", 1, "polynomial-detour", "reference", 1.0, 0.93, 1.0, 3, 1.0)]
    path = tmp_path / "board.csv"
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(fields)
        writer.writerows(rows)
    table = ladder_table(path).splitlines()
    assert table[2] == "| hybrid v0 | reference | 0.98 [0.90, 1.00] | 0.94 [0.84, 0.98] | 0.90 [0.79, 0.96] |"
    assert table[3] == "| hybrid v0 | greedy-split | 0.02 [0.00, 0.10] | - | - |"
    assert table[4] == "| hybrid v0 | PPO | 0.90 [0.79, 0.96] | - | - |"  # each algorithm's best seed per rung
    assert table[5] == "| hybrid v0 | BC | - | - | 0.10 [0.04, 0.21] |"
    assert table[6] == "| hybrid v0 | reference, dynamic | 2/3 [0.21, 0.94] | 3/3 [0.44, 1.00] | - |"
    # hard only where the reference's interval lies above every other method's: PPO's reaches it on the easy
    # rung; the medium rung ranks no other method, the hard rung's BC lies below
    assert table[7] == "| hybrid v0 | **verdict** | sanity: PPO | hard | hard |"
    # the hybrid's ladder v1 is a table group of its own, under the same rung columns
    assert table[8:11] == ["| hybrid v1 | reference | - | - | 1.00 [0.93, 1.00] |",
                           "| hybrid v1 | reference, dynamic | - | - | - |",
                           "| hybrid v1 | **verdict** | - | - | hard |"]
    assert table[11:] == ["| hybrid v2 | reference | 1.00 [0.93, 1.00] | - | - |",
                          "| hybrid v2 | reference, dynamic | 3/3 [0.44, 1.00] | - | - |",
                          "| hybrid v2 | **verdict** | hard | - | - |"]
    assert len(table) == 14  # the v2 id's row is no rung
    newest = ladder_table(path, newest=True).splitlines()  # the README's: each task's newest ladder alone
    assert newest == table[:2] + table[11:]
    from pages import env_page  # and each rung's page says its verdict, a version's page none

    assert "| verdict | sanity: PPO (the committed leaderboard" in env_page(easy, board=path)
    assert "| verdict | hard (" in env_page(hard, board=path)
    assert "| verdict |" not in env_page("paragym/HybridSingularityFree-v2", board=path)


def test_the_cli_guide_lists_every_command_and_option_the_parser_takes():
    """docs/guides/cli.md's synopsis is the parser's own usage of every command (:func:`paragym.cli.synopsis`): a
    command or an option added to the parser and not to the guide fails here."""
    from paragym.cli import synopsis

    guide = (DOCS / "guides" / "cli.md").read_text()
    assert f"```\n{synopsis()}\n```" in guide, "the CLI guide's synopsis is stale: paste paragym.cli.synopsis()"
