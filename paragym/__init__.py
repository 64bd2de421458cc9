"""paragym: a benchmark for motion planning of parallel manipulators.

Importing ``paragym`` registers its environments with Gymnasium (one row per id in
:mod:`paragym.registry`)::

    import gymnasium as gym
    import paragym  # noqa: F401
    env = gym.make("paragym/CaPaManCollisionFree-v0")
"""

from gymnasium.envs.registration import register
from gymnasium.envs.registration import registry as gym_registry

from paragym.registry import ROWS, check_env_id

__version__ = "0.8.0"

#: env id -> (entry point, max episode steps, one-line description), from :mod:`paragym.registry`
ENVIRONMENTS: dict[str, tuple[str, int, str]] = {r.id: (r.entry_point, r.max_episode_steps, r.summary) for r in ROWS}

#: env id -> the native vector env (``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``)
VECTOR_ENTRY_POINTS: dict[str, str] = {r.id: r.vector_entry_point for r in ROWS if r.vector_entry_point}

for _row in ROWS:
    if _row.id not in gym_registry:
        register(id=_row.id, entry_point=_row.entry_point, max_episode_steps=_row.max_episode_steps,
                 vector_entry_point=_row.vector_entry_point)

__all__ = ["ENVIRONMENTS", "VECTOR_ENTRY_POINTS", "check_env_id"]
