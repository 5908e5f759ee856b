"""The axial contact force of every run, aligned on its first contact (:func:`force_overlay`).

Panels: robot (rows) × controller (columns), whichever vary; in each panel one colour per
remaining configuration (planner, clearance, …). A configuration with fewer than
:data:`BAND_MIN` runs draws each run; with more, the median over its runs and the band
from the 10th to the 90th percentile, on a common time grid. Time 0 is the run's first
contact (the state whose physics step first found a contact); the window is zoomed around
it. The docking gate's force budget is drawn (or named, when far above the forces). Runs
without a time series or without contact are counted in a note on the figure.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

import compliant_docking.results.figures.common as common
from compliant_docking.results.load import RunSkippedWarning
from compliant_docking.results.tables import FAILED_STATUSES, configuration_labels
from compliant_docking.run import rundir
from compliant_docking.sim.telemetry import FORCE, axial_force

#: a configuration with at least this many runs is drawn as median and 10–90 % band
BAND_MIN = 5
#: the window around the first contact [s] and the grid step of the band [s]
WINDOW = (-0.05, 0.6)
GRID_STEP = 0.001


def _axis(job: pd.Series) -> np.ndarray | None:
    """The unit stroke of the run (its docking axis): the ``task.stroke`` column of the
    load_runs frame, else the run's .hydra/config.yaml."""
    stroke = job.get("task.stroke")
    try:
        if isinstance(stroke, str):
            stroke = json.loads(stroke)
        if stroke is None or (isinstance(stroke, float) and np.isnan(stroke)):
            cfg = rundir.read_config(Path(job["run_dir"]))
            stroke = None if cfg is None else cfg["task"]["stroke"]
        vector = np.asarray(stroke, dtype=float)
        norm = np.linalg.norm(vector)
        return vector / norm if vector.shape == (3,) and norm > 0 else None
    except Exception:
        return None


def aligned_trace(
    run_dir: Path, axis: np.ndarray | None, window: tuple[float, float] = WINDOW
) -> tuple[np.ndarray, np.ndarray] | None:
    """(time since first contact, axial force along the unit ``axis``: the force's norm when
    None) of a run over ``window``; None without a time series or without contact."""
    if not rundir.has_timeseries(run_dir):
        return None
    try:
        ts = rundir.read_timeseries(run_dir, columns=["t", "contacts", *FORCE])
    except Exception as exc:  # a truncated or corrupt file: leave this run out, say so
        warnings.warn(
            f"skipping the time series of {run_dir}: {type(exc).__name__}: "
            f"{(str(exc).strip().splitlines() or [''])[0][:200]}",
            RunSkippedWarning,
            stacklevel=2,
        )
        return None
    touching = np.flatnonzero(ts["contacts"].to_numpy() > 0)
    if not touching.size:
        return None
    t = ts["t"].to_numpy()
    t0 = t[max(int(touching[0]) - 1, 0)]
    keep = (t >= t0 + window[0]) & (t <= t0 + window[1])
    force = ts[FORCE].to_numpy()[keep]
    axial = axial_force(force, axis) if axis is not None else np.linalg.norm(force, axis=1)
    return t[keep] - t0, axial


