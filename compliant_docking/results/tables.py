"""The comparison of a set of runs: configurations, the metrics table, counts and the sweep
summary files (``summary.parquet``, ``summary.csv``, ``comparison.csv``, ``summary.md``).

:func:`comparison_table` turns the rows of :func:`~compliant_docking.results.load.load_runs`
into one column per configuration and one row per compared metric of the registry
(:mod:`compliant_docking.evaluation.registry`), grouped by section, plus the outcome;
:func:`write_summary` writes the files.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np
import pandas as pd

from compliant_docking.evaluation.registry import compared
from compliant_docking.results.load import GROUPS
from compliant_docking.run.files import atomic_write

#: files written by :func:`write_summary`
SUMMARY_FILES = ("summary.parquet", "summary.csv", "comparison.csv", "summary.md")

SUCCESS_SECTION = "success"
#: keys that repeat a configuration rather than define one
REPEAT_KEYS = re.compile(r"(^|\.)seed$")
#: overrides that change how a job reports, not what it simulates
COSMETIC_KEYS = frozenset({"task.progress"})
#: statuses counted as failed: an error, or a run stopped by Ctrl-C / SIGTERM
FAILED_STATUSES = ("failed", "interrupted")
#: statuses whose metrics do not measure a whole run (left out of the comparison's means)
NOT_MEASURED = ("interrupted",)


def configuration_keys(df: pd.DataFrame) -> list[str]:
    """The columns that tell the configurations of ``df`` apart.

    Candidates are the config choices (``robot``, ``controller``, …, ``experiment``)
    and the dotted override columns (``controller.k``, ``task.misalignment.x_range``;
    metrics.json keys are never dotted); kept are those whose value varies across the
    rows, except repeat keys (any ``…seed``): repeats of one configuration are pooled
    (success rate, means), and cosmetic keys (``task.progress``).
    """
    if df.empty:
        return []
    candidates = [g for g in GROUPS if g in df.columns]
    candidates += [c for c in df.columns if "." in c and c not in candidates]
    return [
        c
        for c in candidates
        if not REPEAT_KEYS.search(c)
        and c not in COSMETIC_KEYS
        and df[c].astype(str).nunique(dropna=False) > 1
    ]


def _short(key: str, keys: list[str]) -> str:
    last = key.rsplit(".", 1)[-1]
    clash = sum(1 for k in keys if k.rsplit(".", 1)[-1] == last) > 1
    return key if clash else last


def _format_value(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "default"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def configuration_labels(df: pd.DataFrame, keys: list[str] | None = None) -> pd.Series:
    """A readable label per row: the values of :func:`configuration_keys`, ' · '-joined.

    Config choices show their value alone (``fr3 · hqp``), other keys as
    ``short_key=value`` (``radial_clearance=0.0004``). With nothing varying, every row
    is labelled by its choices ``robot · controller · trajectory``.
    """
    keys = configuration_keys(df) if keys is None else keys
    if not keys:
        keys = [g for g in ("robot", "controller", "trajectory") if g in df.columns]

    def label(row) -> str:
        parts = []
        for key in keys:
            value = _format_value(row.get(key))
            parts.append(value if key in GROUPS else f"{_short(key, keys)}={value}")
        return " · ".join(parts) or str(row.get("job"))

    return df.apply(label, axis=1) if len(df) else pd.Series([], dtype=object)


def comparison_table(df: pd.DataFrame, keys: list[str] | None = None) -> pd.DataFrame:
    """The Table-10 comparison: one column per configuration, rows (section, metric).

    Metrics are the mean over the finished jobs of a configuration (repeats: seeds),
    in display units (mm, deg, N, %); the ``success`` section holds ``jobs``,
    ``failed`` (status failed or interrupted), ``docked`` (success true) and ``success
    rate`` (docked / jobs). An interrupted job's metrics cover only the part that ran: they
    are left out of the means. Columns keep the order in which configurations first appear.
    One pandas groupby over the configuration labels (benchmarks/comparison_table.py).
    """
    labels = configuration_labels(df, keys)
    metrics = compared()
    index = pd.MultiIndex.from_tuples(
        [(m.section, m.heading) for m in metrics]
        + [(SUCCESS_SECTION, name) for name in ("jobs", "failed", "docked", "success rate")],
        names=["section", "metric"],
    )
    if not len(df):
        return pd.DataFrame(index=index, columns=[], dtype=float)
    by = labels.to_numpy()
    values = pd.DataFrame(
        {m.key: pd.to_numeric(df[m.key], errors="coerce") if m.key in df else np.nan for m in metrics},
        index=df.index,
    )
    if "status" in df:  # an interrupted job measured only the part that ran
        values.loc[df["status"].isin(NOT_MEASURED)] = np.nan
    means = values.groupby(by, sort=False).mean() * [m.scale for m in metrics]  # NaN: no value
    outcome = pd.DataFrame(
        {
            "jobs": 1.0,
            "failed": df["status"].isin(FAILED_STATUSES).astype(float),
            "docked": (df["success"] == True).astype(float) if "success" in df else 0.0,  # noqa: E712
        },
        index=df.index,
    )
    totals = outcome.groupby(by, sort=False).sum()
    totals["success rate"] = totals["docked"] / totals["jobs"]
    table = pd.concat([means, totals], axis=1).T
    table.index = index
    table.columns.name = None
    return table.astype(float)


def _cell(value, metric: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if metric in ("jobs", "failed", "docked"):
        return f"{int(value)}"
    if metric == "success rate":
        return f"{100 * value:.0f} %"
    if value != 0 and (abs(value) >= 1e5 or abs(value) < 1e-3):
        return f"{value:.3e}"
    return f"{value:.4g}" if abs(value) >= 100 else f"{value:.3f}"


def _markdown_grid(header: list[str], rows: list[list[str]], align_right: bool = True) -> str:
    """A pipe table with padded cells (readable as plain text in a terminal)."""
    widths = [
        max(len(header[i]), *(len(r[i]) for r in rows)) if rows else len(header[i])
        for i in range(len(header))
    ]
    line = lambda cells: (
        "| "
        + " | ".join(  # noqa: E731
            c.ljust(w) if i == 0 or not align_right else c.rjust(w)
            for i, (c, w) in enumerate(zip(cells, widths))
        )
        + " |"
    )
    rule = (
        "|"
        + "|".join(
            ("-" * (w + 2)) if i == 0 or not align_right else ("-" * (w + 1) + ":")
            for i, w in enumerate(widths)
        )
        + "|"
    )
    return "\n".join([line(header), rule, *(line(r) for r in rows)])


def comparison_markdown(table: pd.DataFrame) -> str:
    """The comparison as a Markdown pipe table, sections as bold rows."""
    header = ["metric", *map(str, table.columns)]
    rows: list[list[str]] = []
    section = None
    for (sec, metric), values in table.iterrows():
        if sec != section:
            rows.append([f"**{sec}**", *[""] * len(table.columns)])
            section = sec
        rows.append([metric, *(_cell(v, metric) for v in values)])
    return _markdown_grid(header, rows)


def jobs_markdown(df: pd.DataFrame) -> str:
    """One line per job: name, status, docked, peak axial force, wall time, reason."""
    header = ["job", "status", "docked", "peak axial force [N]", "wall time [s]", "error / gate"]
    rows = []
    for _, r in df.iterrows():
        success = r.get("success")
        docked = (
            "n/a"
            if success is None or (isinstance(success, float) and math.isnan(success))
            else ("yes" if bool(success) else "no")
        )
        reason = r.get("error") if isinstance(r.get("error"), str) else r.get("gate_failures")
        reason = reason if isinstance(reason, str) else ""
        rows.append(
            [
                str(r["job"]),
                str(r["status"]),
                docked,
                _cell(r.get("peak_axial_force_N"), ""),
                _cell(r.get("wall_time_s"), ""),
                reason.replace("|", "/"),
            ]
        )
    return _markdown_grid(header, rows, align_right=False)


@dataclass(frozen=True)
class Counts:
    """Outcome of a set of jobs."""

    jobs: int
    ok: int  # status ok
    incomplete: int
    failed: int  # status failed or interrupted
    docked: int  # success true
    unfinished: int = 0  # job directories without a finished metrics.json

    def line(self) -> str:
        text = (
            f"{self.jobs + self.unfinished} jobs: {self.ok} succeeded, "
            f"{self.failed + self.unfinished} failed, {self.docked} docked"
        )
        extra = []
        if self.incomplete:
            extra.append(f"{self.incomplete} incomplete")
        if self.unfinished:
            extra.append(f"{self.unfinished} without metrics.json (crashed or cut short)")
        return text + (f" ({', '.join(extra)})" if extra else "")


def counts(df: pd.DataFrame, unfinished: int = 0) -> Counts:
    status = df["status"] if "status" in df else pd.Series([], dtype=object)
    success = df["success"] if "success" in df else pd.Series([], dtype=object)
    return Counts(
        jobs=len(df),
        ok=int((status == "ok").sum()),
        incomplete=int((status == "incomplete").sum()),
        failed=int(status.isin(FAILED_STATUSES).sum()),
        docked=int((success == True).sum()),  # noqa: E712
        unfinished=unfinished,
    )


def summary_markdown(df: pd.DataFrame, title: str, unfinished: list[Path] | None = None) -> str:
    """summary.md: counts, the Table-10 comparison and the list of jobs."""
    unfinished = unfinished or []
    parts = [
        f"# {title}",
        "",
        f"{counts(df, len(unfinished)).line()}. Written "
        f"{datetime.now().isoformat(timespec='seconds')} by compliant_docking.results; "
        "rebuild with `python -m compliant_docking.report PATH`.",
        "",
    ]
    if len(df):
        keys = configuration_keys(df)
        pooled = [c for c in df.columns if REPEAT_KEYS.search(c) and df[c].nunique() > 1]
        note = (
            "Mean over the jobs of each configuration"
            + (f" (repeats over {', '.join(pooled)} pooled)" if pooled else "")
            + "; configurations differ in: "
            + (", ".join(keys) or "nothing (one configuration)")
            + "."
        )
        parts += [
            "## Comparison (Table 10)",
            "",
            note,
            "",
            comparison_markdown(comparison_table(df, keys)),
            "",
        ]
        parts += ["## Jobs", "", jobs_markdown(df), ""]
    if unfinished:
        parts += ["## Without a finished metrics.json", ""]
        parts += [f"- `{p}`" for p in unfinished] + [""]
    return "\n".join(parts)


def arrow_safe(df: pd.DataFrame) -> pd.DataFrame:
    """A copy whose object columns hold one type each (mixed → str), for Parquet."""
    out = df.copy()
    for column in out.columns:
        if out[column].dtype != object:
            continue
        types = {type(v) for v in out[column].dropna()}
        if len(types) > 1 and not types <= {int, float}:
            if types <= {bool, type(None)}:
                continue
            out[column] = out[column].map(lambda v: None if v is None else str(v))
    return out


def write_summary(
    df: pd.DataFrame,
    out_dir: str | os.PathLike,
    *,
    title: str | None = None,
    unfinished: list[Path] | None = None,
) -> dict[str, Path]:
    """Write summary.parquet, summary.csv (one row per job), comparison.csv and summary.md.

    Each file is written under a temporary name and renamed. Returns {name: path}.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    title = title or f"Runs in {out.name}"
    paths = {name: out / name for name in SUMMARY_FILES}
    safe = arrow_safe(df)
    atomic_write(paths["summary.parquet"], lambda p: safe.to_parquet(p, index=False))
    atomic_write(paths["summary.csv"], lambda p: df.to_csv(p, index=False))
    table = comparison_table(df) if len(df) else pd.DataFrame()
    atomic_write(paths["comparison.csv"], lambda p: table.to_csv(p))
    text = summary_markdown(df, title, unfinished)
    atomic_write(paths["summary.md"], lambda p: p.write_text(text + "\n", encoding="utf-8"))
    return paths
