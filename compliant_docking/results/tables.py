"""The comparison of a set of runs: configurations and their labels, the docking metrics
table, job lines and counts (the summary files: :mod:`compliant_docking.results.summary`).

:func:`comparison_table` turns the rows of :func:`~compliant_docking.results.load.load_runs`
into one column per configuration and one row per compared metric of the registry
(:mod:`compliant_docking.evaluation.registry`), grouped by section, plus the outcome.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
import pandas as pd

from compliant_docking.evaluation.registry import compared
from compliant_docking.results.load import GROUPS, OVERRIDDEN
from compliant_docking.run.rundir import FAILED_STATUSES

SUCCESS_SECTION = "success"
#: keys that repeat a configuration rather than define one
REPEAT_KEYS = re.compile(r"(^|\.)seed$")
#: overrides that change how a job reports, not what it simulates
COSMETIC_KEYS = frozenset({"task.progress"})
#: statuses whose metrics do not measure a whole run (left out of the comparison's means)
NOT_MEASURED = ("interrupted",)


def configuration_keys(df: pd.DataFrame) -> list[str]:
    """The columns that tell the configurations of ``df`` apart.

    Candidates are the config choices (``robot``, ``controller``, …, ``experiment``)
    and the dotted keys some job overrode (``controller.k``, ``task.misalignment.x_range``;
    listed in the ``overridden`` column; a frame without that column: every dotted
    column) — not the config leaves that follow from a choice (``controller.k`` of a
    robot's gain file); kept are those whose value varies across the rows, except repeat
    keys (any ``…seed``): repeats of one configuration are pooled (success rate, means),
    and cosmetic keys (``task.progress``).
    """
    if df.empty:
        return []
    candidates = [g for g in GROUPS if g in df.columns]
    if OVERRIDDEN in df.columns:
        named = {k for keys in df[OVERRIDDEN].dropna() for k in str(keys).split(",")}
        candidates += [c for c in df.columns if "." in c and c in named and c not in candidates]
    else:
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


#: short labels of well-known keys: key → (name, scale to the shown unit, unit)
KNOWN_KEYS = {
    "task.misalignment.x": ("x", 1e3, "mm"),
    "task.misalignment.y": ("y", 1e3, "mm"),
    "task.misalignment.yaw_deg": ("yaw", 1.0, "°"),
    "task.misalignment.tilt_deg": ("tilt", 1.0, "°"),
    "task.misalignment.x_range": ("x", 1e3, "mm"),
    "task.misalignment.y_range": ("y", 1e3, "mm"),
    "task.misalignment.yaw_deg_range": ("yaw", 1.0, "°"),
    "task.misalignment.tilt_deg_range": ("tilt", 1.0, "°"),
    "target.geometry.radial_clearance": ("clearance", 1e3, "mm"),
}


def _bounds(value) -> list[float] | None:
    """[low, high] of a range value (a list, or its JSON / override text), else None."""
    if isinstance(value, str):
        try:
            value = [float(v) for v in value.strip("[] ").split(",")]
        except ValueError:
            return None
    if isinstance(value, (list, tuple)) and len(value) == 2:
        return [float(v) for v in value]
    return None


def short_label(key: str, value, keys: list[str] | None = None) -> str:
    """``x ±2 mm``, ``tilt 0–1.5°``, ``clearance 0.4 mm`` for the misalignment and clearance
    keys (:data:`KNOWN_KEYS`); ``short_key=value`` otherwise; a config choice alone."""
    if key in GROUPS:
        return _format_value(value)
    if key in KNOWN_KEYS and not (value is None or (isinstance(value, float) and math.isnan(value))):
        name, scale, unit = KNOWN_KEYS[key]
        space = "" if unit == "°" else " "
        if key.endswith("_range"):
            bounds = _bounds(value)
            if bounds is not None:
                low, high = (b * scale for b in bounds)
                if low == -high and high > 0:
                    return f"{name} ±{high:g}{space}{unit}"
                return f"{name} {low:g}–{high:g}{space}{unit}"
        elif isinstance(value, (int, float)):
            return f"{name} {value * scale:g}{space}{unit}"
    return f"{_short(key, keys or [key])}={_format_value(value)}"


def drawn_label(row) -> str:
    """The misalignment a job drew, short: ``x +1.20 y −0.40 mm · tilt 0.8° (yaw 120°)``;
    '' when the job has none (free space, or every component zero)."""

    def number(key: str) -> float:
        value = row.get(key) if hasattr(row, "get") else None
        try:
            value = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            return 0.0
        return 0.0 if math.isnan(value) else value

    x, y = number("misalignment_x_m") * 1e3, number("misalignment_y_m") * 1e3
    yaw, tilt = number("misalignment_yaw_deg"), number("misalignment_tilt_deg")
    parts = []
    if x or y:
        parts.append(f"x {x:+.2f} y {y:+.2f} mm".replace("-", "−"))
    if tilt:
        parts.append(f"tilt {tilt:.2f}°" + (f" (yaw {yaw:.0f}°)" if yaw else ""))
    elif yaw:
        parts.append(f"yaw {yaw:+.2f}°".replace("-", "−"))
    return " · ".join(parts)


def _format_value(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "default"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def configuration_labels(df: pd.DataFrame, keys: list[str] | None = None) -> pd.Series:
    """A readable label per row: the values of :func:`configuration_keys`, ' · '-joined.

    Config choices show their value alone (``fr3 · hqp``), the misalignment and clearance
    keys in their unit (``x ±2 mm``, ``clearance 0.4 mm``: :func:`short_label`), other keys
    as ``short_key=value`` (``k=300``). With nothing varying, every row is labelled by its
    choices ``robot · controller · trajectory``.
    """
    keys = configuration_keys(df) if keys is None else keys
    if not keys:
        keys = [g for g in ("robot", "controller", "trajectory") if g in df.columns]

    def label(row) -> str:
        return " · ".join(short_label(key, row.get(key), keys) for key in keys) or str(row.get("job"))

    return df.apply(label, axis=1) if len(df) else pd.Series([], dtype=object)


def comparison_table(df: pd.DataFrame, keys: list[str] | None = None) -> pd.DataFrame:
    """The docking-metrics comparison: one column per configuration, rows (section, metric).

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


#: beyond this many configurations the comparison is transposed (one row per configuration)
WIDE = 6


def comparison_markdown(table: pd.DataFrame, max_columns: int = WIDE) -> str:
    """The comparison as Markdown: up to ``max_columns`` configurations one column each
    (metrics as rows, sections as bold rows); more, one table per section with one row per
    configuration (so the table stays readable at 18+ configurations)."""
    if len(table.columns) <= max_columns:
        header = ["metric", *map(str, table.columns)]
        rows: list[list[str]] = []
        section = None
        for (sec, metric), values in table.iterrows():
            if sec != section:
                rows.append([f"**{sec}**", *[""] * len(table.columns)])
                section = sec
            rows.append([metric, *(_cell(v, metric) for v in values)])
        return _markdown_grid(header, rows)
    blocks = []
    for sec in dict.fromkeys(table.index.get_level_values(0)):
        part = table.loc[sec]
        part = part[part.notna().any(axis=1)]  # a metric no configuration has (e.g. key yaw)
        if part.empty:
            continue
        header = ["configuration", *map(str, part.index)]
        rows = [[str(c), *(_cell(part.at[m, c], m) for m in part.index)] for c in part.columns]
        blocks.append(f"**{sec}**\n\n" + _markdown_grid(header, rows))
    return "\n\n".join(blocks)


def jobs_markdown(df: pd.DataFrame) -> str:
    """One line per job: name, status, docked, the drawn misalignment, peak axial force,
    wall time, reason."""
    drawn = df.apply(drawn_label, axis=1) if len(df) else pd.Series([], dtype=object)
    show_drawn = bool(len(df)) and drawn.astype(bool).any()
    header = ["job", "status", "docked", *(["drawn misalignment"] if show_drawn else [])]
    header += ["peak axial force [N]", "wall time [s]", "error / gate"]
    rows = []
    for index, r in df.iterrows():
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
                *([drawn[index]] if show_drawn else []),
                _cell(r.get("peak_axial_force_N"), ""),
                _cell(r.get("wall_time_s"), ""),
                reason.replace("|", "/"),
            ]
        )
    return _markdown_grid(header, rows, align_right=False)


