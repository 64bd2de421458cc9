"""What every task shares: resolving the ``scenario`` argument, and when a mechanism counts as broken.

An env, its vector env, a planner and the CLI all take a scenario as a name
("paper", "random", ...) or as a custom scenario object; this one helper
checks it, with one message for every task.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["BROKEN_GAP", "renamed", "resolve_scenario"]

S = TypeVar("S")


def resolve_scenario(choice: Any, names: tuple[str, ...], custom: type[S],
                     validate: Callable[[S], Any] | None = None, name: str = "scenario") -> str | S:
    """``choice`` if it is one of ``names`` or a ``custom`` object that
    ``validate`` accepts (``validate`` raises ValueError/TypeError naming the
    field that cannot run). An unknown name is a ValueError, any other type a
    TypeError, both saying "<name> must be one of ... or a <Custom>"."""
    if isinstance(choice, str) and choice in names:
        return choice
    if isinstance(choice, custom):
        if validate is not None:
            validate(choice)
        return choice
    error = ValueError if isinstance(choice, str) else TypeError
    one_of = f"one of {', '.join(map(repr, names))} or " if names else ""
    raise error(f"{name} must be {one_of}a {custom.__name__}; got {choice!r:.120}")

#: a loop of a closed chain open by more than this (m) in dynamic fidelity is a broken mechanism: the episode ends
#: as a failure ("broken") in the ids whose rules say so (the presets hold their loops within 1 mm under contact)
BROKEN_GAP = 0.005


def renamed(module: str, old_to_new: dict[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` that still answers to the names of before paragym 0.9 (``old_to_new``) with
    a DeprecationWarning naming the new one: the tasks share one vocabulary now (``<Task>Scenario``,
    ``<Task>State``, ``paper_scenario()``, ``random_scenario(rng)``)."""
    import sys
    import warnings

    def __getattr__(name: str) -> Any:
        if name in old_to_new:
            warnings.warn(f"{module}.{name} is {module}.{old_to_new[name]} since paragym 0.9", DeprecationWarning,
                          stacklevel=2)
            return getattr(sys.modules[module], old_to_new[name])
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return __getattr__
