"""How a state of arrays travels into its numba kernels: as one plain tuple, named once.

A task's state is a dataclass of arrays with one row per robot. Its kernels
take those arrays as one tuple and unpack it in the order the state's
``KERNEL_FIELDS`` names, instead of dozens of positional arguments. The
tuple is plain (not a NamedTuple): numba's dispatcher types a plain tuple of
arrays in C and a NamedTuple in Python, a microsecond a step. It is made
once per allocation of the arrays and kept.
"""

from __future__ import annotations

from typing import Any, ClassVar

__all__ = ["KernelArrays"]


class KernelArrays:
    """A mixin for a state dataclass: :meth:`kernel_arrays` gives its ``KERNEL_FIELDS`` as one tuple."""

    #: the state's attributes its kernels take, in the order they unpack them
    KERNEL_FIELDS: ClassVar[tuple[str, ...]] = ()

    def kernel_arrays(self) -> tuple[Any, ...]:
        """The attributes of ``KERNEL_FIELDS``, as a plain tuple in that order (kept until
        :meth:`reallocated`)."""
        got = self.__dict__.get("_kernel_arrays")
        if got is None:
            got = self.__dict__["_kernel_arrays"] = tuple(getattr(self, name) for name in self.KERNEL_FIELDS)
        return got

    def reallocated(self) -> None:
        """Say that an array of ``KERNEL_FIELDS`` was replaced by a new one: the tuple is made again."""
        self.__dict__.pop("_kernel_arrays", None)
