"""The sweep's Hydra callback (``hydra.callbacks.sweep`` in conf/config.yaml).

With the joblib launcher the jobs run in loky worker processes, so the launching
process never sees their records; everything reads the sweep directory:

- when the sweep starts (launching process), :meth:`SweepCallback.on_multirun_start`
  checks a resume (:mod:`.resume`), opens the sweep in the
  :class:`~compliant_docking.sweep.session.SweepSession` and prints a header;
- after each job, in the worker that ran it, :meth:`SweepCallback.on_job_end` prints one
  progress line (:func:`~compliant_docking.sweep.progress.job_line`); on the submitit
  launchers the jobs print into their own logs, so the launching process prints the
  lines (:class:`~compliant_docking.sweep.progress.ProgressWatcher`);
- when the sweep ends (launching process), :meth:`SweepCallback.on_multirun_end` writes
  the summary and prints the counts (:mod:`.summary`). A sweep cut short (a worker
  process died: joblib raises ``TerminatedWorkerError`` and Hydra aborts, skipping
  ``on_multirun_end``; or Ctrl-C, SIGTERM) is summarised by the command line through
  :meth:`SweepSession.finish_aborted`.

This module is imported by the launching process and by every worker: keep it light.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig

from compliant_docking.run.rundir import flatten
from compliant_docking.sweep import resume
from compliant_docking.sweep.directories import sweep_dir_of
from compliant_docking.sweep.launchers import describe, is_submitit
from compliant_docking.sweep.progress import ProgressWatcher, display, emit, job_line
from compliant_docking.sweep.session import SweepSession


def expected_jobs(config: DictConfig) -> int | None:
    """How many jobs the sweep of ``config`` launches (None if unknown): Hydra's basic
    sweeper, one per combination; the tuning sweeper (``hydra/sweeper=optuna``), its
    budget of trials × the draws each trial runs (over the whole study, resumed or not)."""
    try:
        sweeper = config.hydra.sweeper
        if "n_trials" in sweeper and "draws" in sweeper:  # compliant_docking.tune
            count = _combinations(sweeper.draws, [])
            return None if count is None else int(sweeper.n_trials) * count
        if not str(sweeper.get("_target_", "")).endswith("BasicSweeper"):
            return None
        return _combinations(sweeper.get("params") or {}, list(config.hydra.overrides.task))
    except Exception:  # e.g. glob() sweeps need the config loader: count unknown
        return None


def _combinations(params, arguments: list[str]) -> int | None:
    """The basic sweeper's rule, through Hydra's public override parser: ``params`` then
    ``arguments``, the last one of each key wins, and the jobs are the product of the
    number of values of each discrete sweep (``a,b``, ``choice``, ``range``). None for an
    interval sweep (which the basic sweeper refuses); ``glob`` (which needs the config
    loader) raises. tests/sweep/test_callback.py checks the count against Hydra's own
    (private) ``BasicSweeper.split_arguments``."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    lines = [f"{key}={value}" for key, value in flatten(params).items()]  # also when nested
    values: dict[str, int] = {}
    for override in OverridesParser.create().parse_overrides(lines + arguments):
        if not override.is_sweep_override():
            values[override.get_key_element()] = 1
        elif override.is_discrete_sweep():
            values[override.get_key_element()] = sum(1 for _ in override.sweep_string_iterator())
        else:
            return None
    return math.prod(values.values())


def _workers(config: DictConfig) -> str:
    """'on 2 worker processes', or how else the launcher runs the jobs."""
    described = describe(config.hydra.launcher)
    if described:
        return described
    n_jobs = config.hydra.launcher.get("n_jobs")
    if n_jobs is None:
        return "one after another in this process"
    n_jobs = int(n_jobs)
    if n_jobs < 0:
        import joblib

        n_jobs = max(joblib.cpu_count() + 1 + n_jobs, 1)
    return f"on {n_jobs} worker process{'es' if n_jobs != 1 else ''}"


def _in_process(launcher_cfg: Any) -> bool:
    """Whether the launcher runs the jobs in this process (Hydra's basic launcher)."""
    try:
        return str(launcher_cfg.get("_target_", "")).endswith("BasicLauncher")
    except Exception:
        return True


class SweepCallback(Callback):
    """Progress lines and the end-of-sweep summary (see the module docstring).

    ``figures``: also draw the comparison figures into ``<sweep>/comparison/`` at the end.
    ``progress``: print one line per finished job.
    ``resume``: the sweep resumes the one in its directory (set by ``resume=<sweep dir>``).
    ``strict``: exit status 1 when a job failed; false (the tuning presets): a failed job
    is a result like one that did not dock (the tuning sweeper penalises it), and only
    an aborted sweep, or one in which every job failed, exits with 1.
    """

    def __init__(
        self, figures: bool = True, progress: bool = True, resume: bool = False, strict: bool = True
    ) -> None:
        self.figures = bool(figures)
        self.progress = bool(progress)
        self.resume = bool(resume)
        self.strict = bool(strict)
        self.total: int | None = None  # set in the parent, carried to the workers by pickle

    # -- parent process
    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        # a resume: the guard checked the command against the sweep; say what it will find
        resumed = resume.status_lines(Path(str(config.hydra.sweep.dir))) if self.resume else []
        self.total = expected_jobs(config)
        sweep_dir = Path(str(config.hydra.sweep.dir))
        independent = is_submitit(config.hydra.launcher)
        session = SweepSession.current()
        session.begin(sweep_dir, self.total, independent_jobs=independent)
        jobs = "?" if self.total is None else str(self.total)
        emit(f"sweep: {jobs} jobs {_workers(config)} → {display(sweep_dir)}")
        for line in resumed:
            emit(line)
        if independent and self.progress:  # the jobs print into their own log files
            session.watch(ProgressWatcher(sweep_dir, self.total))
        if not _in_process(config.hydra.launcher):  # the summary's imports while the jobs run
            session.preload(figures=self.figures)

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        SweepSession.current().finish(
            Path(str(config.hydra.sweep.dir)), figures=self.figures, strict=self.strict
        )

    # -- worker process, after each job
    def on_job_end(self, config: DictConfig, job_return: Any, **kwargs: Any) -> None:
        from hydra.types import RunMode

        if not self.progress or config.hydra.mode != RunMode.MULTIRUN:
            return
        try:
            from hydra.core.utils import JobStatus

            out_dir = Path(str(config.hydra.runtime.output_dir))
            sweep_dir = sweep_dir_of(config.hydra)  # also with hydra.job.chdir=true
            line = job_line(out_dir, sweep_dir, self.total)
            note = job_return.return_value if job_return.status == JobStatus.COMPLETED else None
            if isinstance(note, str):  # resume: skipped, or why it ran again
                line = f"{line} · {note}"
            emit(line)
        except Exception as exc:  # progress must never fail a job
            emit(f"(progress line failed: {exc})")
