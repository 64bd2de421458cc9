"""Workers die with their parent; an interrupted leaderboard says what it saved (issue 15, items 7, 10)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import psutil
import pytest

from paragym.baselines.store import ResultStore

pytestmark = pytest.mark.slow  # every test here starts processes or runs a benchmark

LONG = ["-m", "paragym.cli", "leaderboard", "--env", "CaPaManCollisionFree-v0", "--policy", "rrt-ga",
        "--policy", "grid-dijkstra", "--no-validation", "--no-progress"]


def _start(tmp_path, *extra):
    return subprocess.Popen([sys.executable, *LONG, "--db", str(tmp_path / "r.sqlite"), "--out",
                             str(tmp_path / "out"), *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def _workers(proc, n, timeout=90.0):
    """The parent's child processes once ``n`` of them are up (and an episode is stored)."""
    end = time.time() + timeout
    while time.time() < end:
        kids = psutil.Process(proc.pid).children(recursive=True)
        if len(kids) >= n:
            return kids
        time.sleep(0.2)
    raise AssertionError(f"{n} workers did not start")


def _running(p) -> bool:
    """A zombie has ended: it only awaits its parent."""
    try:
        return p.is_running() and p.status() != psutil.STATUS_ZOMBIE
    except psutil.Error:
        return False


def _gone(procs, timeout=10.0) -> list:
    """Those of ``procs`` still running after ``timeout`` s."""
    end = time.time() + timeout
    alive = [p for p in procs if _running(p)]
    while alive and time.time() < end:
        time.sleep(0.2)
        alive = [p for p in alive if _running(p)]
    return alive


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_pool_workers_die_with_their_parent(tmp_path, sig):
    proc = _start(tmp_path, "--workers", "2")
    kids = _workers(proc, 2)
    time.sleep(2.0)
    proc.send_signal(sig)
    proc.wait(timeout=30)
    alive = _gone(kids)
    for p in alive:
        p.kill()
    assert not alive, f"{len(alive)} workers outlived their parent ({sig.name})"


def test_ctrl_c_prints_one_line_of_what_was_saved(tmp_path):
    proc = _start(tmp_path)
    deadline = time.time() + 90
    while time.time() < deadline:  # until some episodes are stored
        time.sleep(1.0)
        try:
            with ResultStore(tmp_path / "r.sqlite") as store:
                if len(store.rows()) >= 1:
                    break
        except Exception:
            continue
    proc.send_signal(signal.SIGINT)
    # Python acts on SIGINT between bytecodes: from a cold numba cache the process may be inside a
    # kernel's compilation (tens of seconds on a loaded 2-core machine), so its exit can wait that long
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith("pybullet build time")]
    assert len(lines) == 1 and "interrupted" in lines[0] and "run the same command again" in lines[0], err
    with ResultStore(tmp_path / "r.sqlite") as store:
        assert f"{len(store.rows())} episodes" in lines[0]


def test_the_local_ray_that_paragym_started_goes_with_its_driver(tmp_path):
    """SIGKILL of the driver: Ray's head, raylet and agents end within seconds (its agents had
    outlived the driver for over a minute)."""
    pytest.importorskip("ray")
    proc = _start(tmp_path, "--executor", "ray", "--workers", "2")
    kids = _workers(proc, 6)
    time.sleep(3.0)
    proc.kill()
    proc.wait(timeout=30)
    kids = [k for k in kids if k.is_running()]
    alive = _gone(kids, timeout=20)
    names = sorted({p.name() for p in alive if _running(p)})
    for p in alive:
        p.kill()
    assert not alive, f"left behind: {names}"


def test_a_ray_task_error_arrives_as_the_tasks_own_message(tmp_path):
    pytest.importorskip("ray")
    from paragym.baselines.leaderboard import EvalSuite, run_leaderboard
    from paragym.baselines.policies import register_policy

    def broken(env, seed):
        raise ValueError("this policy cannot start")

    register_policy("paragym/Orthoglide2PRRKappa-v0", "broken", broken, replace=True)
    with pytest.raises(ValueError) as info:
        run_leaderboard(db=tmp_path / "r.sqlite", suite=EvalSuite("t", (0,), 1), env_ids=["Orthoglide2PRRKappa-v0"],
                        policies=["broken"], executor="ray", workers=1, out=None, validate=False, progress=False,
                        echo=lambda s: None)
    assert str(info.value) == "this policy cannot start" and "\x1b[" not in str(info.value)


def _signal_handlers() -> tuple[bool, bool]:
    """In a pool worker: whether SIGTERM ends it (the default action) and SIGINT is left to the parent."""
    return signal.getsignal(signal.SIGTERM) == signal.SIG_DFL, signal.getsignal(signal.SIGINT) == signal.SIG_IGN


def test_a_pool_worker_ends_on_sigterm_whatever_its_parent_handles():
    """The CLI turns SIGTERM and SIGINT into KeyboardInterrupt; a forked worker inherited that, caught it as its
    job's error, and went on with the next queued episode, so an interrupted run waited 18 s for episodes it
    would never store. A worker takes SIGTERM's default action and ignores SIGINT (its parent stops it)."""
    import multiprocessing as mp
    import os
    from concurrent.futures import ProcessPoolExecutor

    from paragym.baselines.leaderboard.executors import _init_worker

    def stop(signum, frame):
        raise KeyboardInterrupt

    before = signal.signal(signal.SIGTERM, stop), signal.signal(signal.SIGINT, stop)
    try:
        with ProcessPoolExecutor(1, mp_context=mp.get_context("fork"), initializer=_init_worker,
                                 initargs=(os.getpid(),)) as pool:
            assert pool.submit(_signal_handlers).result(timeout=60) == (True, True)
    finally:
        signal.signal(signal.SIGTERM, before[0])
        signal.signal(signal.SIGINT, before[1])
