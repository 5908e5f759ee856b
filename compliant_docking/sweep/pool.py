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
(``TerminatedWorkerError``, as with joblib). On any exception — a dead worker, Ctrl-C,
SIGTERM — the workers are killed before it propagates, so the summary of an aborted
sweep (:meth:`~compliant_docking.sweep.session.SweepSession.finish_aborted`) runs after
they are gone, as with joblib; a sweeper that launches batch after batch (the tuning
study, which goes on after a failed batch) gets new workers for the next one. A job
whose config the sweeper did not check is composed here, in the launching process. Of
the joblib launcher's keys (the schema is kept, so ``hydra.launcher.n_jobs=N`` works as
before) only ``n_jobs`` is read.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
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
        self.composed: dict[tuple[str, ...], Any] = {}
        self._compose: Any = None

    def workers(self) -> int:
        """The number of worker processes: ``n_jobs``, negative counting back from the cores."""
        from joblib import cpu_count

        n_jobs = int(self.joblib.get("n_jobs") or -1)
        return max(cpu_count() + 1 + n_jobs, 1) if n_jobs < 0 else n_jobs

    def setup(self, *, hydra_context, task_function, config) -> None:
        self.config, self.task_function, self.hydra_context = config, task_function, hydra_context
        self._keep_compositions()
        self._start_workers()

    def _keep_compositions(self) -> None:
        """Keep what the sweeper's check composes (the loader's ``load_sweep_config``),
        so :meth:`launch` sends those configs instead of having the workers compose again."""
        loader = self.hydra_context.config_loader
        original = loader.load_sweep_config  # the guard's lookup of the configs it composed, if any

        def load_sweep_config(master_config, sweep_overrides):
            cfg = original(master_config, sweep_overrides)
            if master_config is self.config:
                self.composed[tuple(sweep_overrides)] = cfg
            return cfg

        loader.load_sweep_config = load_sweep_config  # an instance attribute, removed in launch
        self._compose = original

    def _executor(self):
        """loky's reusable executor for :meth:`workers` processes: the running one, or a new
        one when there is none or it was stopped (a dead worker, an interrupted batch)."""
        from joblib._parallel_backends import LokyBackend
        from joblib.externals.loky import get_reusable_executor

        n = self.workers()
        return get_reusable_executor(
            max_workers=n, timeout=IDLE_WORKER_TIMEOUT_S, env=LokyBackend()._prepare_worker_env(n_jobs=n)
        )

    def _start_workers(self) -> None:
        executor = self._executor()
        for _ in range(self.workers()):  # each worker imports the job's libraries while the sweeper checks
            executor.submit(_import_job_libraries)

    def launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        from hydra.core.singleton import Singleton
        from hydra.core.utils import configure_log, filter_overrides, setup_globals

        setup_globals()
        configure_log(self.config.hydra.hydra_logging, self.config.hydra.verbose)
        Path(str(self.config.hydra.sweep.dir)).mkdir(parents=True, exist_ok=True)
        loader = self.hydra_context.config_loader
        configs = [
            self.composed.pop(tuple(o), None) or self._compose(self.config, list(o)) for o in job_overrides
        ]
        keeping = vars(loader).pop("load_sweep_config", None)  # not sent to the workers with the context
        log.info(f"PoolLauncher({self.workers()} workers) is launching {len(job_overrides)} jobs")
        for idx, overrides in enumerate(job_overrides):
            log.info(f"\t#{initial_job_idx + idx} : {' '.join(filter_overrides(overrides))}")
        singleton_state = Singleton.get_state()
        executor = self._executor()
        try:
            futures = [
                executor.submit(
                    execute_job,
                    initial_job_idx + idx,
                    cfg,
                    self.hydra_context,
                    self.task_function,
                    singleton_state,
                )
                for idx, cfg in enumerate(configs)
            ]
            return [future.result() for future in futures]
        except BaseException:  # a dead worker, Ctrl-C, SIGTERM: stop the others before going on
            _kill_workers(executor)
            raise
        finally:  # every job has been sent: keep the checked configs of a next batch (a tuning study)
            if keeping is not None:
                loader.load_sweep_config = keeping


#: whether this process left loky's threads behind (see :func:`_kill_workers`); the command
#: line then ends the process without joining them (``cli.main``)
_abandoned_threads = False


def _kill_workers(executor) -> None:
    """Kill every worker at once (SIGKILL) and let the executor go without joining its
    threads. A worker killed while it wrote a result (a SIGTERM or Ctrl-C to the process
    group reaches the workers too) leaves half a message in the result pipe; loky's
    manager thread then waits for the rest forever, and ``shutdown(wait=True)`` with it
    (seen: a SIGTERM'd sweep that never exited)."""
    global _abandoned_threads
    for process in list(getattr(executor, "_processes", {}).values()):
        try:
            process.kill()
            process.join(timeout=5)
        except Exception:  # already gone
            pass
    executor.shutdown(wait=False, kill_workers=True)
    _abandoned_threads = True


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
