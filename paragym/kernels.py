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

A batch of many robots is shared among threads (:func:`shares`,
:func:`concurrently`, :meth:`KernelArrays.call_split`): one share per CPU, in a
pool of worker threads that wait on a queue rather than spin (numba's own
parallel loops spin, and the serial code between a native env's kernels would
wait on them). Each thread runs a kernel compiled with ``nogil=True`` on its
own robots, so the numbers are those of one call, bit for bit.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import cached_property
from typing import Any, ClassVar

import numpy as np

__all__ = ["SPLIT_MIN_ROWS", "KernelArrays", "KernelOwner", "concurrently", "entry", "shares", "thread_count"]

#: the fewest robots a kernel runs before they are shared among threads (:func:`shares`): below, waking the
#: threads costs more than they save
SPLIT_MIN_ROWS = 256


def entry(kernel: Any, args: tuple[Any, ...]) -> Callable[..., Any]:
    """The compiled entry of the numba ``kernel`` for exactly the types of ``args`` (compiled, or loaded from
    numba's cache, on first use): calling it skips the dispatcher's typing. The kernel itself where numba's
    JIT is off (``NUMBA_DISABLE_JIT=1``)."""
    if not hasattr(kernel, "compile"):
        return kernel
    return kernel.compile(tuple(kernel.typeof_pyval(a) for a in args))


def thread_count() -> int:
    """How many threads :meth:`KernelArrays.call_split` uses: the environment variable ``PARAGYM_THREADS``
    if set (1 turns the sharing off), else the CPUs this process may run on."""
    wanted = os.environ.get("PARAGYM_THREADS")
    if wanted:
        try:
            count = int(wanted)
        except ValueError:
            raise ValueError(f"PARAGYM_THREADS must be a whole number of threads, not {wanted!r}") from None
        if count < 1:
            raise ValueError(f"PARAGYM_THREADS must be at least 1, not {count}")
        return count
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


_POOL: dict[str, Any] = {"pid": None, "pool": None, "size": 0}
_NO_ENTRIES: dict[Any, Any] = {}


def _pool(size: int) -> ThreadPoolExecutor:
    """This process's pool of ``size`` worker threads (made again in a forked child, which inherits no
    threads, or when the size asked for changes)."""
    if _POOL["pid"] != os.getpid() or _POOL["size"] != size:
        if _POOL["pid"] == os.getpid():
            _POOL["pool"].shutdown(wait=False)
        _POOL.update(pid=os.getpid(), pool=ThreadPoolExecutor(size, thread_name_prefix="paragym-kernel"),
                     size=size)
    return _POOL["pool"]


def shares(count: int) -> list[tuple[int, int]] | None:
    """How ``count`` robots are shared among threads: consecutive (start, stop) ranges of near-equal size, one
    per thread, with at least half of :data:`SPLIT_MIN_ROWS` robots each; None when that leaves one thread
    (:func:`thread_count`), so that the caller runs them in one call."""
    if count < SPLIT_MIN_ROWS:  # before asking the system for its CPUs: a single env's step is microseconds
        return None
    threads = min(thread_count(), count // (SPLIT_MIN_ROWS // 2))
    if threads < 2:
        return None
    bounds = [count * k // threads for k in range(threads + 1)]
    return list(zip(bounds[:-1], bounds[1:], strict=True))


def concurrently(run: Callable[..., Any], calls: list[tuple[Any, ...]]) -> None:
    """``run(*args)`` for each of ``calls`` at once: the first in this thread, the others in this process's
    worker threads. ``run`` must release the GIL (a numba kernel compiled with ``nogil=True``) for the calls to
    overlap, and no two calls may write the same memory."""
    pending = [_pool(max(1, thread_count() - 1)).submit(run, *args) for args in calls[1:]]
    try:
        run(*calls[0])
    finally:
        for done in pending:
            done.result()


class KernelOwner:
    """A parameters class that makes its kernels' arguments once (``functools.cached_property``): a copy or a
    pickle of it leaves out what its cached properties made, and those named in ``not_pickled``, to be made
    again where they are next read. The arguments hold read-only arrays, so that numba compiles each kernel for
    one signature; an array comes back from a pickle writable, and a process that a pool or Ray sends the
    parameters to would compile every kernel a second time for it."""

    not_pickled: ClassVar[tuple[str, ...]] = ()

    def __getstate__(self) -> dict[str, Any]:
        made = {name for cls in type(self).__mro__ for name, value in vars(cls).items()
                if isinstance(value, cached_property)}
        return {k: v for k, v in self.__dict__.items() if k not in made and k not in self.not_pickled}


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
        got = (self.__dict__.get("_entries") or _NO_ENTRIES).get(kernel)
        if got is not None and got[0] is owner and got[1] == key:  # a step's path: no further Python call
            return got[2](*args)
        return self._entry(kernel, args, owner, key)(*args)

    def _entry(self, kernel: Any, args: tuple[Any, ...], owner: Any, key: tuple[Any, ...]) -> Callable[..., Any]:
        """The compiled entry of ``kernel`` for this owner and key (:meth:`call`), typed when it is not kept."""
        entries = self.__dict__.get("_entries")
        if entries is None:
            entries = self.__dict__["_entries"] = {}
        got = entries.get(kernel)
        if got is None or got[0] is not owner or got[1] != key:
            got = entries[kernel] = (owner, key, entry(kernel, args))
        return got[2]

    def call_split(self, kernel: Any, args: tuple[Any, ...], rows_at: int, owner: Any = None,
                   key: tuple[Any, ...] = ()) -> None:
        """:meth:`call`, with the robots that the boolean mask ``args[rows_at]`` selects shared among threads
        (:func:`shares`; equal counts of selected robots, in index order): each thread runs the kernel with a
        mask of its own share. For a kernel compiled with ``nogil=True`` that writes nothing but its selected
        robots' rows, and keeps its scratch arrays to itself: each robot then meets exactly the arithmetic it
        would in one call, so the result is the same bits."""
        rows = args[rows_at]
        parts = None if len(rows) < SPLIT_MIN_ROWS else shares(int(np.count_nonzero(rows)))
        if parts is None:
            self.call(kernel, args, owner, key)
            return
        chosen = np.flatnonzero(rows)
        calls = []
        for lo, hi in parts:
            mask = np.zeros_like(rows)
            mask[chosen[lo:hi]] = True
            calls.append(args[:rows_at] + (mask,) + args[rows_at + 1:])
        concurrently(self._entry(kernel, args, owner, key), calls)

    def reallocated(self) -> None:
        """Say that an array of ``KERNEL_FIELDS`` was replaced by a new one: the tuple is made again."""
        self.__dict__.pop("_kernel_arrays", None)
        self.__dict__.pop("_entries", None)

    def __getstate__(self) -> dict[str, Any]:
        """A copy or a pickle holds the arrays, not the tuple or the compiled entries made of them."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_kernel_arrays", "_entries")}
