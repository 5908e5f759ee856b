"""A worker process's watchdog on its launching process: a sweep's workers exit when the
process that launched them is gone (the guard and the pool launcher start it in each
worker; sweep/guard.py says why)."""

from __future__ import annotations

import os
import threading

#: how often a worker's watchdog looks at its parent process [s]
PERIOD_S = 2.0

_watchdog: threading.Thread | None = None


def start_watchdog(period_s: float = PERIOD_S) -> None:
    """Exit this process when its parent is gone (once per process; a daemon thread).

    The parent is the launching process of a joblib sweep; when it dies the kernel
    re-parents its children, so ``os.getppid()`` changes. The worker then exits at once
    (``os._exit``): a job it was running is left without ``metrics.json``, like any job
    of a killed sweep, and ``resume=`` reruns it.
    """
    global _watchdog
    if _watchdog is not None and _watchdog.is_alive():
        return
    parent = os.getppid()

    def watch() -> None:
        while True:
            threading.Event().wait(period_s)
            if os.getppid() != parent:
                os._exit(1)

    _watchdog = threading.Thread(target=watch, name="orphan-watchdog", daemon=True)
    _watchdog.start()
