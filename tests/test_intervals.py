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


def test_the_noise_floor_is_the_least_drop_the_tables_can_resolve() -> None:
    from paragym.baselines.stats import ahead, resolvable_drop

    for k, n in ((50, 50), (25, 50), (49, 50), (250, 250)):
        m = round(resolvable_drop(k, n) * n)
        assert ahead(wilson(k, n), wilson(k - m, n), +1)  # that drop is apart ...
        assert not ahead(wilson(k, n), wilson(k - m + 1, n), +1)  # ... and one success less is not
    assert resolvable_drop(50, 50) == pytest.approx(0.16)
    assert resolvable_drop(250, 250) < resolvable_drop(50, 50) / 3  # more episodes buy a finer floor
    assert resolvable_drop(3, 3) is None and resolvable_drop(0, 50) is None  # nothing can be apart from these


def test_every_table_and_the_csv_carry_the_noise_floor(tmp_path) -> None:
    from paragym.baselines.leaderboard import write_csv
    from paragym.baselines.leaderboard.summary import noise_floor
    from paragym.baselines.stats import half_width

    steady = _rows("steady", [True] * 50, [4.0 + 0.01 * k for k in range(50)])
    close = _rows("close", [True] * 45 + [False] * 5, [3.9 + 0.02 * k for k in range(50)])
    other = [EpisodeRow(**{**r.__dict__, "env": "paragym/Orthoglide2PRRKappa-v1"}) for r in steady]
    summaries = summarise(steady + close + other)
    (ss, one) = summaries.values()
    floor = noise_floor(ss)
    assert floor.episodes == 50 and floor.success_drop == pytest.approx(0.16)
    assert floor.metric == "mean kappa"
    assert floor.metric_gap == pytest.approx(half_width(ss[0].primary_ci) + half_width(ss[1].primary_ci))
    assert ss[1].separable is False  # 0.90 is within 0.16 of 1.00, and the kappas overlap
    assert noise_floor(one).metric_gap is None  # a table of one policy has nothing to compare with
    md = markdown(summaries, QUICK, {}, "# header")
    assert md.count("**Noise floor** (50 episodes per policy)") == md.count("\n## `") == 2
    assert "success rate at least 0.16 below the leader's 1.00" in md and "--episodes N" in md
    lines = write_csv(summaries, tmp_path / "board.csv").read_text().splitlines()
    header = lines[0].split(",")
    cells = [dict(zip(header, line.split(","), strict=False)) for line in lines[1:3]]
    assert {c["noise_floor_success_drop"] for c in cells} == {"0.1600"}
    assert {c["noise_floor_metric"] for c in cells} == {"mean kappa"}
    assert float(cells[0]["noise_floor_metric_gap"]) == pytest.approx(floor.metric_gap, rel=1e-5)


def test_more_episodes_per_seed_buy_a_finer_floor_and_say_so(tmp_path, capsys) -> None:
    from paragym.baselines.leaderboard import FULL
    from paragym.cli import main

    assert len(FULL.with_episodes(20).keys()) == 100 and not FULL.with_episodes(20).smoke
    assert FULL.with_episodes(2).smoke and QUICK.smoke and not FULL.smoke
    assert FULL.with_episodes(20).options() == " --episodes 20" and QUICK.options() == " --quick"
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="episodes must be a positive integer"):
            FULL.with_episodes(bad)
    assert main(["leaderboard", "--episodes", "0", "--db", str(tmp_path / "x.sqlite")]) == 2
    assert "episodes must be a positive integer" in capsys.readouterr().err
    out = tmp_path / "out"
    assert main(["leaderboard", "--quick", "--episodes", "4", "--env", ENV, "--policy", "zero", "--policy", "random",
                 "--db", str(tmp_path / "q.sqlite"), "--out", str(out), "--no-validation", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "Noise floor (4 episodes per policy)" in printed
    md = next(out.rglob("LEADERBOARD.md")).read_text()
    assert "`paragym leaderboard --quick --episodes 4`" in md and "seeds 0 x 4 episodes per policy" in md
    assert "**Noise floor** (4 episodes per policy)" in md and "A smoke test, not a ranking" in md
