"""The name of before paragym 0.9 of the CaPaMan's grid: :mod:`paragym.sim.capaman_grid` (Psi, cluster points,
the joint matrix) and :mod:`paragym.sim.capaman_clearance` (signed distances). Its names answer from there, with
a DeprecationWarning; it goes in paragym 1.0.
"""

from typing import Any


def __getattr__(name: str) -> Any:
    import warnings

    from paragym.sim import capaman_clearance, capaman_grid

    for module in (capaman_grid, capaman_clearance):
        if hasattr(module, name):
            warnings.warn(f"paragym.sim.occupancy.{name} is {module.__name__}.{name} since paragym 0.9",
                          DeprecationWarning, stacklevel=2)
            return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
