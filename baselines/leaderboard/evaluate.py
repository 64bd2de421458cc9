"""One episode of the leaderboard, in whatever process the executor chooses: kinematic or dynamic."""

from __future__ import annotations

import time
from typing import Any

import gymnasium as gym

from paragym import registry
from paragym.baselines.leaderboard.suite import dynamic_producer, engine_of_job, episode_seed
from paragym.baselines.policies import PolicySpec
from paragym.baselines.store import DynamicRow, EpisodeRow, ValidationRow
from paragym.baselines.tasks import bench_of, dynamic_kwargs, tightest
from paragym.rollout import run_episode

__all__ = ["evaluate_dynamic", "evaluate_episode", "evaluate_job", "evaluate_validation", "run_dynamic"]

_ENVS: dict[str, gym.Env] = {}


def _env(env_id: str) -> gym.Env:
    """One env per id per process, kept: resets re-seed it completely. The
    leaderboard ranks v0 beside v1 on purpose, so Gymnasium's warning that a
    newer version exists is not repeated for every worker."""
    if env_id not in _ENVS:
        import warnings

        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*is out of date.*")
            _ENVS[env_id] = gym.make(env_id)
    return _ENVS[env_id]


def evaluate_episode(spec: PolicySpec, seed: int, episode: int, producer: str | None = None) -> EpisodeRow:
    """Run episode ``episode`` of evaluation seed ``seed`` of ``spec`` on its
    env and measure it; the row records ``producer`` (default: the spec's).
    A planner that finds no plan (PlanningError) leaves the robot standing
    still for the episode, which is then scored as it goes (metric
    ``policy_failed`` = 1)."""
    from paragym.baselines.simple import ZeroPolicy
    from paragym.planners.base import PlanningError

    env = _env(spec.env_id)
    s = episode_seed(seed, episode)
    t0 = time.perf_counter()
    policy = spec.factory(env, s)
    failed = 0.0
    try:
        ep = run_episode(env, policy, seed=s)
    except PlanningError:
        failed = 1.0
        ep = run_episode(env, ZeroPolicy(env.action_space), seed=s)
    except (ValueError, TypeError) as exc:  # an action the env refuses, a policy that breaks: say whose and where
        raise ValueError(f"policy {spec.name!r} on {spec.env_id}, evaluation seed {seed} episode {episode} (reset "
                         f"seed {s}): {exc}") from exc
    wall = time.perf_counter() - t0
    metrics = bench_of(spec.env_id).metrics(ep)
    metrics["policy_failed"] = failed
    return EpisodeRow(spec.env_id, spec.name, seed, episode, spec.kind, ep.episode_return, len(ep.actions),
                      ep.success, metrics, wall, producer=spec.producer() if producer is None else producer)


def run_dynamic(spec: PolicySpec, scenario: str, seed: int, kwargs: dict[str, Any]) -> tuple[Any, float]:
    """Run ``spec``'s episode of ``scenario`` ("paper": the env's paper case) from reset seed ``seed`` in the
    env made with ``kwargs`` (a dynamic fidelity's: :func:`dynamic_kwargs`, or other physics settings), and
    validate what it executed against what it commanded (:func:`paragym.validation.episode.validate_episode`,
    its sensors drawn from ``seed``). A planner that finds no plan stands still, as in :func:`evaluate_episode`.
    Returns the validation and 1.0 where the policy failed so (else 0.0)."""
    import warnings

    from paragym.baselines.simple import ZeroPolicy
    from paragym.planners.base import PlanningError
    from paragym.validation.episode import validate_episode

    arg = registry.row(spec.env_id).paper_scenario if scenario == "paper" else scenario
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*is out of date.*")
        env = gym.make(spec.env_id, scenario=arg, **kwargs)
    try:
        try:
            return validate_episode(env, spec.factory(env, seed), seed=seed, sensor_seed=seed), 0.0
        except PlanningError:
            return validate_episode(env, ZeroPolicy(env.action_space), seed=seed, sensor_seed=seed), 1.0
        except (ValueError, TypeError) as exc:
            raise ValueError(f"policy {spec.name!r} on {spec.env_id}, dynamic fidelity, {scenario} scenario, reset "
                             f"seed {seed}: {exc}") from exc
    finally:
        env.close()


def evaluate_dynamic(spec: PolicySpec, scenario: str, seed: int, producer: str | None = None,
                     engine: str = "pybullet") -> DynamicRow:
    """Run ``spec``'s episode of ``scenario`` ("paper": the env's paper case)
    from reset seed ``seed`` in the dynamic fidelity of ``engine`` (:func:`dynamic_kwargs`),
    measure it as a kinematic episode is measured, and validate what it
    executed against what it commanded (:func:`run_dynamic`)."""
    t0 = time.perf_counter()
    val, failed = run_dynamic(spec, scenario, seed, dynamic_kwargs(spec.env_id, engine))
    metrics = bench_of(spec.env_id).metrics(val.episode)
    metrics["policy_failed"] = failed
    worst = ("not validated: the episode ended before the sensors took enough samples" if val.report is None
             else tightest(val.report))
    kf = {"worst": worst, "position_error_mm": round(val.position_error * 1000, 3)}
    return DynamicRow(spec.env_id, spec.name, scenario, seed, val.episode_return, val.success, metrics, val.passed,
                      kf, time.perf_counter() - t0,
                      producer=dynamic_producer(spec, engine) if producer is None else producer)


def evaluate_validation(spec: PolicySpec, seed: int, producer: str | None = None) -> ValidationRow:
    """The KF validation of the reference plan of ``spec``'s task (its bench's ``validated_plan``, run from
    ``seed``), for ``spec``, the reference."""
    check = bench_of(spec.env_id).validated_plan
    if check is None:
        raise ValueError(f"{spec.env_id} validates no reference plan")
    passed, summary = check(seed)
    return ValidationRow(spec.env_id, spec.name, passed, summary, spec.producer() if producer is None else producer)


def evaluate_job(kind: str, spec: PolicySpec, a: Any, b: Any, producer: str | None = None
                 ) -> EpisodeRow | DynamicRow | ValidationRow:
    """One job of any kind: an "episode" (evaluation seed ``a``, episode ``b``), a "dynamic" episode
    (scenario ``a``, reset seed ``b``; "dynamic@mujoco" in MuJoCo) or the "validation" of the reference plan
    (seed ``a``)."""
    if kind == "episode":
        return evaluate_episode(spec, a, b, producer)
    engine = engine_of_job(kind)
    if engine is not None:
        return evaluate_dynamic(spec, a, b, producer, engine)
    if kind == "validation":
        return evaluate_validation(spec, a, producer)
    raise ValueError(f"unknown kind of job {kind!r}")
