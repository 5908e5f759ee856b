"""Sweeps (``python -m compliant_docking -m …``): progress lines, the summary, the exit status.

With the joblib launcher the jobs run in loky worker processes, so the launching
process never sees their records. Everything here therefore reads the sweep directory:

- :class:`SweepCallback` (configured under ``hydra.callbacks.sweep`` in conf/config.yaml)
  prints a header when the sweep starts (parent process); after each job, in the worker
  that ran it, one line with the job's name, status, docked or not, peak axial force
  and wall time, and a running count ``[finished/total]`` (the finished metrics.json
  files in the sweep directory); when the sweep ends (parent), :func:`finish` writes
  the summary and prints the counts.
- :func:`finish` loads the sweep with :func:`compliant_docking.results.scan`, writes
  ``summary.{parquet,csv,md}`` and ``comparison.csv`` (and the comparison figures under
  ``comparison/``), prints how many jobs succeeded, failed and docked, and stores the
  outcome for ``__main__.main()``: exit status 1 when any job failed (or left no
  metrics.json), else 0 — a job that ran but did not dock is a result, not a failure.
- A sweep cut short (a worker process died, e.g. a segfault: joblib raises
  ``TerminatedWorkerError`` in the parent and Hydra aborts, skipping
  ``on_multirun_end``; or Ctrl-C) is finished by :func:`finish_aborted`, called by
  ``__main__.main()``: the summary of whatever finished is written all the same and the
  exit status is 1.
- ``resume=<sweep dir>`` (compliant_docking/resume.py) runs a sweep again into its own
  directory: :meth:`SweepCallback.on_multirun_start` checks the command against the
  sweep's ``multirun.yaml`` first; jobs kept untouched print ``skipped``.
- On the submitit launchers (compliant_docking/launchers.py) every job prints into its
  own log file, so the launching process prints the progress lines (a
  :class:`~compliant_docking.launchers.ProgressWatcher`); an aborted submitit sweep
  writes no "interrupted" records, since its jobs may still be running.

This module is imported by the launching process and by every worker: keep it light.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig

#: exit status of a sweep with a failed (or vanished) job, and of a clean one
EXIT_FAILED, EXIT_OK = 1, 0


@dataclass
class SweepOutcome:
    """What :func:`finish` found in a sweep directory."""

    sweep_dir: Path
    jobs: int  # finished jobs (with a metrics.json)
    ok: int
    failed: int  # status failed + directories without metrics.json
    docked: int
    unfinished: int
    aborted: bool
    summary: dict[str, Path]

    @property
    def exit_status(self) -> int:
        return EXIT_FAILED if (self.failed or self.aborted) else EXIT_OK


#: state of the sweep of this process (the launching one): set by the callback
_state: dict[str, Any] = {"sweep_dir": None, "total": None, "outcome": None, "started": None,
                          "watcher": None, "independent_jobs": False}


def reset() -> None:
    """Forget the sweep state of this process (``__main__.main()`` calls it first)."""
    _state.update(sweep_dir=None, total=None, outcome=None, started=None, watcher=None,
                  independent_jobs=False)


def last_outcome() -> SweepOutcome | None:
    """The outcome of the sweep this process ran (None after a single run)."""
    return _state["outcome"]


def expected_jobs(config: DictConfig) -> int | None:
    """How many jobs Hydra's basic sweeper will launch for ``config`` (None if unknown)."""
    try:
        from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
        from hydra.core.override_parser.overrides_parser import OverridesParser

        sweeper = config.hydra.sweeper
        if not str(sweeper.get("_target_", "")).endswith("BasicSweeper"):
            return None
        params = [f"{k}={v}" for k, v in (sweeper.get("params") or {}).items()]
        params += list(config.hydra.overrides.task)
        overrides = OverridesParser.create().parse_overrides(params)
        batches = BasicSweeper.split_arguments(overrides, None)
        return sum(len(batch) for batch in batches)
    except Exception:  # e.g. glob() sweeps need the config loader: count unknown
        return None


