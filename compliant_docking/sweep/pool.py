"""The default sweep launcher: Hydra's joblib launcher, rearranged so a job's time goes
to simulating (``hydra/launcher=local``, conf/hydra/launcher/local.yaml).

Hydra's joblib launcher composes every job's config twice — in the launching process,
where the sweeper checks each job before any starts, and again in the worker that runs
it — and starts its loky worker processes only after that check. :class:`PoolLauncher`
runs the same jobs on the same loky processes (reused between jobs, one per core, their
BLAS/OpenMP thread counts set to cores ÷ workers as joblib does) with two changes:

- **The workers start first.** When Hydra sets the launcher up, before the sweeper
  checks the jobs, the workers are started and each imports the simulation's libraries
  (Pinocchio, MuJoCo, pandas, SciPy: ~1 s of CPU) while the launching process composes
  and checks the jobs' configs.
- **One composition per job.** The configs the sweeper composed for its check are kept
  and sent with the jobs; a worker runs Hydra's ``run_job`` on the config it receives
  (the same config: composed by the same loader from the same overrides and master config).

Everything else is Hydra's: its ``run_job`` (job directory, ``.hydra/`` files, logging,
callbacks), its results in job order, its error when a job's process dies
(``TerminatedWorkerError``, as with joblib). On any exception — a dead worker, a signal
(Ctrl-C, SIGTERM, SIGHUP; the workers themselves ignore SIGINT and SIGHUP and leave them
to the launching process) — the jobs not started are cancelled and the workers killed
and waited for before it propagates, so no job starts after it and the summary of an
aborted sweep (:meth:`~compliant_docking.sweep.session.SweepSession.finish_aborted`)
runs after they are gone; a sweeper that launches batch after batch (the tuning
study, which goes on after a failed batch) gets new workers for the next one. A job
whose config the sweeper did not check is composed here, in the launching process. Of
the joblib launcher's keys (the schema is kept, so ``hydra.launcher.n_jobs=N`` works as
before) only ``n_jobs`` is read.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from hydra.core.utils import JobReturn
from hydra.plugins.launcher import Launcher

log = logging.getLogger(__name__)
#: seconds an idle worker waits for more work before it exits (joblib's value)
IDLE_WORKER_TIMEOUT_S = 300


class PoolLauncher(Launcher):
    """See the module docstring. ``**joblib``: the keys of Hydra's joblib launcher."""

    def __init__(self, **joblib: Any) -> None:
        self.joblib = joblib
        self.config: Any = None
        self.task_function: Any = None
        self.hydra_context: Any = None
        self.compositions: Any = None

    def workers(self) -> int:
        """The number of worker processes: ``n_jobs``, negative counting back from the cores."""
        from joblib import cpu_count

        n_jobs = int(self.joblib.get("n_jobs") or -1)
        return max(cpu_count() + 1 + n_jobs, 1) if n_jobs < 0 else n_jobs

    def setup(self, *, hydra_context, task_function, config) -> None:
        from compliant_docking.config.hydra_adapter import share_compositions

        self.config, self.task_function, self.hydra_context = config, task_function, hydra_context
        # what the sweeper's check composes is kept and sent to the jobs (launch)
        self.compositions = share_compositions(hydra_context.config_loader)
        self.compositions.keep_for(config)
        self._start_workers()

    def _executor(self):
        """loky's reusable executor for :meth:`workers` processes: the running one, or a new
        one when there is none or it was stopped (a dead worker, an interrupted batch)."""
        from compliant_docking.sweep import workers

        n = self.workers()
        _quiet_resource_tracker()
        with _signals_left_to_the_launcher():
            return workers.executor(n, IDLE_WORKER_TIMEOUT_S)

    def _start_workers(self) -> None:
        executor = self._executor()
        with _signals_left_to_the_launcher():
            # each worker imports the job's libraries while the sweeper checks
            for _ in range(self.workers()):
                executor.submit(_import_job_libraries)

    def launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        from hydra.core.singleton import Singleton
        from hydra.core.utils import configure_log, filter_overrides, setup_globals

        setup_globals()
        configure_log(self.config.hydra.hydra_logging, self.config.hydra.verbose)
        Path(str(self.config.hydra.sweep.dir)).mkdir(parents=True, exist_ok=True)
        configs = [self.compositions.take(self.config, list(o)) for o in job_overrides]
        log.info(f"PoolLauncher({self.workers()} workers) is launching {len(job_overrides)} jobs")
        for idx, overrides in enumerate(job_overrides):
            log.info(f"\t#{initial_job_idx + idx} : {' '.join(filter_overrides(overrides))}")
        singleton_state = Singleton.get_state()
        executor = self._executor()
        futures: list = []
        try:
            for idx, cfg in enumerate(configs):
                futures.append(
                    executor.submit(
                        execute_job,
                        initial_job_idx + idx,
                        cfg,
                        self.hydra_context,
                        self.task_function,
                        singleton_state,
                    )
                )
            return [future.result() for future in futures]
        except BaseException:  # a dead worker, a signal: no job starts from here on
            _kill_workers(executor, futures)
            raise


