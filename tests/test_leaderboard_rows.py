"""The leaderboard's rows do not change when its code is reorganised (issue 16, item 5).

``tests/data/leaderboard_rows.json`` holds the rows of a small run (every env,
every reference planner, the floors and one shipped model of each algorithm,
evaluation seed 0 x 2 episodes), recorded before ``run_leaderboard`` and
``train`` were split into named steps. The same run must give the same rows:
returns, lengths, successes and every metric, under the rule of ``paragym
verify`` (:func:`paragym.baselines.leaderboard.results.compare`): the
discrete outcomes exactly, the rest within the kinematic tolerance.
``python tests/test_leaderboard_rows.py --record`` rewrites the recording.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from paragym.baselines.leaderboard import EvalSuite, run_leaderboard
from paragym.baselines.leaderboard.results import TOLERANCE, compare
from paragym.baselines.store import ResultStore
from paragym.baselines.tasks import bench_of

FILE = Path(__file__).with_name("data") / "leaderboard_rows.json"
POLICIES = ["zero", "random", "ppo-seed0", "sac-seed0", "rrt-ga", "grid-dijkstra", "polynomial-detour",
            "fixed-table-a", "gradient-c", "encoder-correction", "ukf-fusion"]


#: the env ids of the recording: ids registered since add rows of their own, which the recording cannot hold
RECORDED_ENVS = ["paragym/CaPaManCollisionFree-v0", "paragym/CaPaManCollisionFree-v1",
                 "paragym/HybridSingularityFree-v0", "paragym/HybridSingularityFree-v1",
                 "paragym/MobileTripodOdometry-v0", "paragym/MobileTripodOdometry-v1", "paragym/Orthoglide2PRRKappa-v0"]


def rows(folder: Path) -> list[dict]:
    db = folder / "rows.sqlite"
    run_leaderboard(db=db, suite=EvalSuite("rows", (0,), 2), policies=POLICIES, out=None, validate=False,
                    progress=False, echo=lambda s: None, env_ids=RECORDED_ENVS)
    with ResultStore(db) as store:
        out = [{"env": r.env, "policy": r.policy, "seed": r.seed, "episode": r.episode, "return": r.episode_return,
                "length": r.length, "success": bool(r.success), "metrics": r.metrics} for r in store.rows()]
    return sorted(out, key=lambda r: (r["env"], r["policy"], r["seed"], r["episode"]))


@pytest.mark.slow
def test_the_rows_are_the_recorded_ones(tmp_path):
    want = json.loads(FILE.read_text())
    got = rows(tmp_path)
    assert [(r["env"], r["policy"], r["seed"], r["episode"]) for r in got] == \
        [(r["env"], r["policy"], r["seed"], r["episode"]) for r in want]
    rule = TOLERANCE
    for g, w in zip(got, want, strict=True):
        where = f"{g['env']} {g['policy']} episode {g['episode']}"
        found = compare(w, g, bench_of(g["env"]).exact_metrics(), rule["rtol"], rule["atol"])
        assert found.verdict != "diverged", f"{where}: {found.differences}"


if __name__ == "__main__" and "--record" in sys.argv:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        FILE.write_text(json.dumps(rows(Path(tmp)), indent=1))
    print(f"wrote {FILE}")
