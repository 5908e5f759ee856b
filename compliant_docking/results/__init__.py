"""Runs → pandas tables, comparisons and figures (the orchestration side; no MuJoCo).

- :mod:`.load`: :func:`load_runs` (one row per job directory), :func:`scan`,
  :func:`newest_sweep`, :func:`locate_runs`;
- :mod:`.tables`: configurations and their labels, the docking-metrics comparison table, counts;
- :mod:`.stats`: Wilson and bootstrap intervals, paired tests, Holm's correction;
- :mod:`.compare`: per-configuration statistics and paired comparisons of a frame;
- :mod:`.summary`: ``summary.md`` and the summary files of a set of runs;
- :mod:`.figures`: the figures comparing runs, one module per what they show (the metrics'
  bars, success against the drawn errors, the contact force, the peg-in-hole curves);
- :mod:`.findings`, :mod:`.convergence`, :mod:`.peg_in_hole`, :mod:`.jamming_map`: the
  analyses with a command of their own.

The command that writes the summary files and the figures of any runs is
``python -m compliant_docking.report PATH`` (:mod:`compliant_docking.report`).
"""

from compliant_docking.results.compare import configuration_stats, paired_comparisons
from compliant_docking.results.load import (
    BASE_COLUMNS,
    GROUPS,
    RunSkippedWarning,
    load_runs,
    locate_runs,
    newest_sweep,
    scan,
    sweep_started,
)
from compliant_docking.results.summary import summary_markdown, write_summary
from compliant_docking.results.tables import (
    Counts,
    comparison_markdown,
    comparison_table,
    configuration_keys,
    configuration_labels,
    counts,
    jobs_markdown,
)

__all__ = [
    "BASE_COLUMNS",
    "GROUPS",
    "Counts",
    "RunSkippedWarning",
    "comparison_markdown",
    "comparison_table",
    "configuration_keys",
    "configuration_labels",
    "configuration_stats",
    "counts",
    "jobs_markdown",
    "load_runs",
    "locate_runs",
    "newest_sweep",
    "paired_comparisons",
    "scan",
    "sweep_started",
    "summary_markdown",
    "write_summary",
]
