"""Results anyone can check: the results file a run writes, its raw episodes, and ``paragym verify``."""

from __future__ import annotations

import csv
import gzip
import json
import subprocess
import sys
from pathlib import Path

import pytest

from paragym import machine
from paragym.baselines.leaderboard import EvalSuite, run_leaderboard
from paragym.baselines.leaderboard.results import (
    TOLERANCE,
    _digest,
    compare,
    describe,
    read_results,
    tolerance_of,
    verify,
)
from paragym.baselines.leaderboard.suite import dynamic_engines
from paragym.baselines.store import ResultStore

ORTHO = "paragym/Orthoglide2PRRKappa-v1"


@pytest.fixture(scope="module")
def written(shared_folder) -> Path:
    """A run of three policies, two episodes each and the paper case in dynamic fidelity (run once a session:
    the other xdist worker finds it written)."""
    with shared_folder("results-run") as folder:
        done = sorted((folder / "out").rglob("results.json.gz"))  # a filtered run writes under out/partial-...
        if not done:
            run = run_leaderboard(folder / "db.sqlite", EvalSuite("test", (0,), 2, (("paper", 0),)), env_ids=[ORTHO],
                            policies=["gradient-c", "zero", "random"], out=folder / "out", progress=False,
                            echo=lambda s: None, command="paragym leaderboard --env Orthoglide2PRRKappa-v1")
            done = [p for p in run.files if p.name == "results.json.gz"]
        return done[0]


def _run_verify(path: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "paragym.cli", "verify", str(path), *extra], capture_output=True,
                          text=True, timeout=300)


@pytest.mark.slow
def test_the_results_file_describes_its_run(written: Path) -> None:
    data = read_results(written)
    assert data["written_by"]["paragym"] and data["written_by"]["packages"]["gymnasium"]
    assert data["written_by"]["command"].startswith("paragym leaderboard")
    facts = data["written_by"]["machine"]  # what the numbers depended on, beside the package versions
    assert facts["cpu"]["model"] and facts["cpu"]["isa"]["found"] and facts["blas"][0]["architecture"]
    assert facts["numba"]["cpu_name"] and facts["libc"] is not None
    assert data["tolerance"]["kinematic"] == TOLERANCE and data["tolerance"]["measured_by"]
    assert data["tolerance"]["dynamic"][ORTHO] == tolerance_of(ORTHO, "dynamic")
    assert data["suite"]["seeds"] == [0] and data["envs"][ORTHO]["max_episode_steps"]
    assert {p["policy"] for p in data["policies"]} == {"gradient-c", "zero", "random"}
    assert all(p["producer"] for p in data["policies"])
    assert len(data["episodes"]) == 6 and len(data["dynamic"]) == 3 * len(dynamic_engines(ORTHO))  # per engine
    episodes = list(csv.DictReader((written.parent / "episodes.csv").open()))
    assert len(episodes) == 6 and {"reset_seed", "return", "success", "producer_sha256"} <= set(episodes[0])
    returns = sorted(float(e["return"]) for e in episodes)
    assert returns == sorted(e["return"] for e in data["episodes"])  # to the last bit
    assert str(written.parent.parent) not in written.parent.joinpath("LEADERBOARD.md").read_text()


def test_another_process_reproduces_it(written: Path) -> None:
    done = _run_verify(written, "--sample", "all", "--dynamic", "1")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "7 of 7 episodes reproduced: 7 identical" in done.stdout and "VERIFIED" in done.stdout
    assert done.stdout.count("  identical ") == 7  # each episode on a line


def _tamper(path: Path, out: Path, fix_digest: bool) -> Path:
    data = json.loads(gzip.decompress(path.read_bytes()))
    data["episodes"][0]["return"] += 1.0  # a better score than was earned
    if fix_digest:
        data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})
    out.write_bytes(gzip.compress(json.dumps(data).encode()))
    return out


def test_a_tampered_file_is_reported(written: Path, tmp_path: Path) -> None:
    edited = _tamper(written, tmp_path / "edited.json.gz", fix_digest=False)
    result = verify(edited, sample=1, echo=lambda s: None)
    assert not result.intact and not result.ok
    done = _run_verify(edited, "--sample", "1")
    assert done.returncode == 1 and "DOES NOT MATCH" in done.stdout and "NOT VERIFIED" in done.stdout
    # a digest made to match: the re-run episode gives it away
    forged = verify(_tamper(written, tmp_path / "forged.json.gz", fix_digest=True), sample=None,
                    echo=lambda s: None)
    assert forged.intact and not forged.ok
    assert any("does not reproduce" in p and "return" in p for p in forged.problems), forged.problems


def test_a_row_of_another_producer_is_not_compared(written: Path, tmp_path: Path) -> None:
    data = json.loads(gzip.decompress(written.read_bytes()))
    data["policies"][0]["producer"] = json.dumps({"policy": "someone.else", "params": {}})
    data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})
    path = tmp_path / "other.json"
    path.write_text(json.dumps(data))
    result = verify(path, sample=None, echo=lambda s: None)
    assert not result.ok and any("producer differs" in p for p in result.problems)