def force_overlay(
    df: pd.DataFrame,
    out_dir: str | Path | None = None,
    *,
    runs: pd.DataFrame | None = None,
    window: tuple[float, float] = WINDOW,
    stem: str = "force_overlay",
):
    """Axial contact force around the first contact of every run of ``df`` (or of ``runs``,
    rows of it) that was not failed or interrupted, faceted robot × controller (module
    doc). Returns the Figure, or None when no run has a time series with a contact."""
    chosen = df if runs is None else runs
    chosen = chosen[~chosen["status"].isin(FAILED_STATUSES)] if len(chosen) else chosen
    if chosen.empty:
        return None
    row, rows, col, cols, rest = common.facets(df)
    labels = common.series_labels(df, rest).reindex(chosen.index)
    traces: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    missing: list[str] = []
    for index, job in chosen.iterrows():
        trace = aligned_trace(Path(job["run_dir"]), _axis(job), window)
        if trace is None:
            missing.append(str(job["job"]))
        else:
            traces[index] = trace
    if not traces:
        return None
    plt = common.comparison_style()
    width = 1.9 * len(cols) + 0.7
    height = 1.45 * len(rows) + 1.1
    fig, axes = plt.subplots(len(rows), len(cols), figsize=(width, height), squeeze=False, sharex=True)
    fig.subplots_adjust(left=0.55 / width, right=1 - 0.1 / width, bottom=0.9 / height, top=1 - 0.42 / height,
                        wspace=0.3, hspace=0.35)  # fmt: skip
    palette = common.colors(plt)
    order = list(dict.fromkeys(labels))
    color_of = {label: palette[i % len(palette)] for i, label in enumerate(order)}
    grid = np.arange(window[0], window[1] + GRID_STEP / 2, GRID_STEP)
    budget = common.budget_of(chosen)
    banded = False
    for r, row_value in enumerate(rows):
        for c, col_value in enumerate(cols):
            ax = axes[r][c]
            here = [i for i in traces if common.select(chosen, row, row_value, col, col_value)[i]]
            ax.set_title(common.facet_title(row, row_value, col, col_value))
            drawn_max = 0.0
            for label in order:
                mine = [i for i in here if labels[i] == label]
                if not mine:
                    continue
                color = color_of[label]
                if len(mine) >= BAND_MIN:
                    banded = True
                    stack = np.vstack([np.interp(grid, *traces[i], left=np.nan, right=np.nan) for i in mine])
                    with np.errstate(all="ignore"), warnings.catch_warnings():
                        warnings.simplefilter("ignore", RuntimeWarning)  # grid points no run reached
                        low, mid, high = np.nanpercentile(stack, [10, 50, 90], axis=0)
                    ax.fill_between(grid, low, high, color=color, alpha=0.25, lw=0, gid=f"band:{label}")
                    ax.plot(grid, mid, color=color, lw=0.9, label=label or None, gid=f"median:{label}")
                    drawn_max = max(drawn_max, float(np.nanmax(high, initial=0.0)))
                else:
                    for k, i in enumerate(mine):
                        ax.plot(*traces[i], color=color, lw=0.6, label=(label or None) if k == 0 else None,
                                gid=f"run:{label}")  # fmt: skip
                        drawn_max = max(drawn_max, float(np.max(traces[i][1], initial=0.0)))
            ax.axvline(0.0, color="0.5", lw=0.5, ls=":")
            if budget is not None and budget <= 1.5 * drawn_max:
                ax.axhline(budget, color="C3", lw=0.8, ls="--")
            elif budget is not None and here:
                ax.annotate(f"budget {budget:g} N: above", (0.98, 0.95), xycoords="axes fraction", ha="right",
                            va="top", color="C3", fontsize=common.FONT - 1)  # fmt: skip
            if r == len(rows) - 1:
                ax.set_xlabel("time since first contact [s]")
            if c == 0:
                ax.set_ylabel("axial force [N]")
    fig.align_ylabels(axes[:, 0])
    handles: dict = {}
    for ax in axes.flat:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="lower center", ncols=min(len(handles), 4),
                   bbox_to_anchor=(0.5, 0.2 / height))  # fmt: skip
    configurations = configuration_labels(df).reindex(list(traces))
    counts = configurations.value_counts()
    notes = [
        f"{len(traces)} runs of {len(counts)} configurations ({counts.min()}–{counts.max()} each); "
        + (
            "median and 10–90 % band where a configuration has ≥ 5 runs, each run otherwise"
            if banded
            else "each run"
        )
        + (f"; dashed: the force budget {budget:g} N" if budget is not None else ""),
    ]
    if missing:
        shown = ", ".join(missing[:4]) + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
        notes.append(f"not shown, no readable time series or no contact: {len(missing)} runs ({shown})")
    common.note(fig, notes)
    fig.suptitle("axial contact force (pressing +), aligned on the first contact")
    common.save_figure(fig, out_dir, stem)
    return fig
