"""A sweep worker whose launching process dies exits (compliant_docking/sweep/watchdog.py),
proved on forked processes: a "launcher" that forks a "worker" and dies once it started. The
same property on a real sweep killed with SIGKILL is the nightly
tests/sweep/test_guard.py::test_the_workers_of_a_killed_sweep_exit_within_a_minute."""

from __future__ import annotations

import functools
import os
import time

import psutil

from compliant_docking.sweep import pool, watchdog


def _gone(pid: int) -> bool:
    """The process ended (a zombie nobody reaped yet counts as ended)."""
    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


def test_a_pool_worker_exits_when_its_launching_process_dies(monkeypatch):
    """The pool's start-up of a worker (``_import_job_libraries``, what each new loky worker
    runs first) starts the watchdog; once the worker's parent dies the worker exits."""
    # a short period, for the forked worker (its start-up imports the watchdog's function)
    monkeypatch.setattr(watchdog, "start_watchdog", functools.partial(watchdog.start_watchdog, 0.05))
    read, write = os.pipe()
    launcher = os.fork()
    if launcher == 0:  # the launching process: forks its worker, waits for it to start, dies
        started, ready = os.pipe()
        worker = os.fork()
        if worker == 0:  # the worker: its start-up, then a job far longer than the test
            try:
                pool._import_job_libraries()
                os.write(ready, b"1")
                time.sleep(60)
            finally:
                os._exit(0)
        os.read(started, 1)
        os.write(write, str(worker).encode())
        os._exit(0)
    os.close(write)
    os.waitpid(launcher, 0)
    worker = int(os.read(read, 32).decode())
    os.close(read)
    try:
        deadline = time.monotonic() + 20
        while not _gone(worker) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _gone(worker), "the worker outlived its launching process by 20 s"
    finally:
        if not _gone(worker):
            os.kill(worker, 9)  # only the process this test forked, by pid
