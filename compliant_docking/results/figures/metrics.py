"""Grouped bars of the docking metrics and the success rate across configurations
(:func:`metric_bars`, ``comparison/table10_bars.png``): the Table-10 comparison as a figure."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.ticker import MaxNLocator

from compliant_docking.evaluation import registry
from compliant_docking.results.figures.common import comparison_style, note, save_figure
from compliant_docking.results.stats import bootstrap_ci, wilson
from compliant_docking.results.tables import NOT_MEASURED, configuration_keys, configuration_labels

#: metrics drawn by :func:`metric_bars`, by section of the registry (plus success)
BAR_SECTIONS = (registry.CONTACT, registry.CONTACT_EVENTS, registry.INTERNAL, registry.TRACKING)


def _split_keys(df: pd.DataFrame) -> tuple[str | None, list[str]]:
    """(x key, hue keys): the controller on the x axis when it varies, else the first key."""
    keys = configuration_keys(df)
    if not keys:
        return None, []
    x_key = "controller" if "controller" in keys else keys[0]
    return x_key, [k for k in keys if k != x_key]


def metric_bars(df: pd.DataFrame, out_dir: str | Path | None = None, stem: str = "table10_bars"):
    """Grouped bars of the docking metrics (one panel each) and the success rate.

    Bars are grouped on the x axis by the controller (or the first varying key); the
    bars of a group are the other varying keys (colours, legend). Heights are means
    over the finished jobs of a configuration; whiskers: the seeded bootstrap 95 %
    interval of the mean (none for a single job), Wilson's 95 % interval for the success
    rate.
    """
    plt = comparison_style()
    x_key, hue_keys = _split_keys(df)
    x_labels = df[x_key].astype(str) if x_key else pd.Series(["all"] * len(df), index=df.index)
    hue_labels = configuration_labels(df, hue_keys) if hue_keys else pd.Series([""] * len(df), index=df.index)
    groups = list(dict.fromkeys(x_labels))
    hues = list(dict.fromkeys(hue_labels))
    rows: list[list[registry.Metric | None]] = [
        list(registry.in_section(s, compared_only=True)) for s in BAR_SECTIONS
    ]
    internal = BAR_SECTIONS.index(registry.INTERNAL)
    rows[internal] = rows[internal] + [None]  # the success rate after the internal-safety metrics
    ncols = max(len(r) for r in rows)
    legend_rows = math.ceil(len(hues) / 4) if any(hues) else 0
    height = 1.75 * len(rows) + 0.8 + 0.15 * legend_rows
    fig, axes = plt.subplots(len(rows), ncols, figsize=(1.9 * ncols + 0.4, height), squeeze=False)
    # fixed margins: an automatic layout of 12 panels costs more than drawing them
    fig.subplots_adjust(
        left=0.07,
        right=0.985,
        top=1 - 0.45 / height,
        bottom=(0.62 + 0.15 * legend_rows) / height,
        wspace=0.32,
        hspace=0.5,
    )
    width = 0.8 / max(len(hues), 1)
    colors = plt.rcParams["axes.prop_cycle"].by_key().get("color", ["C0"])
    for r, metrics in enumerate(rows):
        for c in range(ncols):
            ax = axes[r][c]
            if c >= len(metrics):
                ax.set_visible(False)
                continue
            row = metrics[c]
            for h, hue in enumerate(hues):
                means, lows, highs = [], [], []
                for group in groups:
                    mask = (x_labels == group) & (hue_labels == hue)
                    if row is None:
                        docked, jobs = int((df.loc[mask, "success"] == True).sum()), int(mask.sum())  # noqa: E712
                        rate = 100.0 * docked / jobs if jobs else np.nan
                        low, high = (100.0 * b for b in wilson(docked, jobs)) if jobs else (np.nan, np.nan)
                        means.append(rate)
                        lows.append(max(rate - low, 0.0) if jobs else 0.0)
                        highs.append(max(high - rate, 0.0) if jobs else 0.0)
                        continue
                    measured = mask & ~df["status"].isin(NOT_MEASURED)  # interrupted: part of a run
                    values = (
                        pd.to_numeric(df.loc[measured].get(row.key), errors="coerce") * row.scale
                        if row.key in df
                        else pd.Series(dtype=float)
                    )
                    summary = bootstrap_ci(values.to_numpy(), f"{group}|{hue}|{row.key}", median=False)
                    means.append(summary.mean)
                    # ≥ 0: the mean of equal values can round a hair past them
                    lows.append(max(summary.mean - summary.mean_low, 0.0) if summary.n else 0.0)
                    highs.append(max(summary.mean_high - summary.mean, 0.0) if summary.n else 0.0)
                pos = np.arange(len(groups)) + (h - (len(hues) - 1) / 2) * width
                ax.bar(
                    pos,
                    means,
                    width=width * 0.95,
                    color=colors[h % len(colors)],
                    label=hue or None,
                    yerr=np.array([lows, highs]),
                    capsize=1.5,
                    error_kw={"elinewidth": 0.5, "capthick": 0.5},
                )
            ax.set_xticks(np.arange(len(groups)))
            ax.set_xticklabels(groups, rotation=30 if len(groups) > 3 else 0)
            ax.yaxis.set_major_locator(MaxNLocator(nbins=4))
            ax.set_title("success rate [%]" if row is None else row.heading)
            if row is None:
                ax.set_ylim(0, 105)
            if c == 0:
                ax.set_ylabel(BAR_SECTIONS[r])
    fig.align_ylabels(axes[:, 0])
    if any(hues):
        handles, labels = axes[0][0].get_legend_handles_labels()
        fig.legend(
            handles, labels, loc="lower center", ncols=min(len(hues), 4), bbox_to_anchor=(0.5, 0.16 / height)
        )
    if x_key:
        fig.suptitle(f"docking metrics by {x_key}")
    jobs = df.groupby(configuration_labels(df), sort=False).size() if len(df) else pd.Series(dtype=int)
    note(fig, [f"bars: mean over {jobs.min()}–{jobs.max()} jobs per configuration; whiskers: 95 % interval "
               "(bootstrap of the mean; Wilson for the success rate)" if len(jobs) else ""])  # fmt: skip
    save_figure(fig, out_dir, stem)
    return fig
