"""``python -m compliant_docking.report PATH``: tables and comparison figures for runs (the
command and its function :func:`main`).

PATH is anything :func:`compliant_docking.results.load_runs` reads: one run directory,
a sweep directory, a tree of them, or all of ``runs/``. Writes into PATH (or ``--out``):

- ``summary.parquet``, ``summary.csv``: one row per job (the load_runs frame);
- ``comparison.csv``, ``summary.md``: the docking-metrics comparison, one column per
  configuration (summary.md also lists every job);
- ``comparison/``: ``table10_bars``, ``success_vs_misalignment`` (when the
  misalignment varies), ``force_overlay`` (PNG; ``--formats png pdf`` for PDF too);
- with ``--runs``: each run's own ``figures/`` (tracking, errors, contact force,
  joint torques), from its time series — the figures a sweep job leaves out by
  default; written in each run directory, whatever ``--out`` says.

and prints summary.md's counts and comparison. A job directory whose metrics.json is
missing or broken, or whose time series cannot be read, is skipped with a message
naming it. Exit status: 0 when at least one finished run was found, 2 when none was,
PATH does not exist, a format is unknown, or the tables cannot be written there (a
read-only directory: ``--out DIR`` writes them elsewhere).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from compliant_docking import exit_codes
from compliant_docking.results.load import RunSkippedWarning, scan
from compliant_docking.results.summary import write_summary
from compliant_docking.results.tables import counts
from compliant_docking.run.directories import write_problem
from compliant_docking.run.rundir import read_metrics


def main(argv: list[str] | None = None) -> int:
    """``python -m compliant_docking.report``; the exit status (a signal: 128 + its number)."""
    from compliant_docking.run import interrupt

    return interrupt.handled("report", lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m compliant_docking.report",
        description="Rebuild the summary tables and comparison figures of a directory of runs.",
    )
    parser.add_argument(
        "path",
        nargs="?",
        default="runs",
        help="a run directory, a sweep directory, or a tree of them (default: runs)",
    )
    parser.add_argument(
        "--out", type=Path, default=None, help="where to write the tables and comparison/ (default: PATH)"
    )
    parser.add_argument("--no-figures", action="store_true", help="no comparison figures")
    parser.add_argument(
        "--runs",
        action="store_true",
        help="also draw each run's own figures into its figures/ folder (sweep jobs skip them by default)",
    )
    parser.add_argument(
        "--formats",
        nargs="+",
        default=["png"],
        metavar="FORMAT",
        help="file formats of the figures: png, pdf, svg (default: png)",
    )
    args = parser.parse_args(argv)

    path = Path(args.path)
    if not path.exists():
        print(f"report: no such directory: {path}", file=sys.stderr)
        return exit_codes.REFUSED
    from compliant_docking.viz.style import check_formats

    try:
        formats = check_formats(args.formats)
    except ValueError as exc:
        print(f"report: --formats: {exc}", file=sys.stderr)
        return exit_codes.REFUSED
    frame, skipped = scan(path)
    for job_dir in skipped:
        print(f"report: skipped {job_dir}: {read_metrics(job_dir)[1]}", file=sys.stderr)
    if frame.empty:
        print(f"report: no finished runs under {path}", file=sys.stderr)
        return exit_codes.REFUSED
    out = args.out or (path if path.is_dir() else path.parent)
    problem = write_problem(out)
    if problem:
        print(
            f"report: cannot write into {out}: {problem}; write the tables and figures "
            "elsewhere with --out DIR",
            file=sys.stderr,
        )
        return exit_codes.REFUSED
    with warnings.catch_warnings(record=True) as caught:  # broken files: skipped, each said
        warnings.simplefilter("always", RunSkippedWarning)
        try:
            paths = write_summary(frame, out, title=f"Runs in {path}", unfinished=skipped)
            figures = [] if args.no_figures else _figures(frame, out / "comparison", formats)
        except OSError as exc:
            print(
                f"report: cannot write into {out} ({exc.strerror or exc}); write the tables and "
                "figures elsewhere with --out DIR",
                file=sys.stderr,
            )
            return exit_codes.REFUSED
    for warning in caught:
        if issubclass(warning.category, RunSkippedWarning):
            print(f"report: {warning.message}", file=sys.stderr)
    drawn = draw_runs(frame, formats) if args.runs else 0
    text = paths["summary.md"].read_text(encoding="utf-8")
    print(text.split("\n## Jobs", 1)[0].rstrip())
    print(f"\n{counts(frame, len(skipped)).line()}")
    print(
        f"wrote {', '.join(p.name for p in paths.values())} to {out}"
        + (f" and {len(figures)} figure files to {out / 'comparison'}" if figures else "")
    )
    if args.runs:
        print(f"drew the figures of {drawn} of {len(frame)} runs (into <run>/figures/)")
    return 0


def draw_runs(frame, formats) -> int:
    """Each run's own figures (:func:`compliant_docking.run.figures.redraw`); how many
    runs got them. A run that cannot be drawn (failed before its time series, a broken
    time series, a directory it cannot write) is named on stderr and skipped."""
    from compliant_docking.run.figures import redraw

    drawn = 0
    for run_dir in frame["run_dir"]:
        try:
            redraw(Path(run_dir), formats)
            drawn += 1
        except (ValueError, OSError) as exc:
            print(f"report: no figures for {run_dir}: {exc}", file=sys.stderr)
    return drawn


def _figures(frame, out_dir: Path, formats) -> list[Path]:
    from compliant_docking.results.figures import plot_comparison

    return plot_comparison(frame, out_dir, formats)


if __name__ == "__main__":
    sys.exit(main())
