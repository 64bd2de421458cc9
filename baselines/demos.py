"""Demonstrations as Minari datasets (``paragym demos``), and behaviour cloning from them.

The reference planners make this a benchmark with an expert for every task.
:func:`record_demos` runs a policy of the leaderboard (by default the env's
reference) on seeded episodes through Minari's ``DataCollector`` and writes a
Minari dataset, the Farama standard for offline RL, into Minari's own folder
(``MINARI_DATASETS_PATH``, default ``~/.minari/datasets``), with Minari's
metadata: the env spec, the algorithm, the code's version and the reference
scores that :func:`minari.get_normalized_score` needs (the ``random`` floor's
mean return as ``ref_min_score``, the recorded policy's as ``ref_max_score``).

The episodes' reset seeds are :func:`demo_seed` (``200_000 + k``), apart
from the leaderboard's (``100_000 + ...``), so a policy cloned from the
demonstrations is ranked on scenarios it has not seen. A scenario for which
the policy's planner finds no plan (RRT + GA, in about 2 % of the CaPaMan's)
is skipped, the next seed taken, and the skipped seeds named in the
dataset's description.

A dataset that exists is never overwritten without ``force``, and ``force``
replaces only a dataset that paragym wrote (its ``author`` is ``paragym``).
"""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium as gym
import numpy as np

import paragym
from paragym import check_env_id
from paragym.baselines.policies import PolicySpec, policies_for

__all__ = ["AUTHOR", "DEMO_SEED", "dataset_id_for", "demo_seed", "record_demos", "reference_name"]

#: demonstrations start at this reset seed (the leaderboard's episodes start at 100_000)
DEMO_SEED = 200_000
#: the ``author`` field of every dataset paragym writes: what ``force`` may replace
AUTHOR = "paragym"


def demo_seed(episode: int) -> int:
    """The reset seed (and the policy's seed) of demonstration ``episode``."""
    return DEMO_SEED + int(episode)


def reference_name(env_id: str) -> str:
    """The name of ``env_id``'s reference policy (the paper's method)."""
    env_id = check_env_id(env_id)
    return next(name for name, spec in policies_for(env_id).items() if spec.kind == "reference")


def dataset_id_for(env_id: str, policy: str) -> str:
    """Minari's id of the demonstrations of ``policy`` on ``env_id``:
    ``paragym/<env name>-v<N>/<policy>-v0``."""
    return f"{check_env_id(env_id)}/{policy}-v0"


def _rollout(env: gym.Env, spec: PolicySpec, episode: int) -> float | None:
    """One seeded episode of ``spec`` on ``env`` (a DataCollector); its
    return, or None when the policy's planner finds no plan for the scenario
    (no step is taken, and Minari keeps no episode without steps)."""
    from paragym.planners.base import PlanningError

    seed = demo_seed(episode)
    policy = spec.factory(env, seed)
    obs, info = env.reset(seed=seed)
    try:
        policy.reset(obs, info)
    except PlanningError:
        return None
    total, done = 0.0, False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy.act(obs, info))
        total += float(reward)
        done = terminated or truncated
    return total


def _mean_return(env_id: str, spec: PolicySpec, episodes: int) -> float:
    env = gym.make(env_id)
    try:
        returns = [_rollout(env, spec, k) for k in range(episodes)]
        return float(np.mean([r for r in returns if r is not None]))
    finally:
        env.close()


def _progress(total: int, label: str, show: bool) -> Any:
    """A rich progress bar (or a silent stand-in) over ``total`` episodes."""
    if show:
        from rich.progress import Progress

        bar = Progress(transient=True)
        bar.start()
        return bar, bar.add_task(label, total=total)
    return None, None


def record_demos(env_id: str, episodes: int, policy: str | None = None, dataset_id: str | None = None,
                 force: bool = False, progress: bool = False) -> Any:
    """Record ``episodes`` episodes of ``policy`` (default: the env's
    reference) on ``env_id`` as a Minari dataset (module docstring); returns
    the loaded :class:`minari.MinariDataset`."""
    import minari

    env_id = check_env_id(env_id)
    if isinstance(episodes, bool) or not isinstance(episodes, int | np.integer) or episodes < 1:
        raise ValueError(f"episodes must be a positive integer; got {episodes!r}")
    specs = policies_for(env_id)
    name = reference_name(env_id) if policy is None else policy
    if name not in specs:
        raise ValueError(f"unknown policy {name!r} for {env_id}; known: {', '.join(specs)}")
    dataset_id = dataset_id_for(env_id, name) if dataset_id is None else dataset_id
    if dataset_id in minari.list_local_datasets():
        if not force:
            raise ValueError(f"dataset {dataset_id} exists; --force replaces it (or choose another --dataset-id)")
        author = minari.load_dataset(dataset_id).storage.metadata.get("author")
        if author != AUTHOR and author != {AUTHOR}:
            raise ValueError(f"dataset {dataset_id} was not written by paragym (author {author!r}): not replacing it")
        minari.delete_dataset(dataset_id)
    spec = specs[name]
    collector = minari.DataCollector(gym.make(env_id), record_infos=False)
    returns, skipped, k = [], [], 0
    bar, task = _progress(episodes, f"{name} on {env_id}", progress)
    try:
        while len(returns) < episodes:  # seeds in order; a scenario the planner cannot solve is skipped
            if len(skipped) > episodes:
                raise ValueError(f"{name} found no plan for {len(skipped)} of the demonstration scenarios")
            value = _rollout(collector, spec, k)
            if value is None:
                skipped.append(demo_seed(k))
            else:
                returns.append(value)
                if bar is not None:
                    bar.advance(task)
            k += 1
        floor = _mean_return(env_id, specs["random"], episodes)
        with warnings.catch_warnings():  # paragym has no e-mail address to give
            warnings.filterwarnings("ignore", message=".*author_email.*")
            collector.create_dataset(
                dataset_id=dataset_id, eval_env=env_id, algorithm_name=f"paragym policy {name!r}: {spec.description}",
                author=AUTHOR, ref_min_score=floor, ref_max_score=float(np.mean(returns)),
                num_episodes_average_score=episodes,
                description=(f"{episodes} episodes of {name} ({spec.kind}) on {env_id}, reset seeds "
                             f"{demo_seed(0)}-{demo_seed(k - 1)}"
                             + (f" but {skipped} (no plan found)" if skipped else "")
                             + f"; paragym {paragym.__version__}. "
                             f"ref_min_score: the random policy's mean return over reset seeds "
                             f"{demo_seed(0)}-{demo_seed(episodes - 1)}; ref_max_score: this policy's over its "
                             f"{episodes} recorded episodes. What made the actions: {spec.producer()}"),
                requirements=[f"paragym=={paragym.__version__}"])
    finally:
        if bar is not None:
            bar.stop()
        collector.close()
    return minari.load_dataset(dataset_id)
