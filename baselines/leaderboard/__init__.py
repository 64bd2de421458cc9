"""The leaderboard: every registered env x every policy, on fixed seeds.

Evaluation suite (:data:`FULL`): evaluation seeds 0-4, ten episodes each,
50 episodes per (env, policy), every env in its default (random) scenario
and kinematic fidelity. Episode ``k`` of seed ``s`` resets the env with
``episode_seed(s, k) = 100_000 + 1_000 s + k`` and builds its policy with
that same seed, so an episode's numbers depend on nothing else (not on the
executor, the worker or the order). The training runs never see these
seeds (PPO/SAC train on seeds 0-2 and evaluate on 10_000+).
:data:`QUICK` is seed 0, three episodes.

Per (env, policy) the summary holds the success rate, the return's mean
and standard deviation, the task's own metrics (its bench's, each the
mean over episodes of a per-episode value) and the wall time per episode
(reset, planning and steps). Ranking: success rate, then the task's primary
metric (its bench's :attr:`~paragym.baselines.tasks.Bench.primary`). Where a
task's bench has a ``validated_plan``, the reference's plan on the paper's
scenario is also executed in dynamic fidelity and judged by
:mod:`paragym.validation`; its verdict is part of the row.

Executors: ``local`` (this process), ``workers`` (a process pool on this
machine) and ``ray`` (Ray tasks, local or on a cluster). All of them hand
each finished episode back to this process, which commits it to the
:class:`~paragym.baselines.store.ResultStore` at once.

The modules, one concern each: :mod:`.suite` (which episodes),
:mod:`.evaluate` (one episode), :mod:`.executors` (where they run),
:mod:`.reaper`, :mod:`.summary`, :mod:`.render` (the reports) and
:mod:`.run` (:func:`run_leaderboard`); the rows are stored by
:mod:`paragym.baselines.store`.
"""

from paragym.baselines.leaderboard.evaluate import evaluate_dynamic, evaluate_episode
from paragym.baselines.leaderboard.executors import EXECUTORS, die_with_parent
from paragym.baselines.leaderboard.render import markdown, terminal_table, write_csv
from paragym.baselines.leaderboard.run import LeaderboardInterrupted, LeaderboardRun, run_leaderboard
from paragym.baselines.leaderboard.suite import FULL, QUICK, EvalSuite, dynamic_producer, episode_seed
from paragym.baselines.leaderboard.summary import Summary, summarise
from paragym.baselines.tasks import dynamic_kwargs

__all__ = ["EXECUTORS", "FULL", "QUICK", "EvalSuite", "LeaderboardInterrupted", "LeaderboardRun", "Summary",
           "die_with_parent", "dynamic_kwargs", "dynamic_producer", "episode_seed", "evaluate_dynamic",
           "evaluate_episode", "markdown", "run_leaderboard", "summarise", "terminal_table", "write_csv"]
