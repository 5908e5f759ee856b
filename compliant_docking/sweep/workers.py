"""Letting a sweep's loky worker processes go (the launcher starts them, sweep/pool.py):
at once for a sweep the guard refused after it started them, and gently once every job
has returned, so they exit while the launching process writes the summary."""

from __future__ import annotations


def stop_early() -> None:
    """Stop the workers ``sweep.pool.start_early`` started for a sweep the guard then refused."""
    _shutdown(wait=True, kill_workers=True)


def release_workers() -> None:
    """Let the idle workers exit while the launching process writes the sweep's summary
    (at interpreter exit loky would otherwise stop and join them then: ~0.3 s)."""
    _shutdown(wait=False, kill_workers=False)


def _shutdown(*, wait: bool, kill_workers: bool) -> None:
    from joblib.externals.loky import reusable_executor

    executor = reusable_executor._executor
    if executor is not None:
        executor.shutdown(wait=wait, kill_workers=kill_workers)
