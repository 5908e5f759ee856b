"""The end of a sweep, and what it ended with: the outcome (counts, exit status), printed.

The files it leaves are written by the results layer (:mod:`compliant_docking.results.summary`,
:mod:`compliant_docking.results.figures`), as ``python -m compliant_docking.report`` writes
them for any runs. :func:`summarise` loads the sweep with :func:`compliant_docking.results.scan`, writes
``summary.{parquet,csv,md}``, ``comparison.{csv,parquet}`` and ``paired.{csv,parquet}`` (and
the comparison figures under ``comparison/``), prints how many jobs finished, docked and
failed, and returns the
:class:`SweepOutcome`: exit status 1 when any job failed (or left no metrics.json), else
0 — a job that ran but did not dock is a result, not a failure. An aborted sweep (a
worker process died, Ctrl-C, SIGTERM) is summarised the same way after every job
directory left without a result got a failed "interrupted" record (:func:`record_orphan`).
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from compliant_docking import exit_codes
from compliant_docking.sweep.progress import display, emit

#: exit status of a sweep with a failed (or vanished) job, and of a clean one
EXIT_FAILED, EXIT_OK = exit_codes.FAILED, exit_codes.OK


@dataclass
class SweepOutcome:
    """What :func:`summarise` found in a sweep directory."""

    sweep_dir: Path
    jobs: int  # finished jobs (with a metrics.json)
    ok: int
    failed: int  # status failed + directories without metrics.json
    docked: int
    unfinished: int
    aborted: bool
    summary: dict[str, Path] = field(default_factory=dict)
    strict: bool = True  # a failed job fails the sweep (false: only an aborted one, or all failed)

    @property
    def exit_status(self) -> int:
        """1 when the sweep was aborted, when a job failed (``strict``), or when every job
        failed (also not ``strict``: a tuning study that measured nothing); else 0."""
        every_job_failed = self.failed > 0 and self.failed == self.jobs + self.unfinished
        return EXIT_FAILED if ((self.failed and self.strict) or self.aborted or every_job_failed) else EXIT_OK


def summarise(
    sweep_dir: Path,
    *,
    figures: bool = True,
    aborted: bool = False,
    total: int | None = None,
    started: float | None = None,
    independent_jobs: bool = False,
    strict: bool = True,
) -> SweepOutcome:
    """Summarise the sweep in ``sweep_dir``: files, console counts, the outcome.

    ``total``: the jobs the sweep was to run (None: unknown); ``started``: its start
    (``time.perf_counter()``); ``independent_jobs``: the jobs are processes of their own
    that may outlive the launcher (submitit), so an aborted sweep writes no records for
    them; ``strict``: a failed job makes the exit status 1 (else only an aborted sweep,
    or one in which every job failed, does). Never raises for what it finds on disk; a failure to draw figures is reported
    and does not change the outcome.
    """
    from compliant_docking.results import counts, scan, write_summary

    sweep_dir = Path(sweep_dir)
    summary: dict[str, Path] = {}
    # every job directory ends with a metrics.json — except on submitit, whose jobs are
    # processes of their own that may still be running (they write theirs when done)
    if aborted and sweep_dir.is_dir() and not independent_jobs:
        remove_unstarted_job_dirs(sweep_dir)
        for job_dir in scan(sweep_dir)[1]:
            record_orphan(job_dir)
    if sweep_dir.is_dir():
        frame, unfinished = scan(sweep_dir)
    else:  # nothing ran (e.g. aborted before the first job)
        import pandas as pd

        frame, unfinished = pd.DataFrame(columns=["status", "success"]), []
    tally = counts(frame, len(unfinished))
    missing = 0
    if total is not None and aborted:
        missing = max(total - len(frame) - len(unfinished), 0)
    if sweep_dir.is_dir():
        title = f"Sweep {display(sweep_dir)}" + (" (aborted)" if aborted else "")
        try:
            summary = write_summary(frame, sweep_dir, title=title, unfinished=unfinished)
        except Exception as exc:  # the counts and the exit status must still come out
            emit(
                f"sweep: writing the summary failed ({type(exc).__name__}: {exc}); "
                f"rebuild it with `python -m compliant_docking.report {display(sweep_dir)}`"
            )
        if figures and len(frame):
            summary.update(_figures(frame, sweep_dir / "comparison"))
    outcome = SweepOutcome(
        sweep_dir=sweep_dir,
        jobs=len(frame),
        ok=tally.ok,
        failed=tally.failed + tally.unfinished,
        docked=tally.docked,
        unfinished=tally.unfinished,
        aborted=aborted,
        summary=summary,
        strict=strict,
    )
    _report(outcome, tally, frame, missing, started, independent_jobs)
    return outcome


def _figures(frame, out_dir: Path) -> dict[str, Path]:
    try:
        from compliant_docking.results.figures import plot_comparison

        return {p.name: p for p in plot_comparison(frame, out_dir)}
    except Exception as exc:  # figures are a convenience; the tables are the record
        emit(
            f"sweep: comparison figures failed ({type(exc).__name__}: {exc}); "
            f"rebuild them with `python -m compliant_docking.report`"
        )
        return {}


def _report(
    outcome: SweepOutcome, tally, frame, missing: int, started: float | None, independent_jobs: bool
) -> None:
    elapsed = f" in {time.perf_counter() - started:.1f} s" if started else ""
    head = "sweep ABORTED" if outcome.aborted else "sweep finished"
    lines = ["=" * 64, f"{head}{elapsed}: {tally.line()}"]
    if missing:
        lines.append(f"  {missing} more jobs never started")
    if outcome.aborted:  # how to finish it (compliant_docking/sweep/resume.py)
        again = f"the same command with resume={display(outcome.sweep_dir)}"
        lines.append(
            f"  jobs may still be running (submitit); when they are done: {again}"
            if independent_jobs
            else f"  to finish it: {again}"
        )
    from compliant_docking.results.tables import FAILED_STATUSES

    failed = frame[frame["status"].isin(FAILED_STATUSES)] if len(frame) else frame
    for _, row in failed.iterrows():
        lines.append(f"  FAILED {row['job']}: {row.get('error')}")
    if outcome.summary.get("summary.md"):
        table = _comparison_text(outcome.summary["summary.md"]) if tally.ok + tally.incomplete else ""
        if table:
            lines.append(table)
        lines.append(
            f"  summary: {display(outcome.summary['summary.md'])} "
            f"(+ summary.csv/.parquet, comparison.csv/.parquet, paired.csv/.parquet)"
        )
    lines.append("=" * 64)
    emit("\n".join(lines))


def _comparison_text(summary_md: Path, max_width: int = 160) -> str:
    """From summary.md: the configurations table (jobs, docked, success rate with its
    interval) when it fits a terminal, and the paired comparisons in words; else ''."""
    import shutil

    text = summary_md.read_text(encoding="utf-8")
    parts = []
    start = text.find("## Configurations")
    if start >= 0:
        block = text[start:].split("\n## ", 1)[0]
        table = "\n".join(line for line in block.splitlines() if line.startswith("|"))
        width = max((len(line) for line in table.splitlines()), default=0)
        limit = max(shutil.get_terminal_size((max_width, 24)).columns, max_width)
        if 0 < width <= limit and table.count("\n") > 2:  # more than one configuration
            parts.append(table)
    start = text.find("## Paired comparisons")
    if start >= 0:
        block = text[start:].split("\n## ", 1)[0].split("\n### ", 1)[0]
        # each metric and its significant differences; the others are named in summary.md
        words = [
            line
            for line in block.splitlines()
            if line.startswith("- **") or (line.startswith("  - ") and not line.startswith("  - not "))
        ]
        if words:
            parts.append(
                "paired comparisons (Holm-corrected, 5 %; the rest in summary.md):\n" + "\n".join(words)
            )
    return "\n".join(parts)


ORPHAN_ERROR = (
    "interrupted: no result, the sweep was aborted while this job ran (its "
    "worker process died, e.g. a segmentation fault in it or in a sibling job, "
    "or the sweep was interrupted: Ctrl-C, SIGTERM); resume=<sweep dir> reruns it"
)


def remove_unstarted_job_dirs(sweep_dir: Path) -> list[Path]:
    """Remove the empty directories of jobs whose worker was killed between creating the
    job's directory and writing its ``.hydra/`` (a window of Hydra's job start): nothing of
    the job exists yet, so it is a job that never started (counted as missing, and a resume
    runs it), not a job directory without a record. Only a ``<job number>_…`` folder of
    ``sweep_dir`` with no file anywhere below it is removed (an empty ``.hydra/``
    included; ``os.rmdir`` never removes anything else); returns the folders removed."""
    import re

    removed = []
    for top in sorted(sweep_dir.iterdir()):
        if not (top.is_dir() and re.match(r"\d+_", top.name)):
            continue
        tree = list(os.walk(top, topdown=False))
        if any(files for _, _, files in tree):  # something of the job exists: kept
            continue
        for current, _, _ in tree:  # bottom-up: every folder empty by the time it is reached
            try:
                Path(current).rmdir()
                removed.append(Path(current))
            except OSError:  # written meanwhile (or not ours to remove): kept
                pass
    return removed


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

    from compliant_docking.evaluation.registry import compared
    from compliant_docking.run.files import temporary_name
    from compliant_docking.run.rundir import METRICS_FILE, read_overrides

    record: dict = {"status": "failed", "error": ORPHAN_ERROR, "success": False, "interrupted": True}
    try:
        hydra_cfg = yaml.safe_load((job_dir / ".hydra" / "hydra.yaml").read_text(encoding="utf-8"))
        choices = hydra_cfg["hydra"]["runtime"]["choices"]
        overrides = hydra_cfg["hydra"]["overrides"]["task"]
    except Exception:
        choices, overrides = {}, [f"{k}={v}" for k, v in read_overrides(job_dir).items()]
    record["overrides"] = " ".join(overrides) or None
    for group in ("robot", "controller", "trajectory", "tool", "target", "physics", "task"):
        record[group] = choices.get(group)
    record.update({m.key: None for m in compared()})
    path = job_dir / METRICS_FILE
    tmp = temporary_name(path)
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
