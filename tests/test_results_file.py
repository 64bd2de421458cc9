"""Results anyone can check: the results file a run writes, its raw episodes, and ``paragym verify``."""

from __future__ import annotations

import csv
import gzip
import json
import subprocess
import sys
from pathlib import Path

import pytest

from paragym.baselines.leaderboard import EvalSuite, run_leaderboard
from paragym.baselines.leaderboard.results import _digest, read_results, verify

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


def test_the_results_file_describes_its_run(written: Path) -> None:
    data = read_results(written)
    assert data["written_by"]["paragym"] and data["written_by"]["packages"]["gymnasium"]
    assert data["written_by"]["command"].startswith("paragym leaderboard")
    assert data["suite"]["seeds"] == [0] and data["envs"][ORTHO]["max_episode_steps"]
    assert {p["policy"] for p in data["policies"]} == {"gradient-c", "zero", "random"}
    assert all(p["producer"] for p in data["policies"])
    assert len(data["episodes"]) == 6 and len(data["dynamic"]) == 3
    episodes = list(csv.DictReader((written.parent / "episodes.csv").open()))
    assert len(episodes) == 6 and {"reset_seed", "return", "success", "producer_sha256"} <= set(episodes[0])
    returns = sorted(float(e["return"]) for e in episodes)
    assert returns == sorted(e["return"] for e in data["episodes"])  # to the last bit
    assert str(written.parent.parent) not in written.parent.joinpath("LEADERBOARD.md").read_text()


def test_another_process_reproduces_it(written: Path) -> None:
    done = _run_verify(written, "--sample", "all", "--dynamic", "1")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "7 of 7 episodes reproduced" in done.stdout and "VERIFIED" in done.stdout


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


def test_the_committed_results_file_reproduces() -> None:
    """A sample of the committed leaderboard's episodes, re-run here: the published numbers are this code's."""
    committed = Path(__file__).parents[1] / "leaderboard" / "results.json.gz"
    result = verify(committed, sample=3, seed=2, echo=lambda s: None)
    assert result.ok, result.problems
