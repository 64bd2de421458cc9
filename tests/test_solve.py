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
    assert reach.met([0.8]) and reach.met([0.7, 0.9]) and not reach.met([0.79])
    assert beat.met([4.9, 4.85, 4.9, 4.88], [5.0, 5.0, 5.0, 5.0])
    assert not beat.met([5.0, 5.0], [5.0, 5.0])  # equalling the floor is not beating it
    assert not beat.met([9.0, 10.4], [10.0, 10.0])  # better on the mean, by chance: the interval reaches past 0
    assert not beat.met([4.0], [5.0])  # one episode has no interval
    assert reach.describe() == "success >= 0.8"
    assert beat.describe() == "final_unit_error_cm < zero's (paired, 95 %)"


def test_a_mean_better_than_the_floor_by_one_episode_does_not_solve_the_task():
    """The tripod's PPO had 'solved' its task by a mean 0.01 cm below raw odometry's over 20 episodes: a policy
    that plays the reference on the first episode and does nothing on the others has a better mean than doing
    nothing, and is not better than it episode by episode."""
    check = SolveCheck("paragym/MobileTripodOdometry-v1", episodes=4)
    specs = policies_for(check.env_id)
    reference = bench_of(check.env_id).reference

    class OnceThenNothing:
        def __init__(self) -> None:
            self.episode = -1

        def reset(self, obs, info):
            self.episode += 1
            self.now = specs[reference if self.episode == 0 else "zero"].factory(check.env, check.seeds[self.episode])
            self.now.reset(obs, info)

        def act(self, obs, info):
            return self.now.act(obs, info)

    solved, figures = check.check(OnceThenNothing())
    assert figures["final_unit_error_cm"] < check.bounds[0]  # the mean alone would call it solved
    assert not solved
    check.close()


def test_doing_nothing_never_solves_a_task_and_the_reference_does():
    """The tripod's floor (raw odometry, the zero action) against itself is not solved; the orthoglide's
    reference meets its own targets (within 1 % of its kappa, and it completes the path)."""
    check = SolveCheck("paragym/MobileTripodOdometry-v1", episodes=2)
    env = check.env
    zero = policies_for(check.env_id)["zero"].factory(env, 0)
    solved, figures = check.check(zero)
    assert not solved and figures["final_unit_error_cm"] == pytest.approx(check.bounds[0])
    check.close()
    check = SolveCheck("paragym/Orthoglide2PRRKappa-v1", episodes=3)
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
    result = train(env_id, "ppo", 0, timesteps=200_000, models_dir=tmp_path, progress_bar=False, force=True,
                   callbacks=[stop_when_solved(hard, 0.5, 2.0, points)])
    # the budget ended it (not the timesteps), at its first check past 2 s of learning
    assert not any(p.solved for p in points) and points[-1].seconds >= 2.0 and points[-2].seconds < 2.0
    assert result.model.num_timesteps < 200_000
    assert all(b.seconds - a.seconds >= 0.5 or b is points[-1] for a, b in zip(points, points[1:], strict=False))
