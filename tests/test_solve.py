"""When a task counts as solved (paragym.baselines.solve), and the check that stops training."""

from __future__ import annotations

import dataclasses

import pytest

from paragym.baselines.policies import policies_for
from paragym.baselines.solve import SolveCheck, stop_when_solved
from paragym.baselines.tasks import Target, bench_of, missing
from paragym.registry import ROWS, newest


def test_every_task_states_targets_its_bench_can_check():
    for row in ROWS:
        bench = bench_of(row.id)
        assert bench.solved, f"{row.id}: its task states no targets"
        assert missing(bench, row.id) == []
    bad = dataclasses.replace(bench_of("paragym/Orthoglide2PRRKappa-v1"),
                              solved=(Target("mean_kappa", -1, against="no-such-policy"), Target("nope", 1, 0.5)))
    said = " ".join(missing(bad, "paragym/Orthoglide2PRRKappa-v1"))
    assert "'no-such-policy'" in said and "'nope'" in said


def test_a_target_has_one_bound_and_a_direction():
    with pytest.raises(ValueError, match="direction"):
        Target("success", 0, 0.5)
    with pytest.raises(ValueError, match="either a value or a policy"):
        Target("success", 1, 0.5, against="zero")
    with pytest.raises(ValueError, match="either a value or a policy"):
        Target("success", 1)
    reach, beat = Target("success", 1, 0.8), Target("final_unit_error_cm", -1, against="zero")
    assert reach.met(0.8, 0.8) and not reach.met(0.79, 0.8)
    assert beat.met(4.9, 5.0) and not beat.met(5.0, 5.0)  # equalling the floor is not beating it
    assert reach.describe() == "success >= 0.8" and beat.describe() == "final_unit_error_cm < zero's"


def test_doing_nothing_never_solves_a_task_and_the_reference_does():
    """The tripod's floor (raw odometry, the zero action) against itself is not solved; the orthoglide's
    reference meets its own targets (within 1 % of its kappa, and it completes the path)."""
    check = SolveCheck("paragym/MobileTripodOdometry-v1", episodes=2)
    env = check.env
    zero = policies_for(check.env_id)["zero"].factory(env, 0)
    solved, figures = check.check(zero)
    assert not solved and figures["final_unit_error_cm"] == pytest.approx(check.bounds[0])
    check.close()
    check = SolveCheck("paragym/Orthoglide2PRRKappa-v1", episodes=2)
    specs = policies_for(check.env_id)
    assert check.check(specs["gradient-c"].factory(check.env, 0))[0]
    assert not check.check(specs["zero"].factory(check.env, 0))[0]
    check.close()


def test_a_check_refuses_what_it_cannot_measure():
    with pytest.raises(ValueError, match="episodes"):
        SolveCheck("paragym/Orthoglide2PRRKappa-v1", episodes=0)
    with pytest.raises(ValueError, match="no policy 'nobody'"):
        SolveCheck("paragym/Orthoglide2PRRKappa-v1", episodes=1, targets=(Target("mean_kappa", -1, against="nobody"),))


def test_training_stops_when_solved_and_when_out_of_time(tmp_path):
    """A target every policy meets stops learning at the first check; an unmet one at the budget. The
    checks' own time is not counted as learning."""
    from paragym.baselines.training import train

    env_id = newest()[2]  # the orthoglide: cheap episodes
    easy = SolveCheck(env_id, episodes=1, targets=(Target("success", +1, 0.0),))
    points = []
    result = train(env_id, "ppo", 0, timesteps=200_000, models_dir=tmp_path, progress_bar=False, force=True,
                   callbacks=[stop_when_solved(easy, 0.5, 600, points)])
    assert len(points) == 1 and points[0].solved and points[0].seconds >= 0.5
    assert result.model.num_timesteps < 200_000
    hard = SolveCheck(env_id, episodes=1, targets=(Target("success", +1, 1.5),))
    points = []
    train(env_id, "ppo", 0, timesteps=200_000, models_dir=tmp_path, progress_bar=False, force=True,
          callbacks=[stop_when_solved(hard, 0.5, 2.0, points)])
    assert not any(p.solved for p in points) and 2.0 <= points[-1].seconds < 4.0
    assert all(b.seconds - a.seconds >= 0.5 or b is points[-1] for a, b in zip(points, points[1:], strict=False))
