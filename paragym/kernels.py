"""How a state of arrays travels into its numba kernels: as one plain tuple, named once, through the
kernel's compiled entry.

A task's state is a dataclass of arrays with one row per robot. Its kernels
take those arrays as one tuple and unpack it in the order the state's
``KERNEL_FIELDS`` names, instead of dozens of positional arguments. The
tuple is plain (not a NamedTuple): numba's dispatcher types a plain tuple of
arrays in C and a NamedTuple in Python, a microsecond a step. It is made
once per allocation of the arrays and kept.

A call through numba's dispatcher types every argument before it runs the
kernel: for a state of sixteen arrays that costs about as much as the
single env's whole kinematic step. :meth:`KernelArrays.call` types them
once, keeps the compiled entry (``Dispatcher.compile``) on the state, and
calls it directly after. The entry trusts its arguments' types, so the
caller fixes them: every array that is not the state's or the owner's has
its dtype and contiguity set by the caller (``np.ascontiguousarray``) and its
number of dimensions in ``key``; every other argument is of one Python
type. A new owner (the parameters) or key types the call again.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

__all__ = ["KernelArrays", "entry"]


def entry(kernel: Any, args: tuple[Any, ...]) -> Callable[..., Any]:
    """The compiled entry of the numba ``kernel`` for exactly the types of ``args`` (compiled, or loaded from
    numba's cache, on first use): calling it skips the dispatcher's typing. The kernel itself where numba's
    JIT is off (``NUMBA_DISABLE_JIT=1``)."""
    if not hasattr(kernel, "compile"):
        return kernel
    return kernel.compile(tuple(kernel.typeof_pyval(a) for a in args))


class KernelArrays:
    """A mixin for a state dataclass: :meth:`kernel_arrays` gives its ``KERNEL_FIELDS`` as one tuple, and
    :meth:`call` runs a kernel on it through the kernel's compiled entry."""

    #: the state's attributes its kernels take, in the order they unpack them
    KERNEL_FIELDS: ClassVar[tuple[str, ...]] = ()

    def kernel_arrays(self) -> tuple[Any, ...]:
        """The attributes of ``KERNEL_FIELDS``, as a plain tuple in that order (kept until
        :meth:`reallocated`)."""
        got = self.__dict__.get("_kernel_arrays")
        if got is None:
            got = self.__dict__["_kernel_arrays"] = tuple(getattr(self, name) for name in self.KERNEL_FIELDS)
        return got

    def call(self, kernel: Any, args: tuple[Any, ...], owner: Any = None, key: tuple[Any, ...] = ()) -> Any:
        """``kernel(*args)`` through the entry typed on the first call with this ``kernel``, ``owner`` (held by
        identity: the parameters whose numbers ``args`` carry) and ``key`` (what else sets the types: each
        caller-made array's number of dimensions). The caller keeps every other type fixed (module docstring)."""
        entries = self.__dict__.get("_entries")
        if entries is None:
            entries = self.__dict__["_entries"] = {}
        got = entries.get(kernel)
        if got is None or got[0] is not owner or got[1] != key:
            got = entries[kernel] = (owner, key, entry(kernel, args))
        return got[2](*args)

    def reallocated(self) -> None:
        """Say that an array of ``KERNEL_FIELDS`` was replaced by a new one: the tuple is made again."""
        self.__dict__.pop("_kernel_arrays", None)
        self.__dict__.pop("_entries", None)

    def __getstate__(self) -> dict[str, Any]:
        """A copy or a pickle holds the arrays, not the tuple or the compiled entries made of them."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_kernel_arrays", "_entries")}