def _workers(config: DictConfig) -> str:
    """'on 2 worker processes', or how else the launcher runs the jobs."""
    from compliant_docking.launchers import describe

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


class SweepCallback(Callback):
    """Progress lines and the end-of-sweep summary (see the module docstring).

    ``figures``: also draw the comparison figures into ``<sweep>/comparison/`` at the end.
    ``progress``: print one line per finished job.
    ``resume``: the sweep resumes the one in its directory (set by ``resume=<sweep dir>``).
    """

    def __init__(self, figures: bool = True, progress: bool = True, resume: bool = False) -> None:
        self.figures = bool(figures)
        self.progress = bool(progress)
        self.resume = bool(resume)
        self.total: int | None = None  # set in the parent, carried to the workers by pickle

    # -- parent process
    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        resumed: list[str] = []
        if self.resume:  # before anything is written; SystemExit passes Hydra's callback guard
            from compliant_docking import resume

            try:
                resumed = resume.check_sweep(config)
            except resume.ResumeError as exc:
                raise SystemExit(resume.fail(exc)) from None
        from compliant_docking.launchers import ProgressWatcher, is_submitit

        self.total = expected_jobs(config)
        sweep_dir = Path(str(config.hydra.sweep.dir))
        independent = is_submitit(config.hydra.launcher)
        _state.update(sweep_dir=sweep_dir, total=self.total, outcome=None,
                      started=time.perf_counter(), independent_jobs=independent)
        jobs = "?" if self.total is None else str(self.total)
        _print(f"sweep: {jobs} jobs {_workers(config)} → {_display(sweep_dir)}")
        for line in resumed:
            _print(line)
        if independent and self.progress:  # the jobs print into their own log files
            _state["watcher"] = ProgressWatcher(sweep_dir, self.total).start()

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        _stop_watcher()
        finish(Path(str(config.hydra.sweep.dir)), figures=self.figures)

    # -- worker process, after each job
    def on_job_end(self, config: DictConfig, job_return: Any, **kwargs: Any) -> None:
        from hydra.types import RunMode

        if not self.progress or config.hydra.mode != RunMode.MULTIRUN:
            return
        try:
            from hydra.core.utils import JobStatus

            from compliant_docking.resume import SKIPPED

            out_dir = Path(str(config.hydra.runtime.output_dir))
            sweep_dir = Path(str(config.hydra.sweep.dir)).resolve()
            line = job_line(out_dir, sweep_dir, self.total)
            if job_return.status == JobStatus.COMPLETED and job_return.return_value == SKIPPED:
                line = f"{line} · {SKIPPED}"
            _print(line)
        except Exception as exc:  # progress must never fail a job
            _print(f"(progress line failed: {exc})")


def _stop_watcher() -> None:
    watcher = _state.get("watcher")
    if watcher is not None:
        _state["watcher"] = None
        watcher.stop()


def _print(text: str) -> None:
    print(text, flush=True)


