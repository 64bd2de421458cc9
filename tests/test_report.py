"""``paragym report``: learning curves with bootstrap intervals and rliable's aggregates (issue 17)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rliable")

from paragym.baselines.report import bootstrap_mean_ci, latest_versions, normalized_scores, write_report  # noqa: E402
from paragym.baselines.store import EpisodeRow, ResultStore  # noqa: E402


def test_bootstrap_interval_holds_the_mean_and_narrows_with_agreement():
    rng = np.random.default_rng(0)
    spread = np.array([[0.0, 1.0], [1.0, 2.0], [2.0, 6.0]])
    mean, low, high = bootstrap_mean_ci(spread, rng)
    np.testing.assert_allclose(mean, [1.0, 3.0])
    assert np.all(low <= mean) and np.all(mean <= high) and np.all(high - low > 0.5)
    same = np.tile([[4.0, 5.0]], (3, 1))
    _, low, high = bootstrap_mean_ci(same, rng)
    np.testing.assert_allclose(low, [4.0, 5.0])
    np.testing.assert_allclose(high, [4.0, 5.0])


def test_latest_versions_pick_the_newest_version_of_each_task():
    latest = latest_versions()
    assert "paragym/CaPaManCollisionFree-v1" in latest and "paragym/CaPaManCollisionFree-v0" not in latest
    assert "paragym/HybridSingularityFree-v2" in latest and "paragym/HybridSingularityFree-v1" not in latest
    assert "paragym/MobileTripodOdometry-v3" in latest and "paragym/MobileTripodOdometry-v2" not in latest
    assert "paragym/Orthoglide2PRRKappa-v2" in latest and "paragym/Orthoglide2PRRKappa-v1" not in latest
    assert len(latest) == 4


def test_scores_are_normalised_between_the_floor_and_the_reference(tmp_path: Path):
    """Reference 10, floors 0 (zero) and -5 (random): a learned return of 5
    scores 0.5, one of 0 scores 0. Rows of a policy the env does not have, or
    of another producer, are left out."""
    from paragym.baselines.policies import policies_for

    env = "paragym/HybridSingularityFree-v0"
    specs = policies_for(env)
    returns = {"polynomial-detour": 10.0, "zero": 0.0, "random": -5.0, "ppo-seed0": 5.0, "ppo-seed1": 0.0}
    with ResultStore(tmp_path / "r.sqlite") as store:
        for name, value in returns.items():
            for k in range(2):
                store.add(EpisodeRow(env, name, 0, k, specs[name].kind, value + (k - 0.5), 10, True,
                                     producer=specs[name].producer()))
        store.add(EpisodeRow(env, "ppo-seed0", 0, 9, "learned", -100.0, 10, True, producer="an older model"))
    scores, tasks = normalized_scores(tmp_path / "r.sqlite", [env])
    assert tasks == [env]
    np.testing.assert_allclose(scores["ppo"][:, 0], [0.5, 0.0])


@pytest.mark.slow
def test_report_writes_curves_of_the_shipped_models(tmp_path: Path):
    page = write_report(tmp_path / "rep", None)
    text = page.read_text()
    assert "## `paragym/HybridSingularityFree-v0`" in text and "| PPO | 3 |" in text
    assert (tmp_path / "rep" / "curves-HybridSingularityFree-v0.png").stat().st_size > 10_000
    with pytest.raises(ValueError, match="no leaderboard database"):
        write_report(tmp_path / "rep", tmp_path / "missing.sqlite")


def test_the_report_says_what_it_rests_on(tmp_path: Path):
    """A report from a quick database says it is a smoke test; the default folder is not the committed report."""
    from paragym.baselines.policies import policies_for
    from paragym.baselines.report import evidence
    from paragym.cli import build_parser

    env = "paragym/HybridSingularityFree-v0"
    specs = policies_for(env)
    with ResultStore(tmp_path / "quick.sqlite") as store:
        for name in ("polynomial-detour", "zero"):
            for k in range(3):
                store.add(EpisodeRow(env, name, 0, k, specs[name].kind, 1.0, 10, True,
                                     producer=specs[name].producer()))
    text = evidence(tmp_path / "quick.sqlite", [env])
    assert "rest on 3 episodes per policy" in text and "seeds 0" in text and "smoke test, not a ranking" in text
    assert str(tmp_path) not in text
    assert build_parser().parse_args(["report"]).out != "report"
