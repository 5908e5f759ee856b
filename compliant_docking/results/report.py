"""``python -m compliant_docking.report PATH``: tables and comparison figures for runs.

PATH is anything :func:`compliant_docking.results.load_runs` reads: one run directory,
a sweep directory, a tree of them, or all of ``runs/``. Writes into PATH (or ``--out``):

- ``summary.parquet``, ``summary.csv``: one row per job (the load_runs frame);
- ``comparison.csv``, ``summary.md``: the Table-10 comparison, one column per
  configuration (summary.md also lists every job);
- ``comparison/``: ``table10_bars``, ``success_vs_misalignment`` (when the
  misalignment varies), ``force_overlay`` (PNG + PDF).

and prints summary.md's counts and comparison. Exit status: 0 when at least one
finished run was found, 2 when none was (or PATH does not exist).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from compliant_docking.results.load import RunSkippedWarning, scan
from compliant_docking.results.tables import counts, write_summary


def main(argv: list[str] | None = None) -> int:
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
    parser.add_argument("--no-figures", action="store_true", help="tables only")
    args = parser.parse_args(argv)

    path = Path(args.path)
    if not path.exists():
        print(f"report: no such directory: {path}", file=sys.stderr)
        return 2
    frame, skipped = scan(path)
    for job_dir in skipped:
        print(f"report: skipped {job_dir}: no finished metrics.json", file=sys.stderr)
    if frame.empty:
        print(f"report: no finished runs under {path}", file=sys.stderr)
        return 2
    out = args.out or (path if path.is_dir() else path.parent)
    paths = write_summary(frame, out, title=f"Runs in {path}", unfinished=skipped)
    if not args.no_figures:
        from compliant_docking.results.figures import plot_comparison

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RunSkippedWarning)
            figures = plot_comparison(frame, out / "comparison")
    else:
        figures = []
    text = paths["summary.md"].read_text(encoding="utf-8")
    print(text.split("\n## Jobs", 1)[0].rstrip())
    print(f"\n{counts(frame, len(skipped)).line()}")
    print(
        f"wrote {', '.join(p.name for p in paths.values())} to {out}"
        + (f" and {len(figures)} figure files to {out / 'comparison'}" if figures else "")
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
