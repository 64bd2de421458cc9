"""The CLI says what is wrong in one line, before it runs anything, and writes to no file it did not
make (issue 15, items 10-11)."""

from __future__ import annotations

import sqlite3

import pytest

import paragym
from paragym import registry
from paragym.baselines.leaderboard import EvalSuite, run_leaderboard
from paragym.baselines.store import ResultStore
from paragym.cli import main

QUICK = ["leaderboard", "--quick", "--no-progress", "--no-validation", "--env", "Orthoglide2PRRKappa-v0",
         "--policy", "zero"]


def _run(capsys, *args):
    code = main(list(args))
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def test_a_damaged_database_is_a_message(tmp_path, capsys):
    db = tmp_path / "r.sqlite"
    assert _run(capsys, *QUICK, "--db", str(db), "--out", str(tmp_path / "o"))[0] == 0
    data = bytearray(db.read_bytes())
    for k in range(4096, len(data), 4096):  # every page after the first, overwritten
        data[k:k + 4096] = bytes(range(256)) * 16
    db.write_bytes(bytes(data))
    damaged = db.read_bytes()
    code, _, err = _run(capsys, *QUICK, "--db", str(db), "--out", str(tmp_path / "o"))
    assert code == 2 and ("damaged" in err or "not a paragym results database" in err) and str(db) in err
    assert db.read_bytes() == damaged


def test_a_database_of_another_program_is_never_written_to(tmp_path, capsys):
    db = tmp_path / "theirs.sqlite"
    con = sqlite3.connect(db)
    con.execute("CREATE TABLE users (name TEXT)")
    con.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
    con.commit()
    con.close()
    before = db.read_bytes()
    code, _, err = _run(capsys, *QUICK, "--db", str(db), "--out", str(tmp_path / "o"))
    assert code == 2 and "not a paragym results database" in err
    assert db.read_bytes() == before


@pytest.mark.parametrize("where", ["db", "out"])
def test_an_unusable_path_fails_before_any_episode_runs(tmp_path, capsys, where):
    blocker = tmp_path / "a_file"
    blocker.write_text("mine")
    db, out = tmp_path / "r.sqlite", tmp_path / "o"
    if where == "db":
        db = blocker / "r.sqlite"  # a folder that is a file
    else:
        out = blocker
    code, _, err = _run(capsys, *QUICK, "--db", str(db), "--out", str(out))
    assert code == 2 and str(blocker) in err and "Traceback" not in err
    assert blocker.read_text() == "mine"
    if where == "out":
        with ResultStore(db) as store:
            assert store.rows() == []  # nothing ran


def test_a_filtered_run_never_overwrites_the_full_table(tmp_path):
    kw = dict(db=tmp_path / "r.sqlite", suite=EvalSuite("t", (0,), 1), validate=False, progress=False,
              echo=lambda s: None, out=tmp_path / "out")
    full = run_leaderboard(env_ids=None, policies=["zero"], **{**kw, "out": None})  # fills the store cheaply
    assert full.new_episodes == len(paragym.ENVIRONMENTS)  # one zero episode per env
    run = run_leaderboard(env_ids=["Orthoglide2PRRKappa-v0"], policies=["zero"], **kw)
    md = [p for p in run.files if p.name == "LEADERBOARD.md"][0]
    assert md.parent != tmp_path / "out" and md.parent.parent == tmp_path / "out"
    assert "A partial table" in md.read_text()
    assert not (tmp_path / "out" / "LEADERBOARD.md").exists()
    assert sorted(p.name for p in md.parent.iterdir()) == ["LEADERBOARD.md", "Orthoglide2PRRKappa-v0.png",
                                                          "episodes.csv", "leaderboard.csv", "results.json.gz"]


def test_demo_and_plan_work_on_every_env_with_their_defaults_and_name_the_policy(tmp_path, capsys):
    code, out, _ = _run(capsys, "demo", "MobileTripodOdometry-v0", "--out", str(tmp_path))
    assert code == 0 and "push scenario" in out and "collision" not in out
    code, out, _ = _run(capsys, "demo", "MobileTripodOdometry-v0", "--policy", "zero", "--out", str(tmp_path))
    assert code == 0
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == ["MobileTripodOdometry-v0_push_seed0_best.png", "MobileTripodOdometry-v0_push_seed0_zero.png"]
    code, out, _ = _run(capsys, "plan", "MobileTripodOdometry-v0", "--out", str(tmp_path / "plan"))
    assert code == 0 and "correction (paper)" in out


def test_policies_lists_every_registered_ids_policies_by_the_names_the_other_commands_take(capsys):
    """``paragym validate --help`` and DAgger's messages point to ``paragym policies ENV``: it exists, for every
    registered id, and lists what ``--policy`` accepts."""
    from paragym import registry
    from paragym.baselines.policies import policies_for

    for row in registry.ROWS:
        code, out, _ = _run(capsys, "policies", row.name)
        listed = [line.split()[0] for line in out.splitlines() if line.strip()]
        assert code == 0 and listed == list(policies_for(row.id)), row.id
        assert any(line.split()[1] == "reference" for line in out.splitlines() if line.strip()), row.id


