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
sys.path.insert(0, sys.argv[1] + "/../docs")
out = sys.argv[2]
import point_task  # registers paragym/PointReach-v0
from paragym.cli import main
from paragym.baselines.tasks import bench_of, missing
from pages import env_page, index_page

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
    # no offline planner, no dynamic fidelity: one line each saying so (a crash would say something else)
    for refused, why in (("plan", "has no offline planner"), ("validate", "has no dynamic fidelity")):
        err = res[refused]["err"].strip()
        assert res[refused]["code"] == 2 and len(err.splitlines()) == 1, res[refused]
        assert err.startswith(f"paragym: error: paragym/PointReach-v0 {why}"), err
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


EQUAL = r"""
import sys
sys.path.insert(0, sys.argv[1])
import gymnasium as gym
import numpy as np
import point_task  # registers paragym/PointReach-v0

native = gym.make_vec("paragym/PointReach-v0", num_envs=3, vectorization_mode="vector_entry_point")
sync = gym.make_vec("paragym/PointReach-v0", num_envs=3, vectorization_mode="sync")
a, b = native.reset(seed=5), sync.reset(seed=5)
np.testing.assert_array_equal(a[0], b[0])
rng, ended = np.random.default_rng(0), 0
for _ in range(120):
    act = rng.uniform(-1.2, 1.2, (3, 2)).astype(np.float32)
    got, want = native.step(act), sync.step(act)
    for x, y in zip(got[:4], want[:4], strict=True):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(got[4]["is_success"], want[4]["is_success"])
    np.testing.assert_array_equal(got[4]["distance"], want[4]["distance"])
    ended += int(np.sum(got[2] | got[3]))
print(ended)
"""


def test_the_task_runs_alike_in_its_single_and_native_vector_env():
    """The recipe's task implements the contract once; its native vector env is the same numbers as
    gymnasium's SyncVectorEnv over single envs (as every paragym task's, ``tests/test_single_vs_vector.py``).
    In a process of its own: registering the task here would add an id to the other tests' registry."""
    proc = subprocess.run([sys.executable, "-c", EQUAL, str(TESTS)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert int(proc.stdout.split()[-1]) >= 3  # autoresets on the way
