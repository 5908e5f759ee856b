"""The summary files of a set of runs (a sweep, or any directory ``report`` reads).

- ``summary.parquet``, ``summary.csv``: the :func:`~compliant_docking.results.load.load_runs`
  frame, one row per job;
- ``comparison.csv``, ``comparison.parquet``: one row per configuration, the statistics of
  :func:`~compliant_docking.results.compare.configuration_stats` (success rate with its
  Wilson interval, means and medians with bootstrap intervals, the docking metrics' means);
- ``paired.csv``, ``paired.parquet``: the paired comparisons between controllers
  (:func:`~compliant_docking.results.compare.paired_comparisons`; empty when the
  controller does not vary);
- ``summary.md``: the counts, the configurations, the paired comparisons in words and
  tables, the statistics per configuration, the docking-metrics comparison and every job.
"""

from __future__ import annotations

import math
import os
from datetime import datetime
from pathlib import Path

import pandas as pd

from compliant_docking.evaluation import registry
from compliant_docking.results.compare import ALPHA, FACTOR, SUCCESS, configuration_stats, paired_comparisons
from compliant_docking.results.stats import RESAMPLES
from compliant_docking.results.tables import (
    REPEAT_KEYS,
    _markdown_grid,
    comparison_markdown,
    comparison_table,
    configuration_keys,
    counts,
    jobs_markdown,
)
from compliant_docking.run.files import atomic_write

#: files written by :func:`write_summary`
SUMMARY_FILES = (
    "summary.parquet",
    "summary.csv",
    "comparison.csv",
    "comparison.parquet",
    "paired.csv",
    "paired.parquet",
    "summary.md",
)


