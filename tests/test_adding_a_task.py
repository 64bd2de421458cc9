"""Adding a task is a recipe (issue 27, item 5): a task defined in the test suite, with one registry row
and one bench module (``tests/point_task.py``) and no edit to any module of paragym, is found by
``paragym envs``, ``policies``, ``demo``, ``plan``/``validate`` (which refuse it in one line),
``leaderboard --quick`` and the generated docs, as a user's own package would be."""

import json
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent

SCRIPT = r"""
import contextlib, io, json, sys
sys.path.insert(0, sys.argv[1])
out = sys.argv[2]
import point_task  # registers paragym/PointReach-v0
from paragym.cli import main
from paragym.baselines.tasks import bench_of, missing
from paragym.docpages import env_page, index_page

def run(*argv):
    buf, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return {"code": code, "out": buf.getvalue(), "err": err.getvalue()}

res = {
    "envs": run("envs"),
    "policies": run("policies", "PointReach-v0"),
    "demo": run("demo", "PointReach-v0", "--out", out),
    "plan": run("plan", "PointReach-v0", "--out", out),
    "validate": run("validate", "PointReach-v0", "--out", out),
    "leaderboard": run("leaderboard", "--quick", "--env", "PointReach-v0", "--db", out + "/r.sqlite", "--out", out,
                       "--workers", "1", "--no-progress"),
    "missing": missing(bench_of("paragym/PointReach-v0"), "paragym/PointReach-v0"),
    "page": env_page("paragym/PointReach-v0"),
    "index": index_page(),
}
print(json.dumps(res))
"""


def test_a_task_of_one_row_and_one_bench_module_is_found_everywhere(tmp_path):
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(TESTS), str(tmp_path)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert "paragym/PointReach-v0" in res["envs"]["out"]
    assert "go-straight" in res["policies"]["out"] and "random" in res["policies"]["out"]
    assert res["demo"]["code"] == 0 and list(tmp_path.glob("PointReach-v0_paper_seed0_best.png"))
    for refused in ("plan", "validate"):  # no offline planner, no dynamic fidelity: one line each, exit code 2
        assert res[refused]["code"] == 2 and len(res[refused]["err"].strip().splitlines()) == 1, res[refused]
    board = res["leaderboard"]
    assert board["code"] == 0, board["err"]
    table = board["out"].split("paragym/PointReach-v0")[-1]
    first = [line for line in table.splitlines() if line.strip().startswith("1 ")][0]
    assert "go-straight" in first and "final distance [m]" in table
    assert list(tmp_path.glob("partial-*/LEADERBOARD.md"))
    assert res["missing"] == []
    page = res["page"]
    for section in ("## Description", "## Action Space", "## Observation Space", "## Rewards", "## Starting State",
                    "## Episode End", "## Arguments", "## Version History", "go-straight"):
        assert section in page
    assert "PointReach-v0.md" in res["index"]


def test_the_task_is_in_no_module_of_paragym():
    """The proof is only a proof if nothing of paragym names the task."""
    root = TESTS.parent
    sources = [p for folder in ("paragym", "envs", "planners", "baselines", "validation", "models")
               for p in (root / folder).rglob("*.py")]
    assert sources
    assert not [p for p in sources if "PointReach" in p.read_text() or "point_task" in p.read_text()]


def test_an_installed_task_plugin_is_found_by_the_paragym_command(tmp_path):
    """A package that declares its task module under the entry-point group ``paragym.tasks`` is imported by
    ``import paragym``: the ``paragym`` command lists its ids without the user importing anything."""
    site = tmp_path / "site"
    dist = site / "point_plugin-1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: point-plugin\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[paragym.tasks]\npoint = point_task\n")
    env = {**__import__("os").environ, "PYTHONPATH": f"{site}:{TESTS}"}
    proc = subprocess.run([sys.executable, "-m", "paragym.cli", "envs"], capture_output=True, text=True, env=env,
                          timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "paragym/PointReach-v0" in proc.stdout
