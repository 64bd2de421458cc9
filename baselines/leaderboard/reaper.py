"""The reaper of a local Ray: ends the Ray processes a driver started if the driver dies without shutting
Ray down (SIGKILL), since Ray's own agents otherwise outlive it for minutes.

Run as a file (``python reaper.py DRIVER_PID``) by
:func:`paragym.baselines.ray_session.ray_session`, before Ray starts, so that it sees every
process Ray starts and imports nothing of paragym. It forks into the background, prints its pid and
leaves the driver's family (Ray ends a dead driver's child processes), disarms any parent-death signal the
driver's fork hooks armed, then notes the driver's descendants every 0.2 s (pid and start time, so that a
reused pid is left alone); when the driver is gone it ends those still running (SIGTERM, SIGKILL after 3 s).
"""

from __future__ import annotations

import ctypes
import os
import sys
import time


def _detach() -> None:
    if os.fork():
        os._exit(0)
    print(os.getpid(), flush=True)
    sys.stdout.close()
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None).prctl(1, 0)  # PR_SET_PDEATHSIG: none
        except (OSError, AttributeError):
            pass


def _watch(driver: int, known: dict[int, float]) -> dict[int, float]:
    """The driver's descendants (pid -> start time) seen until it ends."""
    import psutil

    me = os.getpid()
    try:
        parent = psutil.Process(driver)
        while parent.status() != psutil.STATUS_ZOMBIE:
            try:
                children = parent.children(recursive=True)
            except psutil.Error:
                children = []
            for child in children:
                try:
                    if child.pid != me:
                        known.setdefault(child.pid, child.create_time())
                except psutil.Error:
                    pass
            time.sleep(0.2)
    except psutil.Error:
        pass
    return known


def _end(known: dict[int, float]) -> None:
    """End the processes of ``known`` that still run (the same process: its start time matches)."""
    import psutil

    procs = []
    for pid, created in known.items():
        try:
            p = psutil.Process(pid)
            if abs(p.create_time() - created) < 1e-3:
                procs.append(p)
        except psutil.Error:
            pass
    for p in procs:
        try:
            p.terminate()
        except psutil.Error:
            pass
    _, alive = psutil.wait_procs(procs, timeout=3)
    for p in alive:
        try:
            p.kill()
        except psutil.Error:
            pass


def main(argv: list[str]) -> None:
    """``argv``: the driver's pid, then any ``pid:start_time`` to end with its descendants."""
    _detach()
    known = {int(pid): float(created) for pid, created in (item.split(":") for item in argv[1:])}
    _end(_watch(int(argv[0]), known))


if __name__ == "__main__":
    main(sys.argv[1:])
