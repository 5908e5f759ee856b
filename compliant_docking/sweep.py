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
_state: dict[str, Any] = {"sweep_dir": None, "total": None, "outcome": None, "started": None}


def reset() -> None:
    """Forget the sweep state of this process (``__main__.main()`` calls it first)."""
    _state.update(sweep_dir=None, total=None, outcome=None, started=None)


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
    """

    def __init__(self, figures: bool = True, progress: bool = True) -> None:
        self.figures = bool(figures)
        self.progress = bool(progress)
        self.total: int | None = None  # set in the parent, carried to the workers by pickle

    # -- parent process
    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        self.total = expected_jobs(config)
        sweep_dir = Path(str(config.hydra.sweep.dir))
        _state.update(sweep_dir=sweep_dir, total=self.total, outcome=None,
                      started=time.perf_counter())
        jobs = "?" if self.total is None else str(self.total)
        _print(f"sweep: {jobs} jobs {_workers(config)} → {_display(sweep_dir)}")

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        finish(Path(str(config.hydra.sweep.dir)), figures=self.figures)

    # -- worker process, after each job
    def on_job_end(self, config: DictConfig, job_return: Any, **kwargs: Any) -> None:
        from hydra.types import RunMode

        if not self.progress or config.hydra.mode != RunMode.MULTIRUN:
            return
        try:
            out_dir = Path(str(config.hydra.runtime.output_dir))
            sweep_dir = Path(str(config.hydra.sweep.dir)).resolve()
            _print(job_line(out_dir, sweep_dir, self.total))
        except Exception as exc:  # progress must never fail a job
            _print(f"(progress line failed: {exc})")


def _print(text: str) -> None:
    print(text, flush=True)


def _display(path: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def finished_count(sweep_dir: Path, depth: int = 1) -> int:
    """Job directories ``depth`` levels below ``sweep_dir`` that hold a metrics.json."""
    return sum(1 for _ in Path(sweep_dir).glob("*/" * depth + "metrics.json"))


def job_line(out_dir: Path, sweep_dir: Path, total: int | None) -> str:
    """``[3/6] 2_controller=hqp,robot=fr3 · ok · docked · peak 12.3 N · 4.2 s``."""
    from compliant_docking.results import read_metrics

    record, problem = read_metrics(out_dir)
    try:
        depth = len(out_dir.resolve().relative_to(sweep_dir).parts)
    except ValueError:
        depth = 1
    done = finished_count(sweep_dir, depth)
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
    if aborted and sweep_dir.is_dir():  # every job directory ends with a metrics.json
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


ORPHAN_ERROR = ("no result: the sweep was aborted while this job ran (its worker process "
                "died, e.g. a segmentation fault in it or in a sibling job, or the sweep was "
                "interrupted); see the sweep's console output")


def record_orphan(job_dir: Path) -> None:
    """Give a job directory left without metrics.json (its process died) a failed record.

    Written only by the process that launched the sweep, after its workers are gone,
    so the contract "every job directory ends with a metrics.json" holds after a crash.
    """
    import json

    import yaml

    from compliant_docking.results import METRICS_FILE, TABLE10, read_overrides

    record: dict = {"status": "failed", "error": ORPHAN_ERROR, "success": False}
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
        os.replace(tmp, path)
    except OSError as exc:
        print(f"sweep: could not write {path}: {exc}", file=sys.stderr)


def finish_aborted() -> SweepOutcome | None:
    """Summarise a sweep that Hydra aborted (worker crash, Ctrl-C); None if none ran."""
    sweep_dir = _state.get("sweep_dir")
    if sweep_dir is None or _state.get("outcome") is not None:
        return None
    try:
        return finish(sweep_dir, figures=False, aborted=True)
    except Exception as exc:  # never mask the original error
        print(f"sweep: could not summarise the aborted sweep: {exc}", file=sys.stderr)
        return None

