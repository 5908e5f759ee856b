"""Figures comparing runs (SciencePlots style, PNG; PDF on request), from a :func:`load_runs` frame.

- :func:`metric_bars`: grouped bars of the Table-10 metrics and the success rate across
  configurations (mean over repeats, whiskers: min to max of the repeats);
- :func:`success_vs_misalignment`: success rate and peak axial force against the drawn
  socket misalignment (lateral, yaw, tilt: the components that vary);
- :func:`force_overlay`: the axial contact force over time of selected runs, read from
  their ``timeseries.parquet``;
- :func:`plot_comparison`: those that have something to show into one folder (what
  the sweep callback and ``python -m compliant_docking.report`` call).

Every function returns the matplotlib Figure (for a notebook: ``display(fig)``) and,
given ``out_dir``, also saves it as ``<stem>.png`` (other formats: ``formats``, e.g.
``("png", "pdf")``; a PDF costs about as much as the PNG).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.ticker import MaxNLocator

from compliant_docking.evaluation import registry
from compliant_docking.results.load import RunSkippedWarning
from compliant_docking.results.tables import FAILED_STATUSES, configuration_keys, configuration_labels
from compliant_docking.run import rundir
from compliant_docking.sim.telemetry import FORCE, axial_force
from compliant_docking.viz.plotting import FORMATS, apply_style, check_formats, envelope

#: metrics drawn by :func:`metric_bars`, by section of the registry (plus success)
BAR_SECTIONS = (registry.CONTACT, registry.CONTACT_EVENTS, registry.INTERNAL, registry.TRACKING)
#: misalignment components: (metrics.json key, axis label, scale to the shown unit)
MISALIGNMENT_AXES = (
    ("misalignment_lateral_m", "lateral error [mm]", 1e3),
    ("misalignment_yaw_deg", "yaw error [deg]", 1.0),
    ("misalignment_tilt_deg", "tilt error [deg]", 1.0),
)


def save_figure(fig, out_dir: str | Path | None, stem: str, formats: Sequence[str] = FORMATS) -> list[Path]:
    """Save ``fig`` as ``out_dir/stem.<format>`` for each of ``formats`` (nothing when
    out_dir is None)."""
    if out_dir is None:
        return []
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for fmt in check_formats(formats):
        path = out / f"{stem}.{fmt}"
        fig.savefig(path)
        paths.append(path)
        fig.set_layout_engine("none")  # laid out once, by the first save (text layout is slow)
    return paths


def _split_keys(df: pd.DataFrame) -> tuple[str | None, list[str]]:
    """(x key, hue keys): the controller on the x axis when it varies, else the first key."""
    keys = configuration_keys(df)
    if not keys:
        return None, []
    x_key = "controller" if "controller" in keys else keys[0]
    return x_key, [k for k in keys if k != x_key]


def metric_bars(df: pd.DataFrame, out_dir: str | Path | None = None, stem: str = "table10_bars"):
    """Grouped bars of the Table-10 metrics (one panel each) and the success rate.

    Bars are grouped on the x axis by the controller (or the first varying key); the
    bars of a group are the other varying keys (colours, legend). Heights are means
    over the finished jobs of a configuration; whiskers span their min to max.
    """
    plt = apply_style()
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
    height = 1.75 * len(rows) + 0.6 + 0.15 * legend_rows
    fig, axes = plt.subplots(len(rows), ncols, figsize=(1.9 * ncols + 0.4, height), squeeze=False)
    # fixed margins: an automatic layout of 12 panels costs more than drawing them
    fig.subplots_adjust(
        left=0.07,
        right=0.985,
        top=1 - 0.45 / height,
        bottom=(0.45 + 0.15 * legend_rows) / height,
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
                        values = (df.loc[mask, "success"] == True).astype(float)  # noqa: E712
                        values = values * 100.0
                    else:
                        values = (
                            pd.to_numeric(df.loc[mask].get(row.key), errors="coerce") * row.scale
                            if row.key in df
                            else pd.Series(dtype=float)
                        )
                        values = values.dropna()
                    if len(values):
                        mean = values.mean()
                        means.append(mean)
                        # ≥ 0: the mean of equal values can round a hair past them
                        lows.append(max(mean - values.min(), 0.0))
                        highs.append(max(values.max() - mean, 0.0))
                    else:
                        means.append(np.nan)
                        lows.append(0.0)
                        highs.append(0.0)
                pos = np.arange(len(groups)) + (h - (len(hues) - 1) / 2) * width
                yerr = np.array([lows, highs]) if row is not None else None
                ax.bar(
                    pos,
                    means,
                    width=width * 0.95,
                    color=colors[h % len(colors)],
                    label=hue or None,
                    yerr=yerr,
                    capsize=1.5,
                    error_kw={"elinewidth": 0.5, "capthick": 0.5},
                )
            ax.set_xticks(np.arange(len(groups)))
            ax.set_xticklabels(groups, fontsize=5.5, rotation=30 if len(groups) > 3 else 0)
            ax.tick_params(axis="y", labelsize=5.5)
            ax.yaxis.get_offset_text().set_fontsize(5.5)
            ax.yaxis.set_major_locator(MaxNLocator(nbins=4))
            ax.set_title("success rate [%]" if row is None else row.heading, fontsize=6.5)
            if row is None:
                ax.set_ylim(0, 105)
            if c == 0:
                ax.set_ylabel(BAR_SECTIONS[r], fontsize=7)
    if any(hues):
        handles, labels = axes[0][0].get_legend_handles_labels()
        fig.legend(
            handles,
            labels,
            loc="lower center",
            ncols=min(len(hues), 4),
            fontsize=6,
            bbox_to_anchor=(0.5, 0.0),
        )
    if x_key:
        fig.suptitle(f"Table-10 metrics by {x_key}", fontsize=8)
    save_figure(fig, out_dir, stem)
    return fig


def _bins(values: np.ndarray, max_bins: int = 8) -> np.ndarray:
    """Bin edges: one bin per distinct value when few, else bins of about equal counts."""
    distinct = np.unique(np.round(values, 12))
    if len(distinct) <= max_bins:
        if len(distinct) == 1:
            return np.array([distinct[0] - 0.5, distinct[0] + 0.5])
        mids = (distinct[1:] + distinct[:-1]) / 2
        return np.concatenate(
            [[distinct[0] - (mids[0] - distinct[0])], mids, [distinct[-1] + (distinct[-1] - mids[-1])]]
        )
    n = int(min(max_bins, max(3, math.sqrt(len(values)))))
    edges = np.unique(np.quantile(values, np.linspace(0.0, 1.0, n + 1)))
    return edges if len(edges) > 1 else np.array([values.min() - 0.5, values.max() + 0.5])


def misalignment_components(df: pd.DataFrame) -> list[tuple[str, str, float]]:
    """The misalignment components (lateral, yaw, tilt) that vary in ``df``."""
    found = []
    for key, label, scale in MISALIGNMENT_AXES:
        if key in df and pd.to_numeric(df[key], errors="coerce").abs().round(12).nunique() > 1:
            found.append((key, label, scale))
    return found


def success_vs_misalignment(
    df: pd.DataFrame, out_dir: str | Path | None = None, stem: str = "success_vs_misalignment"
):
    """Success rate (top) and peak axial force (bottom) against each varying component.

    x: the drawn |error| of the job (lateral distance, |yaw|, |tilt|); success rate per
    bin of it, one line per controller when the controller varies, annotated with the
    number of jobs; bottom: every job's peak force, filled when it docked. Returns None
    when no misalignment component varies in ``df``.
    """
    components = misalignment_components(df)
    if not components:
        return None
    plt = apply_style()
    series_key = "controller" if "controller" in configuration_keys(df) else None
    series = list(dict.fromkeys(df[series_key].astype(str))) if series_key else [""]
    fig, axes = plt.subplots(
        2,
        len(components),
        figsize=(2.4 * len(components) + 0.4, 3.6),
        constrained_layout=True,
        squeeze=False,
        sharex="col",
    )
    colors = plt.rcParams["axes.prop_cycle"].by_key().get("color", ["C0"])
    for c, (key, label, scale) in enumerate(components):
        x_all = pd.to_numeric(df[key], errors="coerce").abs().to_numpy() * scale
        edges = _bins(x_all[np.isfinite(x_all)])
        for s, name in enumerate(series):
            mask = (df[series_key].astype(str) == name).to_numpy() if series_key else np.ones(len(df), bool)
            x = x_all[mask]
            docked = (df.loc[mask, "success"] == True).to_numpy()  # noqa: E712
            idx = np.clip(np.digitize(x, edges) - 1, 0, len(edges) - 2)
            centers, rates, ns = [], [], []
            for b in range(len(edges) - 1):
                sel = (idx == b) & np.isfinite(x)
                if sel.any():
                    centers.append(x[sel].mean())
                    rates.append(100.0 * docked[sel].mean())
                    ns.append(int(sel.sum()))
            color = colors[s % len(colors)]
            axes[0][c].plot(centers, rates, "o-", color=color, ms=3, label=name or None)
            for xc, rate, n in zip(centers, rates, ns):
                axes[0][c].annotate(
                    str(n),
                    (xc, rate),
                    textcoords="offset points",
                    xytext=(0, 3),
                    fontsize=4.5,
                    ha="center",
                    color=color,
                )
            peak = (
                pd.to_numeric(df.loc[mask, "peak_axial_force_N"], errors="coerce").to_numpy()
                if "peak_axial_force_N" in df
                else np.full(mask.sum(), np.nan)
            )
            axes[1][c].scatter(
                x[docked], peak[docked], s=9, facecolors=color, edgecolors=color, linewidths=0.6, marker="o"
            )
            axes[1][c].scatter(
                x[~docked],
                peak[~docked],
                s=9,
                facecolors="none",
                edgecolors=color,
                linewidths=0.6,
                marker="o",
            )
        axes[0][c].set_ylim(-5, 105)
        axes[0][c].set_ylabel("success rate [%]" if c == 0 else "")
        axes[1][c].set_ylabel("peak axial force [N]" if c == 0 else "")
        axes[1][c].set_xlabel(label)
    if series_key:
        axes[0][0].legend(fontsize=6)
    fig.suptitle("docking against socket misalignment (filled: docked; numbers: jobs)", fontsize=7)
    save_figure(fig, out_dir, stem)
    return fig


def _docking_axis(run_dir: Path) -> np.ndarray | None:
    """The unit stroke of the run (its docking axis) from .hydra/config.yaml."""
    cfg = rundir.read_config(run_dir)
    if cfg is None:
        return None
    try:
        stroke = np.asarray(cfg["task"]["stroke"], dtype=float)
        norm = np.linalg.norm(stroke)
        return stroke / norm if norm > 0 else None
    except Exception:
        return None


def select_runs(df: pd.DataFrame, max_runs: int = 6) -> pd.DataFrame:
    """One run per configuration (its first finished one), at most ``max_runs``."""
    if df.empty:
        return df
    finished = df[~df["status"].isin(FAILED_STATUSES)]
    labels = configuration_labels(finished)
    picked = finished.groupby(labels, sort=False).head(1)
    return picked.head(max_runs)


def force_overlay(
    df: pd.DataFrame,
    out_dir: str | Path | None = None,
    *,
    runs: pd.DataFrame | None = None,
    max_runs: int = 6,
    stem: str = "force_overlay",
):
    """Axial contact force over time of selected runs (default :func:`select_runs`).

    The axial force is −f·axis (positive: the plug presses into the socket), the axis
    being the run's unit ``task.stroke``; runs without a time series are left out.
    Returns None when no selected run has a time series.
    """
    chosen = select_runs(df, max_runs) if runs is None else runs
    if chosen.empty:
        return None
    labels = configuration_labels(df).reindex(chosen.index)
    traces = []
    for index, row in chosen.iterrows():
        if not rundir.has_timeseries(Path(row["run_dir"])):
            continue
        try:
            ts = rundir.read_timeseries(Path(row["run_dir"]), columns=["t", *FORCE])
        except Exception as exc:  # a truncated or corrupt file: leave this run out, say so
            warnings.warn(
                f"skipping the time series of {row['run_dir']}: {type(exc).__name__}: "
                f"{(str(exc).strip().splitlines() or [''])[0][:200]}",
                RunSkippedWarning,
                stacklevel=2,
            )
            continue
        axis = _docking_axis(Path(row["run_dir"]))
        force = ts[FORCE].to_numpy()
        axial = axial_force(force, axis) if axis is not None else np.linalg.norm(force, axis=1)
        traces.append((labels.get(index, row["job"]), ts["t"].to_numpy(), axial))
    if not traces:
        return None
    plt = apply_style()
    fig, ax = plt.subplots(figsize=(4.2, 2.4))
    # fixed margins [in] and a fixed legend corner: an automatic layout and the "best"
    # legend place (searched against every point drawn) cost more than the drawing
    fig.subplots_adjust(left=0.72 / 4.2, right=1 - 0.1 / 4.2, bottom=0.45 / 2.4, top=1 - 0.3 / 2.4)
    for label, t, axial in traces:
        ax.plot(*envelope(t, axial), lw=0.7, label=label)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("axial contact force [N]")
    ax.legend(fontsize=5.5, loc="upper left")
    ax.set_title("axial contact force (pressing +)", fontsize=7)
    save_figure(fig, out_dir, stem)
    return fig


def plot_comparison(df: pd.DataFrame, out_dir: str | Path, formats: Sequence[str] = FORMATS) -> list[Path]:
    """All comparison figures of ``df`` into ``out_dir`` (PNG, or ``formats``); returns the files.

    The bars only when there are configurations to compare (:func:`configuration_keys`:
    repeats of one configuration are one bar per panel, which the table says better);
    the success against the misalignment only when the misalignment varies.
    """
    plt = apply_style()
    out = Path(out_dir)
    saved: list[Path] = []
    makers: list[tuple[Callable[[pd.DataFrame], Any], str]] = [
        (success_vs_misalignment, "success_vs_misalignment"),
        (force_overlay, "force_overlay"),
    ]
    if configuration_keys(df):
        makers.insert(0, (metric_bars, "table10_bars"))
    for make, stem in makers:
        fig = make(df)
        if fig is None:
            continue
        saved += save_figure(fig, out, stem, formats)
        plt.close(fig)
    return saved