def test_compare_tells_identical_within_tolerance_and_diverged() -> None:
    stored = {"return": 5.0, "length": 40, "success": True, "metrics": {"min_clearance_mm": 14.0, "collision": 0.0}}

    def again(**change):
        out = {k: v for k, v in stored.items() if k != "metrics"} | {"metrics": dict(stored["metrics"])}
        for k, v in change.items():
            (out["metrics"] if k in stored["metrics"] else out)[k] = v
        return out

    exact = ("collision",)
    assert compare(stored, again(), exact, 1e-6, 1e-9).verdict == "identical"
    near = compare(stored, again(**{"return": 5.0 * (1 + 2e-9)}), exact, 1e-6, 1e-9)
    assert near.verdict == "within tolerance" and near.worst == "return" and 1e-9 < near.deviation < 3e-9
    for change in ({"return": 5.1}, {"length": 41}, {"success": False}, {"collision": 1e-12},
                   {"min_clearance_mm": 14.1}):
        assert compare(stored, again(**change), exact, 1e-6, 1e-9).verdict == "diverged", change


def test_a_file_cannot_loosen_its_own_tolerance(written: Path, tmp_path: Path) -> None:
    data = json.loads(gzip.decompress(written.read_bytes()))
    data["tolerance"]["kinematic"] = {"rtol": 1.0, "atol": 1.0}
    data["episodes"][0]["return"] *= 1.01  # 1 %: inside the file's tolerance, not inside paragym's
    data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})
    path = tmp_path / "loose.json"
    path.write_text(json.dumps(data))
    result = verify(path, sample=None, echo=lambda s: None)
    assert all(rule == TOLERANCE for (_, fidelity), rule in result.tolerance.items() if fidelity == "kinematic")
    assert not result.ok and result.count("diverged") == 1


@pytest.mark.parametrize("content", [b"\x89PNG\r\n\x1a\n\x00\x00", b"name,return\n", b'{"a": 1}', b"\x1f\x8bnot gzip"])
def test_a_file_that_is_not_a_results_file_gets_one_line(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "thing.bin"
    path.write_bytes(content)
    done = _run_verify(path)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert str(path) in lines[0] and "not a paragym results file" in lines[0]
    assert "Expecting value" not in lines[0] and "codec" not in lines[0]


@pytest.mark.parametrize("cpu", ["host", "older-x86-64"])
@pytest.mark.slow
def test_the_committed_results_file_reproduces_on_another_cpu(cpu: str) -> None:
    """A sample of the committed leaderboard's episodes, re-run in a new process as this machine computes and
    as an older x86-64 would (another BLAS kernel, numba's generic target, numpy without its SIMD loops, libm
    without its FMA variants: :data:`paragym.machine.SIMULATED`): every one reproduces under ``verify``'s
    rule, and the episodes whose numbers paragym computes itself are identical."""
    committed = Path(__file__).parents[1] / "leaderboard" / "results.json.gz"
    done = subprocess.run([sys.executable, "-m", "paragym.cli", "verify", str(committed), "--sample", "4", "--seed",
                           "2"], capture_output=True, text=True, timeout=900, env=machine.simulated_environment(cpu))
    assert done.returncode == 0 and "VERIFIED" in done.stdout, done.stdout + done.stderr[-2000:]
    assert "4 of 4 episodes reproduced" in done.stdout
    if cpu == "host":
        assert "4 identical" in done.stdout, done.stdout


def test_the_verdict_names_both_machines(written: Path) -> None:
    text = describe(verify(written, sample=1, echo=lambda s: None))
    assert "written on" in text and "re-run on" in text and "the rule:" in text


def test_a_fresh_database_resumes_from_the_results_file(written: Path, tmp_path: Path) -> None:
    """A fresh checkout has the committed results file but no database: ``--resume-from`` takes the file's rows,
    so the same run runs nothing again and writes the same episodes; an edited file is refused before a row is
    taken."""
    seen: list[str] = []
    kw = dict(suite=EvalSuite("test", (0,), 2, (("paper", 0),)), env_ids=[ORTHO],
              policies=["gradient-c", "zero", "random"], out=tmp_path / "out", progress=False)
    run = run_leaderboard(tmp_path / "fresh.sqlite", resume_from=written, echo=seen.append, **kw)
    dynamic = 3 * len(dynamic_engines(ORTHO))  # each policy's paper case in each engine
    assert (run.new_episodes, run.skipped_episodes, run.new_dynamic, run.skipped_dynamic) == (0, 6, 0, dynamic)
    assert any(f"took 6 episodes and {dynamic} dynamic episodes" in line for line in seen)
    again = read_results(next((tmp_path / "out").rglob("results.json.gz")))
    assert again["episodes"] == read_results(written)["episodes"]
    assert again["dynamic"] == read_results(written)["dynamic"]
    with pytest.raises(ValueError, match="digest does not match"):
        run_leaderboard(tmp_path / "other.sqlite", resume_from=_tamper(written, tmp_path / "e.json.gz", False),
                        echo=seen.append, **kw)
    assert not (tmp_path / "other.sqlite").exists() or not ResultStore(tmp_path / "other.sqlite").rows()