#: the ids whose demo and plan run: a task's released versions in the quick suite, its rungs among the slow tests
DEMO_IDS = [pytest.param(r, marks=[pytest.mark.slow] if r.rung is not None else [], id=r.name)
            for r in registry.ROWS if r.kinematic_as is None]


@pytest.mark.parametrize("row", DEMO_IDS)
def test_demo_and_plan_work_on_every_registered_id(row, tmp_path, capsys):
    """Every id (but a kinematic twin, whose demo and plan are its source's episodes: ``EnvRow.kinematic_as``)
    through the generic CLI, as its env page tells a new user to run it: ``demo`` with the id's
    reference on its default scenario and seed must succeed (exit 0), and ``plan`` must plan it. A table keyed
    by id once missed v1 and crashed ``paragym demo HybridSingularityFree-v1`` with a KeyError; the hybrid's
    easy rung's seed 0 draws a path whose working splits jump faster than the rate limit lets the split move,
    where the reference without its step-4 detours found no plan and both commands exited 1."""
    from paragym.baselines.tasks import bench_of

    code, out, err = _run(capsys, "demo", row.name, "--out", str(tmp_path))
    assert code == 0, out + err
    assert f"{row.id}: {row.paper_scenario} scenario" in out and "success True" in out
    assert bench_of(row.id).plan is not None
    code, out, err = _run(capsys, "plan", row.name, "--out", str(tmp_path / "plan"))
    assert code == 0 and "wrote" in out, out + err


@pytest.mark.parametrize("task", sorted({r.task for r in registry.ROWS}))
@pytest.mark.slow
def test_validate_runs_a_policy_episode_of_each_task(task, tmp_path, capsys):
    """``validate`` dispatches the same way for every id of a task (through its bench): the newest id of each."""
    row = registry.rows_of(task)[-1]
    code, out, err = _run(capsys, "validate", row.name, "--policy", "zero", "--out", str(tmp_path))
    assert code in (0, 1), err  # 1: the KF check failed, said in the report; never a traceback
    assert "wrote" in out and list(tmp_path.rglob("report.json"))


AGENTS = {  # an agent file, and what the one line must say of it
    "syntax": ("class A:\n    def __init__(self, env, seed) pass\n", ["line 2", "SyntaxError"]),
    "import": ("import paragym_no_such_module_here\n", ["line 1", "ModuleNotFoundError"]),
    "action": ("class A:\n    def __init__(self, env, seed):\n        pass\n\n    def reset(self, obs, info):\n"
               "        pass\n\n    def act(self, obs, info):\n        return 'x'\n",
               ["policy 'A'", "Orthoglide2PRRKappa-v1", "evaluation seed 0 episode 0", "action must be"]),
}


@pytest.mark.parametrize("case", sorted(AGENTS))
def test_a_broken_agent_gets_one_line_naming_it(case, tmp_path, capsys):
    """A submission's error names the file or the agent, the env and the episode, on one line (issue 38)."""
    source, said = AGENTS[case]
    agent = tmp_path / "my_agent.py"
    agent.write_text(source)
    code, _, err = _run(capsys, "leaderboard", "--no-progress", "--no-validation", "--workers", "1", "--env",
                        "Orthoglide2PRRKappa-v1", "--agent", f"{agent}:A", "--policy", "A", "--db",
                        str(tmp_path / "r.sqlite"), "--out", str(tmp_path / "o"))
    lines = [line for line in err.strip().splitlines() if not line.startswith("pybullet build")]
    assert code == 2 and len(lines) == 1, err
    assert all(s in lines[0] for s in said), lines[0]
    if case != "action":
        assert str(agent) in lines[0]


def test_a_tasks_own_option_is_its_benchs_and_refused_elsewhere(tmp_path, capsys):
    """``--dt`` is the CaPaMan bench's option (``Bench.options``), not the CLI's: another task refuses it by
    name, saying which options it takes; an option no command takes stays argparse's error."""
    from paragym.cli import main

    assert main(["plan", "Orthoglide2PRRKappa-v1", "--dt", "1", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("paragym: error: paragym/Orthoglide2PRRKappa-v1 does not take --dt 1 (its task's options for "
                   "plan: none)"), err
    with pytest.raises(SystemExit):
        main(["envs", "--dt", "1"])
    assert "unrecognized arguments: --dt 1" in capsys.readouterr().err


def test_bad_input_is_one_line_with_no_engine_banner():
    """PyBullet prints a build banner on stdout when it is imported: it is imported at its first use, so a
    command refused before any scene is built says its one line and nothing else."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "paragym.cli", "export", "Nope-v0"], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("paragym: error: unknown env id 'Nope-v0'") and done.stderr.count("\n") == 1


def test_the_leaderboards_database_goes_in_its_out_folder(tmp_path, capsys, monkeypatch):
    """Without --db the database is written in --out, never in ./results of wherever the command was run."""
    monkeypatch.chdir(tmp_path)
    assert _run(capsys, *QUICK, "--out", "elsewhere")[0] == 0
    assert (tmp_path / "elsewhere" / "paragym.sqlite").is_file()
    assert not (tmp_path / "results").exists()
