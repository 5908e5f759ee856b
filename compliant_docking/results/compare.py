"""Sweep statistics from a :func:`~compliant_docking.results.load.load_runs` frame.

- :func:`configuration_stats`: one row per configuration: jobs, docked, the success rate
  with its Wilson 95 % interval, and for each metric of the registry marked ``interval``
  (forces, seat errors, docking time) its mean and median with seeded bootstrap 95 %
  intervals (``comparison.csv`` / ``comparison.parquet``);
- :func:`paired_comparisons`: controllers compared on the same draws: for each metric and
  each pair of controllers within each combination of the other configuration keys (a
  *stratum*: robot, planner, …), Wilcoxon's signed-rank test, the rank-biserial
  correlation, the median difference and the relative change of the medians with bootstrap
  intervals; the success indicators with McNemar's exact test; Holm's correction over the
  comparisons of one metric across the sweep (``paired.csv`` / ``paired.parquet``).

Units are those of metrics.json (SI, or the unit a key names); the ``_low``/``_high``
columns are the 95 % interval's bounds.
"""

from __future__ import annotations

import math
from dataclasses import asdict
from itertools import combinations

import numpy as np
import pandas as pd

import compliant_docking.results.stats as stats  # the module, not the package (no import cycle)
from compliant_docking.evaluation import registry
from compliant_docking.results.tables import (
    FAILED_STATUSES,
    NOT_MEASURED,
    REPEAT_KEYS,
    configuration_keys,
    configuration_labels,
)

#: the factor whose levels are compared on the same draws
FACTOR = "controller"
#: columns that identify a draw (beside the seed columns): the drawn misalignment
DRAW_COLUMNS = ("misalignment_x_m", "misalignment_y_m", "misalignment_yaw_deg", "misalignment_tilt_deg")
#: the significance level of the words in summary.md
ALPHA = 0.05
#: the success indicator's row in the paired table
SUCCESS = "success"


def _docked(df: pd.DataFrame) -> pd.Series:
    return (df["success"] == True).astype(float) if "success" in df else pd.Series(0.0, index=df.index)  # noqa: E712


def configuration_stats(
    df: pd.DataFrame, keys: list[str] | None = None, *, seed: int = stats.SEED
) -> pd.DataFrame:
    """One row per configuration (in order of first appearance).

    Columns: the configuration keys, ``configuration`` (its label), ``jobs``, ``failed``
    (status failed or interrupted), ``finished`` (the others), ``docked``, ``success_rate`` (docked / jobs,
    a failed job counting as not docked) with ``success_rate_low``/``_high`` (Wilson);
    per metric marked ``interval`` in the registry: ``<key>_n`` (jobs with a value),
    ``<key>_mean``, ``<key>_mean_low``, ``<key>_mean_high``, ``<key>_median``,
    ``<key>_median_low``, ``<key>_median_high`` (bootstrap, seeded by ``seed`` and the
    configuration's label); per other compared metric ``<key>_mean``.
    """
    keys = configuration_keys(df) if keys is None else keys
    if df.empty:
        return pd.DataFrame(columns=[*keys, "configuration", "jobs", "success_rate"])
    labels = configuration_labels(df, keys)
    rows = []
    for label, group in df.groupby(labels, sort=False):
        row: dict = {k: group[k].iloc[0] for k in keys}
        jobs = len(group)
        docked = int(_docked(group).sum())
        failed = int(group["status"].isin(FAILED_STATUSES).sum())
        low, high = stats.wilson(docked, jobs)
        row.update(
            configuration=label,
            jobs=jobs,
            failed=failed,
            finished=jobs - failed,
            docked=docked,
            success_rate=docked / jobs,
            success_rate_low=low,
            success_rate_high=high,
        )
        measured = group[~group["status"].isin(NOT_MEASURED)]  # an interrupted run: only a part
        for metric in registry.compared() + [m for m in registry.with_intervals() if not m.compared]:
            values = pd.to_numeric(measured[metric.key], errors="coerce") if metric.key in measured else None
            if not metric.interval:
                row[f"{metric.key}_mean"] = values.mean() if values is not None else math.nan
                continue
            summary = stats.bootstrap_ci(
                [] if values is None else values.to_numpy(), f"{label}|{metric.key}", seed=seed
            )
            row.update(
                {
                    f"{metric.key}_n": summary.n,
                    f"{metric.key}_mean": summary.mean,
                    f"{metric.key}_mean_low": summary.mean_low,
                    f"{metric.key}_mean_high": summary.mean_high,
                    f"{metric.key}_median": summary.median,
                    f"{metric.key}_median_low": summary.median_low,
                    f"{metric.key}_median_high": summary.median_high,
                }
            )
        rows.append(row)
    return pd.DataFrame(rows)


def draw_keys(df: pd.DataFrame) -> list[str]:
    """The columns that identify a draw: the seed columns (``…seed``, not constant-free
    ``misalignment_seed`` which is null for undrawn runs) and the drawn misalignment."""
    seeds = [c for c in df.columns if REPEAT_KEYS.search(c) and "." in c]
    return seeds + [c for c in DRAW_COLUMNS if c in df.columns]


