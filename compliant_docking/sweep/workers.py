"""A sweep's loky worker processes (the pool launcher, sweep/pool.py, runs its jobs on
them): starting them, letting them go — at once for a sweep the guard refused after it
started them, gently once every job has returned, so they exit while the launching
process writes the summary — and their process ids, to kill them.

The one module that relies on joblib's non-public objects (loky's public
``get_reusable_executor`` gives the rest); :func:`problems` checks them against the
installed joblib and tests/sweep/test_workers.py fails first, naming what changed:

- ``joblib._parallel_backends.LokyBackend._prepare_worker_env(n_jobs)``: the environment
  that limits each worker's BLAS/OpenMP threads to cores ÷ workers, as joblib's own
  workers get it (the list of variables is joblib's);
- a loky executor's ``_processes`` (pid → process): loky's process objects have no
  ``kill`` and its executor no list of its workers; an aborted sweep kills them by pid
  (sweep/pool.py says why);
- ``joblib.externals.loky.reusable_executor._executor``: the running reusable executor
  (ours, or that of Hydra's joblib launcher), if any; loky's public getter would start one.
"""

from __future__ import annotations

from typing import Any


def executor(n: int, timeout_s: float) -> Any:
    """loky's reusable executor for ``n`` worker processes that exit after ``timeout_s``
    idle, their thread counts limited as joblib limits its workers': the running one, or
    a new one when there is none or it was stopped."""
    from joblib._parallel_backends import LokyBackend
    from joblib.externals.loky import get_reusable_executor

    return get_reusable_executor(
        max_workers=n, timeout=timeout_s, env=LokyBackend()._prepare_worker_env(n_jobs=n)
    )


def worker_pids(pool: Any) -> list[int]:
    """The process ids of the worker processes of the loky executor ``pool``."""
    return [process.pid for process in list(getattr(pool, "_processes", {}).values())]


def stop_early() -> None:
    """Stop the workers ``sweep.pool.start_early`` started for a sweep the guard then refused."""
    _shutdown(wait=True, kill_workers=True)


def release_workers() -> None:
    """Let the idle workers exit while the launching process writes the sweep's summary
    (at interpreter exit loky would otherwise stop and join them then: ~0.3 s)."""
    _shutdown(wait=False, kill_workers=False)


def _shutdown(*, wait: bool, kill_workers: bool) -> None:
    from joblib.externals.loky import reusable_executor

    pool = reusable_executor._executor  # the running one, also Hydra's joblib launcher's; no new one
    if pool is not None:
        pool.shutdown(wait=wait, kill_workers=kill_workers)


def problems() -> list[str]:
    """What the installed joblib no longer offers as this module relies on it (one
    sentence each); [] when everything is there."""
    import inspect

    import joblib

    found: list[str] = []

    def changed(what: str) -> None:
        found.append(
            f"joblib {joblib.__version__} changed what compliant_docking/sweep/workers.py relies on "
            f"({what}); install joblib < 2 (pyproject.toml) or update sweep/workers.py"
        )

    try:
        from joblib._parallel_backends import LokyBackend

        params = tuple(inspect.signature(LokyBackend._prepare_worker_env).parameters)
        if params != ("self", "n_jobs"):
            changed(f"LokyBackend._prepare_worker_env{params} is not _prepare_worker_env(self, n_jobs)")
        else:
            env = LokyBackend()._prepare_worker_env(n_jobs=2)
            if not isinstance(env, dict) or "OMP_NUM_THREADS" not in env:
                changed(f"LokyBackend._prepare_worker_env(n_jobs=2) gave {env!r}, not the thread variables")
    except (ImportError, AttributeError) as exc:
        changed(f"joblib._parallel_backends.LokyBackend._prepare_worker_env: {exc}")
    try:
        from joblib.externals.loky.process_executor import ProcessPoolExecutor

        if "self._processes = {}" not in inspect.getsource(ProcessPoolExecutor.__init__).replace(" :", ":"):
            changed("loky's ProcessPoolExecutor no longer keeps its workers in _processes")
    except (ImportError, AttributeError, OSError) as exc:
        changed(f"joblib.externals.loky.process_executor.ProcessPoolExecutor: {exc}")
    try:
        from joblib.externals.loky import reusable_executor

        reusable_executor._executor  # noqa: B018  (the attribute must exist)
    except (ImportError, AttributeError) as exc:
        changed(f"joblib.externals.loky.reusable_executor._executor: {exc}")
    return found
