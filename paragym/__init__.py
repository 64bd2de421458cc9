"""paragym: a benchmark for motion planning of parallel manipulators.

Importing ``paragym`` registers its environments with Gymnasium (one row per id in
:mod:`paragym.registry`)::

    import gymnasium as gym
    import paragym  # noqa: F401
    env = gym.make("paragym/CaPaManCollisionFree-v0")
"""

from types import MappingProxyType
from typing import Any

from gymnasium.envs.registration import register
from gymnasium.envs.registration import registry as gym_registry

from paragym import machine as _machine
from paragym import registry as _registry
from paragym.registry import ROWS, EnvRow, check_env_id

__version__ = "0.10.0"


def __getattr__(name: str) -> Any:
    """Two read-only views of :mod:`paragym.registry`, made when asked (so they hold every row added since):
    ``ENVIRONMENTS``, env id -> (entry point, max episode steps, one-line description), and
    ``VECTOR_ENTRY_POINTS``, env id -> the native vector env
    (``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``)."""
    if name == "ENVIRONMENTS":
        return MappingProxyType({r.id: (r.entry_point, r.max_episode_steps, r.summary) for r in _registry.rows()})
    if name == "VECTOR_ENTRY_POINTS":
        return MappingProxyType({r.id: r.vector_entry_point for r in _registry.rows() if r.vector_entry_point})
    raise AttributeError(f"module 'paragym' has no attribute {name!r}")



def register_env(row: EnvRow) -> EnvRow:
    """Register an env id of :mod:`paragym.registry`'s form with paragym and Gymnasium: ``gym.make``,
    the ``paragym`` command, the leaderboard and the docs find it. A task defined outside paragym
    registers each of its ids with one row (its env classes and its bench module named in it);
    ``docs/guides/adding-a-task.md`` is the recipe."""
    _registry.add(row)
    if row.id not in gym_registry:
        register(id=row.id, entry_point=row.entry_point, max_episode_steps=row.max_episode_steps,
                 vector_entry_point=row.vector_entry_point)
    return row


def _load_task_plugins() -> None:
    """Import the modules of the entry-point group ``paragym.tasks``: tasks of other packages, which
    register their rows on import (:func:`register_env`). One that fails to import is a warning."""
    import warnings
    from importlib.metadata import entry_points

    for ep in entry_points(group="paragym.tasks"):
        try:
            ep.load()
        except Exception as exc:  # noqa: BLE001 - another package's bug must not break paragym
            warnings.warn(f"paragym: the task plugin {ep.name!r} ({ep.value}) failed to load: "
                          f"{type(exc).__name__}: {exc}", RuntimeWarning, stacklevel=2)


def _kernel_folders() -> list[str]:
    """The folders of paragym's sources that compile numba kernels (the core, and baselines' actor)."""
    import importlib.util
    from pathlib import Path

    core = Path(__path__[0])
    spec = importlib.util.find_spec("paragym.baselines")
    extra = [Path(p) for p in (spec.submodule_search_locations or [])] if spec else []
    return [str(core), *(str(p) for p in extra if core not in p.parents)]


_machine.refresh_kernel_cache(_kernel_folders())  # before any kernel loads: a cache older than its sources goes
for _row in ROWS:
    register_env(_row)
_load_task_plugins()

__all__ = ["ENVIRONMENTS", "VECTOR_ENTRY_POINTS", "check_env_id", "register_env"]
