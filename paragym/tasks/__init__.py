"""The tasks' scenarios: each task's scenario dataclass, its validation, the
paper's case and the random generator, in one module per task.

This layer sits above the mechanisms and the PyBullet sim and below the envs,
the planners and the CLI, which all take their scenarios from here.
"""

from paragym.tasks.base import resolve_scenario

__all__ = ["resolve_scenario"]
