"""Runs → pandas tables, comparisons and figures (the orchestration side; no MuJoCo).

- :mod:`.load`: :func:`load_runs` (one row per job directory), :func:`scan`,
  :func:`newest_sweep`, :func:`locate_runs`;
- :mod:`.tables`: configurations and their labels, the docking-metrics comparison table, counts;
- :mod:`.stats`: Wilson and bootstrap intervals, paired tests, Holm's correction;
- :mod:`.compare`: per-configuration statistics and paired comparisons of a frame;
- :mod:`.summary`: ``summary.md`` and the summary files;
- :mod:`.figures`: comparison figures across runs;
- :mod:`.report`: ``python -m compliant_docking.report PATH``.
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
