"""Every number says how sure it is: intervals in the leaderboard's summaries, tables and pictures."""

from __future__ import annotations

import math

import pytest

from paragym.baselines.leaderboard import QUICK, EvalSuite, markdown, summarise, terminal_table
from paragym.baselines.leaderboard.render import smoke_note
from paragym.baselines.stats import mean_ci, wilson
from paragym.baselines.store import EpisodeRow

ENV = "paragym/Orthoglide2PRRKappa-v0"


def _rows(policy: str, successes: list[bool], returns: list[float]) -> list[EpisodeRow]:
    return [EpisodeRow(ENV, policy, 0, k, "user", r, 10, ok, {"mean_kappa": 3.0 - r / 10, "max_kappa": 4.0,
                                                                "tracking_error_mm": 0.0, "max_tracking_error_mm": 0.0,
                                                                "path_completed": 1.0}, 0.1)
            for k, (ok, r) in enumerate(zip(successes, returns, strict=True))]


def test_wilson_interval_matches_the_formula() -> None:
    for k, n in ((0, 3), (3, 3), (48, 50), (25, 50)):
        p, z = k / n, 1.959963984540054
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
        assert wilson(k, n) == pytest.approx((centre - half, centre + half), abs=1e-9)
    assert wilson(3, 3)[0] < 0.5  # three lucky episodes say little


def test_a_lucky_three_episode_agent_is_not_separable_from_a_fifty_episode_one() -> None:
    lucky = _rows("lucky", [True] * 3, [4.9, 4.1, 4.6])  # 3 of 3, from the same returns as steady's
    steady = _rows("steady", [True] * 48 + [False] * 2, [4.0 + 0.01 * k for k in range(50)])
    (ss,) = summarise(lucky + steady).values()
    assert [s.policy for s in ss] == ["lucky", "steady"]  # the point estimates put it first ...
    assert ss[1].separable is False  # ... but the table must not say it is ahead
    table = terminal_table(ss)
    assert "[0.44, 1.00]" in table and " no" in table
    poor = _rows("poor", [False] * 50, [1.0] * 50)
    (ss,) = summarise(steady + poor).values()
    assert ss[1].policy == "poor" and ss[1].separable is True


def test_every_table_shows_intervals_and_a_quick_one_says_it_is_a_smoke_test() -> None:
    rows = _rows("a", [True, False, True], [1.0, 2.0, 3.0]) + _rows("b", [False] * 3, [0.0, 0.5, 1.0])
    summaries = summarise(rows)
    (ss,) = summaries.values()
    assert ss[0].return_ci == pytest.approx((2.0 - 4.302652729911275 / math.sqrt(3), 2.0 + 4.302652729911275 /
                                             math.sqrt(3)))  # Student's t, s = 1
    assert mean_ci([1.0]) != mean_ci([1.0])  # nan: one episode has no interval
    quick = markdown(summaries, QUICK, {}, "# header\n\n" + smoke_note(QUICK))
    assert "success [95% CI]" in quick and "return [95% CI]" in quick and "apart from #1" in quick
    assert "A smoke test, not a ranking" in quick
    assert not smoke_note(EvalSuite("full", (0, 1, 2, 3, 4), 10))