def _display(path: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def finished_rank(out_dir: Path, sweep_dir: Path, depth: int = 1) -> int:
    """The job's place among the finished jobs of the sweep: how many metrics.json files
    ``depth`` levels below ``sweep_dir`` were written no later than its own (by
    modification time, then path). Unlike a plain count, two workers finishing at the
    same moment still get different numbers."""
    def key(path: Path) -> tuple[int, str]:
        try:
            return path.stat().st_mtime_ns, str(path)
        except OSError:  # replaced while we looked
            return 0, str(path)

    own = key(Path(out_dir) / "metrics.json")
    return sum(1 for p in Path(sweep_dir).glob("*/" * depth + "metrics.json") if key(p) <= own)


def job_line(out_dir: Path, sweep_dir: Path, total: int | None, done: int | None = None) -> str:
    """``[3/6] 2_controller=hqp,robot=fr3 · ok · docked · peak 12.3 N · 4.2 s``.

    ``done``: the running count; by default the job's rank among the finished jobs.
    """
    from compliant_docking.results import read_metrics

    record, problem = read_metrics(out_dir)
    try:
        depth = len(out_dir.resolve().relative_to(sweep_dir).parts)
    except ValueError:
        depth = 1
    if done is None:
        done = finished_rank(out_dir, sweep_dir, depth)
    count = f"[{done}/{total}]" if total else f"[{done} done]"
    if record is None:
        return f"{count} {out_dir.name} · {problem}"
    status = record.get("status")
    success = record.get("success")
    docked = {True: "docked", False: "not docked", None: "no gate"}.get(success, str(success))
    parts = [f"{count} {out_dir.name}", "FAILED" if status == "failed" else str(status)]
    if status != "failed":
        parts.append(docked)
        peak = record.get("peak_axial_force_N")
        parts.append("peak n/a" if peak is None else f"peak {peak:.1f} N")
    wall = record.get("wall_time_s")
    parts.append("n/a" if wall is None else f"{wall:.1f} s")
    if status == "failed" and record.get("error"):
        parts.append(str(record["error"])[:160])
    return " · ".join(parts)


def finish(sweep_dir: Path, *, figures: bool = True, aborted: bool = False) -> SweepOutcome:
    """Summarise the sweep in ``sweep_dir``: files, console counts, the stored outcome.

    Never raises for what it finds on disk; a failure to draw figures is reported and
    does not change the outcome.
    """
    from compliant_docking.results import counts, scan, write_summary

    sweep_dir = Path(sweep_dir)
    summary: dict[str, Path] = {}
    # every job directory ends with a metrics.json — except on submitit, whose jobs are
    # processes of their own that may still be running (they write theirs when done)
    if aborted and sweep_dir.is_dir() and not _state.get("independent_jobs"):
        for job_dir in scan(sweep_dir)[1]:
            record_orphan(job_dir)
    if sweep_dir.is_dir():
        frame, unfinished = scan(sweep_dir)
    else:  # nothing ran (e.g. aborted before the first job)
        import pandas as pd

        frame, unfinished = pd.DataFrame(columns=["status", "success"]), []
    tally = counts(frame, len(unfinished))
    missing = 0
    total = _state.get("total") if _state.get("sweep_dir") == sweep_dir else None
    if total is not None and aborted:
        missing = max(total - len(frame) - len(unfinished), 0)
    if sweep_dir.is_dir():
        title = f"Sweep {_display(sweep_dir)}" + (" (aborted)" if aborted else "")
        try:
            summary = write_summary(frame, sweep_dir, title=title, unfinished=unfinished)
        except Exception as exc:  # the counts and the exit status must still come out
            _print(f"sweep: writing the summary failed ({type(exc).__name__}: {exc}); "
                   f"rebuild it with `python -m compliant_docking.report {_display(sweep_dir)}`")
        if figures and len(frame):
            summary.update(_figures(frame, sweep_dir / "comparison"))
    outcome = SweepOutcome(sweep_dir=sweep_dir, jobs=len(frame), ok=tally.ok,
                           failed=tally.failed + tally.unfinished, docked=tally.docked,
                           unfinished=tally.unfinished, aborted=aborted, summary=summary)
    _state["outcome"] = outcome
    _report(outcome, tally, frame, missing)
    return outcome


def _figures(frame, out_dir: Path) -> dict[str, Path]:
    try:
        from compliant_docking.comparison_plots import plot_comparison

        return {p.name: p for p in plot_comparison(frame, out_dir)}
    except Exception as exc:  # figures are a convenience; the tables are the record
        _print(f"sweep: comparison figures failed ({type(exc).__name__}: {exc}); "
               f"rebuild them with `python -m compliant_docking.report`")
        return {}


def _report(outcome: SweepOutcome, tally, frame, missing: int) -> None:
    started = _state.get("started")
    elapsed = f" in {time.perf_counter() - started:.1f} s" if started else ""
    head = "sweep ABORTED" if outcome.aborted else "sweep finished"
    lines = ["=" * 64, f"{head}{elapsed}: {tally.line()}"]
    if missing:
        lines.append(f"  {missing} more jobs never started")
    if outcome.aborted:  # how to finish it (compliant_docking/resume.py)
        again = f"the same command with resume={_display(outcome.sweep_dir)}"
        lines.append(f"  jobs may still be running (submitit); when they are done: {again}"
                     if _state.get("independent_jobs") else f"  to finish it: {again}")
    failed = frame[frame["status"] == "failed"] if len(frame) else frame
    for _, row in failed.iterrows():
        lines.append(f"  FAILED {row['job']}: {row.get('error')}")
    if outcome.summary.get("summary.md"):
        table = (_comparison_text(outcome.summary["summary.md"])
                 if tally.ok + tally.incomplete else "")
        if table:
            lines.append(table)
        lines.append(f"  summary: {_display(outcome.summary['summary.md'])} "
                     f"(+ summary.csv, summary.parquet, comparison.csv)")
    lines.append("=" * 64)
    _print("\n".join(lines))


def _comparison_text(summary_md: Path, max_width: int = 160) -> str:
    """The comparison table of summary.md when it fits a terminal, else ''."""
    import shutil

    text = summary_md.read_text(encoding="utf-8")
    start = text.find("## Comparison")
    if start < 0:
        return ""
    block = text[start:].split("\n## ", 1)[0]
    table = "\n".join(line for line in block.splitlines() if line.startswith("|"))
    width = max((len(line) for line in table.splitlines()), default=0)
    limit = max(shutil.get_terminal_size((max_width, 24)).columns, max_width)
    return table if 0 < width <= limit else ""


ORPHAN_ERROR = ("interrupted: no result, the sweep was aborted while this job ran (its "
                "worker process died, e.g. a segmentation fault in it or in a sibling job, "
                "or the sweep was interrupted: Ctrl-C, SIGTERM); resume=<sweep dir> reruns it")


def record_orphan(job_dir: Path) -> None:
    """Give a job directory left without metrics.json (its process died) a failed record.

    Written only by the process that launched the sweep, after its workers are gone,
    so the contract "every job directory ends with a metrics.json" holds after a crash.
    Never replaces a metrics.json that appeared meanwhile (a hard link fails on an
    existing name); the record is status failed with ``interrupted: true``, and a resume
    reruns the job.
    """
    import json

    import yaml

    from compliant_docking.results import METRICS_FILE, TABLE10, read_overrides

    record: dict = {"status": "failed", "error": ORPHAN_ERROR, "success": False,
                    "interrupted": True}
    try:
        hydra_cfg = yaml.safe_load((job_dir / ".hydra" / "hydra.yaml").read_text(encoding="utf-8"))
        choices = hydra_cfg["hydra"]["runtime"]["choices"]
        overrides = hydra_cfg["hydra"]["overrides"]["task"]
    except Exception:
        choices, overrides = {}, [f"{k}={v}" for k, v in read_overrides(job_dir).items()]
    record["overrides"] = " ".join(overrides) or None
    for group in ("robot", "controller", "trajectory", "tool", "target", "physics", "task"):
        record[group] = choices.get(group)
    record.update({row.key: None for row in TABLE10})
    path = job_dir / METRICS_FILE
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        tmp.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
        try:
            os.link(tmp, path)  # atomic, and never over a result written meanwhile
        except FileExistsError:
            pass
        except OSError:  # a file system without hard links
            if not path.exists():
                os.replace(tmp, path)
        tmp.unlink(missing_ok=True)
    except OSError as exc:
        print(f"sweep: could not write {path}: {exc}", file=sys.stderr)


def finish_aborted() -> SweepOutcome | None:
    """Summarise a sweep that Hydra aborted (worker crash, Ctrl-C); None if none ran."""
    _stop_watcher()
    sweep_dir = _state.get("sweep_dir")
    if sweep_dir is None or _state.get("outcome") is not None:
        return None
    try:
        return finish(sweep_dir, figures=False, aborted=True)
    except Exception as exc:  # never mask the original error
        print(f"sweep: could not summarise the aborted sweep: {exc}", file=sys.stderr)
        return None

