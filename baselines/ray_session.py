"""A Ray session for paragym's distributed work: the leaderboard's ``ray`` executor and ``paragym train --ray``.

:func:`ray_session` connects to the Ray cluster at an address, or starts a local Ray that is paragym's own: shut
down when the work ends, and reaped (:mod:`paragym.baselines.leaderboard.reaper`) if this process dies without
shutting it down (SIGKILL), since Ray's agents otherwise outlive their driver for minutes. A Ray this process
had already initialised is used as it is and left running.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["LOCAL", "import_ray", "ray_session"]

#: the address that asks for a local Ray of this process's own
LOCAL = "local"


def import_ray(what: str, tune: bool = False) -> Any:
    """Ray (``tune``: with Ray Tune), or a ValueError saying that ``what`` needs the ``ray`` extra."""
    try:
        import ray

        if tune:
            import ray.tune  # noqa: F401
    except ImportError as exc:
        raise ValueError(f"{what} needs Ray: pip install 'paragym[ray]'") from exc
    return ray


@contextmanager
def ray_session(address: str | None, cpus: int | None = None, what: str = "Ray") -> Iterator[Any]:
    """Ray, initialised for the ``with`` block: connected to the cluster at ``address``, or a local Ray of
    ``cpus`` CPUs (None: every core) for ``address`` None or ``"local"`` (module docstring)."""
    ray = import_ray(what)
    local = address in (None, LOCAL)
    started = not ray.is_initialized()
    reaper_pid = None
    try:
        if started:
            kwargs: dict[str, Any] = {"num_cpus": cpus or None} if local else {"address": address}
            if local:  # the local Ray is ours: it goes when we go, even on SIGKILL
                reaper_pid = _start_reaper()
            ray.init(include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING, **kwargs)
        yield ray
    finally:
        if started:
            ray.shutdown()
        if reaper_pid is not None:
            _stop_reaper(reaper_pid)


def _start_reaper() -> int:
    """Start :mod:`~paragym.baselines.leaderboard.reaper` (run as a file, so that it imports nothing of
    paragym and starts in milliseconds), which ends the local Ray's processes (its head,
    raylet, agents and workers: whatever descends from this process from now
    on) if this process dies without shutting Ray down (SIGKILL). Started before Ray, so
    that it sees every process Ray starts. Returns its pid, to end it when
    Ray was shut down normally."""
    import os
    import subprocess
    import sys

    from paragym.baselines.leaderboard import reaper

    proc = subprocess.Popen([sys.executable, reaper.__file__, str(os.getpid())], stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, start_new_session=True, text=True)
    pid = int(proc.stdout.readline())
    proc.wait()
    return pid


def _stop_reaper(pid: int) -> None:
    import os
    import signal

    try:
        os.kill(pid, signal.SIGTERM)
    except OSError:
        pass