@dataclass(frozen=True)
class Counts:
    """Outcome of a set of jobs. *Finished* is a job that ran (status ok or incomplete:
    it has results); *docked* a finished job that passed its gate (success true)."""

    jobs: int
    ok: int  # status ok
    incomplete: int
    failed: int  # status failed or interrupted
    docked: int  # success true
    unfinished: int = 0  # job directories without a finished metrics.json
    no_gate: int = 0  # finished without a gate to pass (success null: free-space holds)

    @property
    def finished(self) -> int:
        return self.ok + self.incomplete

    def line(self) -> str:
        """``18 jobs: 17 finished (15 docked, 2 not docked), 1 failed``."""
        outcome = [f"{self.docked} docked", f"{self.finished - self.docked - self.no_gate} not docked"]
        if self.no_gate:
            outcome.append(f"{self.no_gate} without a gate")
        text = (
            f"{self.jobs + self.unfinished} jobs: {self.finished} finished ({', '.join(outcome)}), "
            f"{self.failed + self.unfinished} failed"
        )
        extra = []
        if self.incomplete:
            extra.append(f"{self.incomplete} of the finished incomplete")
        if self.unfinished:
            extra.append(f"{self.unfinished} without metrics.json (crashed or cut short)")
        return text + (f" ({', '.join(extra)})" if extra else "")


def counts(df: pd.DataFrame, unfinished: int = 0) -> Counts:
    status = df["status"] if "status" in df else pd.Series([], dtype=object)
    success = df["success"] if "success" in df else pd.Series([], dtype=object)
    finished = ~status.isin(FAILED_STATUSES)
    return Counts(
        jobs=len(df),
        ok=int((status == "ok").sum()),
        incomplete=int((status == "incomplete").sum()),
        failed=int(status.isin(FAILED_STATUSES).sum()),
        docked=int((success == True).sum()),  # noqa: E712
        unfinished=unfinished,
        no_gate=int((finished & success.isna()).sum()) if len(success) else 0,
    )