def draw_identity(df: pd.DataFrame) -> pd.Series:
    """One hashable identity per row of the draw it docked into (:func:`draw_keys`; ``()``
    for every row when nothing identifies a draw)."""
    keys = draw_keys(df)
    return _key_frame(df, keys) if keys else pd.Series([()] * len(df), index=df.index)


def _key_frame(df: pd.DataFrame, columns: list[str]) -> pd.Series:
    """One hashable draw identity per row (numbers rounded to 1e-12: the same draw is the
    same bits, but a CSV round trip may not be)."""

    def norm(value):
        if isinstance(value, float):
            return None if math.isnan(value) else round(value, 12)
        return value

    return pd.Series(
        [tuple(norm(v) for v in row) for row in df[columns].itertuples(index=False)], index=df.index
    )


def paired_comparisons(
    df: pd.DataFrame, factor: str = FACTOR, *, seed: int = stats.SEED, alpha: float = ALPHA
) -> pd.DataFrame:
    """Every pair of ``factor`` levels compared on the same draws, per stratum and metric.

    A stratum is a combination of the other configuration keys (robot, planner,
    clearance, …). Within it, a job of level a and one of level b form a pair when they
    drew the same misalignment with the same seeds (:func:`draw_keys`); a draw that a
    level ran more than once is left out (``dropped``). Rows: for each metric marked
    ``interval`` (pairs where both have a value) and for ``success`` (McNemar's exact test
    over all pairs; a failed job counts as not docked), the fields of
    :class:`~compliant_docking.results.stats.Paired` (b − a), then ``p_holm`` (Holm over
    the rows of the same metric) and ``significant`` (p_holm ≤ ``alpha``). Empty when
    ``factor`` does not vary.
    """
    keys = configuration_keys(df)
    if df.empty or factor not in keys:
        return pd.DataFrame()
    others = [k for k in keys if k != factor]
    strata = configuration_labels(df, others) if others else pd.Series("all", index=df.index)
    ids = draw_identity(df)
    levels = list(dict.fromkeys(df[factor].astype(str)))
    metrics = registry.with_intervals()
    rows = []
    for stratum in dict.fromkeys(strata):
        here = df[strata == stratum]
        by_level = {}
        for level in levels:
            rows_of = here[here[factor].astype(str) == level]
            counts = ids[rows_of.index].value_counts()
            unique = rows_of[ids[rows_of.index].map(counts) == 1]
            by_level[level] = (unique.set_index(ids[unique.index]), len(rows_of) - len(unique))
        for a, b in combinations(levels, 2):
            (frame_a, drop_a), (frame_b, drop_b) = by_level[a], by_level[b]
            if frame_a.empty or frame_b.empty:
                continue
            common = frame_a.index.intersection(frame_b.index, sort=False)
            left, right = frame_a.loc[common], frame_b.loc[common]
            base = {"stratum": stratum, "a": a, "b": b, "pairs": len(common), "dropped": drop_a + drop_b}
            base["unpaired"] = len(frame_a) + len(frame_b) - 2 * len(common)
            measured_a = ~left["status"].isin(NOT_MEASURED).to_numpy()
            measured_b = ~right["status"].isin(NOT_MEASURED).to_numpy()
            for metric in metrics:
                if metric.key not in df:
                    continue
                values_a = pd.to_numeric(left[metric.key], errors="coerce").to_numpy().copy()
                values_b = pd.to_numeric(right[metric.key], errors="coerce").to_numpy().copy()
                values_a[~measured_a], values_b[~measured_b] = np.nan, np.nan
                result = stats.paired(
                    values_a,
                    values_b,
                    f"{stratum}|{a}|{b}|{metric.key}",
                    seed=seed,
                )
                rows.append({"metric": metric.key, **base, **asdict(result)})
            docked_a, docked_b = _docked(left).to_numpy(bool), _docked(right).to_numpy(bool)
            only_a, only_b, p = stats.mcnemar(docked_a, docked_b)
            n = len(common)
            rate_a, rate_b = (docked_a.mean(), docked_b.mean()) if n else (math.nan, math.nan)
            rows.append(
                {
                    "metric": SUCCESS,
                    **base,
                    "n": n,
                    "median_a": rate_a,
                    "median_b": rate_b,
                    "median_difference": rate_b - rate_a,
                    "only_a": only_a,
                    "only_b": only_b,
                    "p_value": p if n else math.nan,
                    "method": "McNemar exact",
                }
            )
    out = pd.DataFrame(rows)
    if out.empty:
        return out
    out["p_holm"] = np.nan
    for _, index in out.groupby("metric", sort=False).groups.items():
        out.loc[index, "p_holm"] = stats.holm(out.loc[index, "p_value"].to_numpy(float))
    out["significant"] = out["p_holm"] <= alpha
    return out