def _num(value: float, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if value != 0 and (abs(value) >= 1e5 or abs(value) < 1e-3):
        return f"{value:.{digits - 1}e}"
    return f"{value:.{digits}g}"


def _ci(value: float, low: float, high: float, scale: float = 1.0, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    text = _num(value * scale, digits)
    if isinstance(low, float) and math.isnan(low):
        return text
    return f"{text} [{_num(low * scale, digits)}, {_num(high * scale, digits)}]"


def _pct(value: float) -> str:
    return "n/a" if value is None or math.isnan(value) else f"{100 * value:.0f} %"


def configurations_markdown(table: pd.DataFrame) -> str:
    """One row per configuration: jobs, failed, docked, success rate [Wilson 95 % CI]."""
    header = ["configuration", "jobs", "failed", "docked", "success rate [95 % CI]"]
    rows = [
        [
            str(r["configuration"]),
            str(r["jobs"]),
            str(r["failed"]),
            str(r["docked"]),
            f"{_pct(r['success_rate'])} [{_pct(r['success_rate_low'])}, {_pct(r['success_rate_high'])}]",
        ]
        for _, r in table.iterrows()
    ]
    return _markdown_grid(header, rows)


def statistics_markdown(table: pd.DataFrame) -> str:
    """Per metric marked ``interval``: one row per configuration with n, the mean and the
    median, each with its bootstrap 95 % interval (display units)."""
    blocks = []
    for metric in registry.with_intervals():
        if f"{metric.key}_n" not in table or not table[f"{metric.key}_n"].any():
            continue
        rows = []
        for _, r in table.iterrows():
            k = metric.key
            rows.append(
                [
                    str(r["configuration"]),
                    str(int(r[f"{k}_n"])),
                    _ci(r[f"{k}_mean"], r[f"{k}_mean_low"], r[f"{k}_mean_high"], metric.scale),
                    _ci(r[f"{k}_median"], r[f"{k}_median_low"], r[f"{k}_median_high"], metric.scale),
                ]
            )
        grid = _markdown_grid(["configuration", "n", "mean [95 % CI]", "median [95 % CI]"], rows)
        blocks.append(f"### {metric.heading}\n\n{grid}")
    return "\n\n".join(blocks)


def _heading(key: str) -> str:
    return "success rate [%]" if key == SUCCESS else registry.BY_KEY[key].heading


def _scale(key: str) -> float:
    return 100.0 if key == SUCCESS else registry.BY_KEY[key].scale


def _unit(key: str) -> str:
    return "%-points" if key == SUCCESS else registry.BY_KEY[key].unit


def _effect(r, key: str) -> str:
    """``−20.1 N [−28, −12] (−81 % [−90, −70]), r = −1.00``: the median of the paired
    differences with its interval, the relative change of the medians and r."""
    scale, unit = _scale(key), _unit(key)
    if key == SUCCESS:
        return f"{r['median_difference'] * scale:+.0f} {unit} ({int(r['only_a'])} vs {int(r['only_b'])} discordant)"
    text = (
        _ci(r["median_difference"], r["difference_low"], r["difference_high"], scale, 3) + f" {unit}".rstrip()
    )
    if not math.isnan(r["relative_change"]):
        low, high = r["relative_low"], r["relative_high"]
        bounds = "" if math.isnan(low) else f" [{100 * low:+.0f}, {100 * high:+.0f}]"
        text += f" ({100 * r['relative_change']:+.0f} %{bounds})"
    if not math.isnan(r["rank_biserial"]):
        text += f", r = {r['rank_biserial']:+.2f}"
    return text


def _pair(r) -> str:
    where = "" if r["stratum"] == "all" else f" on {r['stratum']}"
    return f"{r['b']} − {r['a']}{where}"


def paired_words(paired: pd.DataFrame, alpha: float = ALPHA) -> str:
    """Which differences are significant at ``alpha`` after Holm's correction, and which
    are not, metric by metric, in words."""
    lines = []
    for key, rows in paired.groupby("metric", sort=False):
        tested = rows[rows["p_value"].notna()]
        significant = tested[tested["significant"]]
        rest = tested[~tested["significant"]]
        level = f"{100 * alpha:g} %"
        head = f"- **{_heading(key)}**, {len(tested)} comparison{'s' * (len(tested) != 1)}: "
        if tested.empty:
            lines.append(
                f"- **{_heading(key)}**: no test (no comparison with 2 or more pairs that have values)."
            )
            continue
        if significant.empty:
            smallest = _num(tested["p_holm"].min(), 2)
            lines.append(head + f"none significant at {level} (smallest Holm p = {smallest}).")
            continue
        # one sub-item per significant difference (readable at 18 comparisons), then the rest
        lines.append(head + f"{len(significant)} significant at {level}:")
        lines += [
            f"  - {_pair(r)}: {_effect(r, key)}, p = {_num(r['p_value'], 2)} (Holm {_num(r['p_holm'], 2)})"
            for _, r in significant.iterrows()
        ]
        if len(rest):
            lines.append(
                f"  - not significant ({len(rest)}): "
                + ", ".join(f"{_pair(r)} (Holm p {_num(r['p_holm'], 2)})" for _, r in rest.iterrows())
                + "."
            )
    return "\n".join(lines)


def paired_markdown(paired: pd.DataFrame) -> str:
    """One table per metric: each comparison's pairs, medians, effect, p and Holm p."""
    blocks = []
    for key, rows in paired.groupby("metric", sort=False):
        scale = _scale(key)
        body = []
        for _, r in rows.iterrows():
            body.append(
                [
                    _pair(r),
                    str(int(r["n"])),
                    _num(r["median_a"] * scale),
                    _num(r["median_b"] * scale),
                    _effect(r, key),
                    _num(r["p_value"], 2),
                    _num(r["p_holm"], 2),
                    "yes" if r["significant"] else "no",
                ]
            )
        name = "rate" if key == SUCCESS else "median"
        header = [
            "b − a",
            "pairs",
            f"{name} a",
            f"{name} b",
            "effect: median of b − a [95 % CI]",
            "p",
            "p Holm",
            "significant",
        ]
        blocks.append(f"### {_heading(key)}\n\n{_markdown_grid(header, body)}")
    return "\n\n".join(blocks)


def summary_markdown(
    df: pd.DataFrame,
    title: str,
    unfinished: list[Path] | None = None,
    *,
    per_configuration: pd.DataFrame | None = None,
    paired: pd.DataFrame | None = None,
) -> str:
    """summary.md: counts, configurations, paired comparisons, statistics, the docking metrics, jobs
    (``per_configuration``, ``paired``: the tables when already computed)."""
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
        pooled = [c for c in df.columns if REPEAT_KEYS.search(c) and df[c].astype(str).nunique() > 1]
        stats_table = configuration_stats(df, keys) if per_configuration is None else per_configuration
        parts += [
            "## Configurations",
            "",
            "Configurations differ in: "
            + (", ".join(keys) or "nothing (one configuration)")
            + (f"; repeats over {', '.join(pooled)} are pooled" if pooled else "")
            + ". Success rate: docked / jobs (a failed job counts as not docked), with its Wilson "
            "95 % interval.",
            "",
            configurations_markdown(stats_table),
            "",
        ]
        paired = paired_comparisons(df) if paired is None else paired
        if len(paired):
            others = [k for k in keys if k != FACTOR]
            parts += [
                "## Paired comparisons: controllers on the same draws",
                "",
                f"Each pair of controllers (b − a) is compared within each combination of "
                f"{', '.join(others) or 'the sweep'} on the draws both ran (the same seeds, so the same "
                "socket poses): Wilcoxon's signed-rank test (two-sided), Holm-corrected over the "
                "comparisons of each metric in this sweep; effect: the median of the paired "
                f"differences with its bootstrap 95 % interval ({RESAMPLES} resamples, seeded), the "
                "relative change of the medians, and the matched-pairs rank-biserial correlation r "
                "(+1: b larger in every pair). Success: McNemar's exact test on the same pairs.",
                "",
                paired_words(paired),
                "",
                paired_markdown(paired),
                "",
            ]
        statistics = statistics_markdown(stats_table)
        if statistics:
            parts += [
                "## Statistics per configuration",
                "",
                "Over the finished jobs of each configuration that have the value; 95 % intervals: "
                f"seeded percentile bootstrap ({RESAMPLES} resamples); docking time = from the first "
                "contact on, the first time the plug tip is within the gate's depth and lateral "
                "tolerances of the true seat and stays there to the end (docking_time_s).",
                "",
                statistics,
                "",
            ]
        parts += [
            "## Comparison: the docking metrics (Ren & Shan 2026, Table 10)",
            "",
            "Mean over the jobs of each configuration, in display units.",
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
    """Write the files of :data:`SUMMARY_FILES` (module doc) into ``out_dir``.

    Each file is written under a temporary name and renamed. Returns {name: path}.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    title = title or f"Runs in {out.name}"
    paths = {name: out / name for name in SUMMARY_FILES}
    safe = arrow_safe(df)
    atomic_write(paths["summary.parquet"], lambda p: safe.to_parquet(p, index=False))
    atomic_write(paths["summary.csv"], lambda p: df.to_csv(p, index=False))
    per_configuration = configuration_stats(df) if len(df) else pd.DataFrame()
    paired = paired_comparisons(df) if len(df) else pd.DataFrame()
    for stem, table in (("comparison", per_configuration), ("paired", paired)):
        safe_table = arrow_safe(table)

        def write_csv(p: Path, t: pd.DataFrame = safe_table) -> None:
            t.to_csv(p, index=False)

        def write_parquet(p: Path, t: pd.DataFrame = safe_table) -> None:
            t.to_parquet(p, index=False)

        atomic_write(paths[f"{stem}.csv"], write_csv)
        atomic_write(paths[f"{stem}.parquet"], write_parquet)
    text = summary_markdown(df, title, unfinished, per_configuration=per_configuration, paired=paired)
    atomic_write(paths["summary.md"], lambda p: p.write_text(text + "\n", encoding="utf-8"))
    return paths