#: whether this process left loky's threads behind (see :func:`_kill_workers`); the command
#: line then ends the process without joining them (``cli.main``)
_abandoned_threads = False


def _kill_workers(executor, futures: Sequence = ()) -> None:
    """Stop the sweep's jobs at once: cancel the jobs not yet started, kill every worker
    (SIGKILL, by process id: loky's process objects have no ``kill``) and wait for each to
    be gone, then let the executor go without joining its threads. A worker killed while
    it wrote a result (a signal to the process group reaches the workers too) leaves half
    a message in the result pipe; loky's manager thread then waits for the rest forever,
    and ``shutdown(wait=True)`` with it (seen: a SIGTERM'd sweep that never exited). When
    this returns, no job of the sweep runs or will start."""
    import os
    import signal

    global _abandoned_threads
    for future in futures:
        future.cancel()  # queued, not started: never runs
    from compliant_docking.sweep.workers import worker_pids

    pids = worker_pids(executor)
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except (OSError, TypeError):  # gone already (or never started)
            pass
    for pid in pids:
        _wait_gone(pid)
    executor.shutdown(wait=False, kill_workers=True)
    _abandoned_threads = True


#: the interpreter option that silences loky's resource tracker's warnings (its module)
QUIET_TRACKER = "ignore::UserWarning:joblib.externals.loky.backend.resource_tracker"


def _quiet_resource_tracker() -> None:
    """Start loky's resource tracker without its warnings: when an aborted sweep kills its
    workers, the tracker frees their semaphores itself and says "There appear to be N
    leaked semlock objects to clean up at shutdown" on the console after the sweep's
    summary. loky starts it with this interpreter's ``-W`` options (``sys.warnoptions``);
    the filter names the tracker's module only."""
    import sys

    if QUIET_TRACKER not in sys.warnoptions:
        sys.warnoptions.append(QUIET_TRACKER)


@contextlib.contextmanager
def _signals_left_to_the_launcher() -> Iterator[None]:
    """Start loky's processes (its workers, its resource tracker) ignoring SIGINT and
    SIGHUP, which a terminal sends to the whole process group (Ctrl-C, closing it): the
    launching process handles them (it stops the sweep and kills the workers:
    run/interrupt.py), while a worker interrupted itself printed a traceback when it was
    still importing, and a resource tracker killed by a hang-up was started again by loky
    and printed tracebacks for the resources it lost. An ignored signal stays ignored in a
    started process; the launching process ignores them only while loky starts its
    processes (main thread only). SIGTERM is left as it is: it ends a worker."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGHUP)}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _wait_gone(pid: int, timeout_s: float = 5.0) -> None:
    """Wait until the process ``pid`` (a child of this one) is gone: reaped by loky's
    manager thread, or by us."""
    import os
    import time

    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            done, _ = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:  # reaped elsewhere (loky's manager thread): gone
            return
        if done == pid:
            return
        time.sleep(0.01)


def abandoned_threads() -> bool:
    """Whether a sweep in this process was aborted and left loky's threads behind."""
    return _abandoned_threads


def start_early(launcher_config: Any) -> bool:
    """Start the pool's workers now, when ``launcher_config`` (``hydra.launcher``) is this
    launcher: the guard calls it before it composes and checks every job's config, which
    happens before Hydra sets the launcher up (a 180-job preset composes for ~3 s). The
    launcher's set-up then finds the same running executor. Returns whether it started them."""
    if not str(launcher_config.get("_target_", "")).endswith(".PoolLauncher"):
        return False
    PoolLauncher(**{k: v for k, v in launcher_config.items() if k != "_target_"})._start_workers()
    return True


def execute_job(idx: int, sweep_config, hydra_context, task_function, singleton_state) -> JobReturn:
    """Hydra's joblib ``execute_job`` for a config composed already: run job ``idx``."""
    from hydra.core.hydra_config import HydraConfig
    from hydra.core.singleton import Singleton
    from hydra.core.utils import run_job, setup_globals
    from omegaconf import open_dict

    setup_globals()
    Singleton.set_state(singleton_state)
    with open_dict(sweep_config):
        sweep_config.hydra.job.id = f"{sweep_config.hydra.job.name}_{idx}"
        sweep_config.hydra.job.num = idx
    HydraConfig.instance().set_config(sweep_config)
    return run_job(
        hydra_context=hydra_context,
        config=sweep_config,
        task_function=task_function,
        job_dir_key="hydra.sweep.dir",
        job_subdir_key="hydra.sweep.subdir",
    )


def _import_job_libraries() -> None:
    """In a new worker: import what every job needs, before the first job arrives; and
    watch the launching process (a worker whose parent died exits: sweep/watchdog.py)."""
    from compliant_docking.sweep.watchdog import start_watchdog

    start_watchdog()
    import hydra.core.utils  # noqa: F401  (Hydra's run_job)

    import compliant_docking.control.base  # noqa: F401  (SciPy's LAPACK)
    import compliant_docking.run.runner  # noqa: F401  (pandas, pyarrow)
    import compliant_docking.sim.simulate  # noqa: F401  (MuJoCo, Pinocchio)
    import compliant_docking.sweep.callback  # noqa: F401  (the progress line)
