"""Success against the drawn socket misalignment, and against the drawn model, sensor and
contact errors.

- :func:`success_vs_misalignment`: per varying component (lateral distance, yaw magnitude, tilt),
  the success rate per bin of draws with its Wilson 95 % interval, one line per controller,
  and below it every job's first-strike force (else its peak axial force), filled when
  it docked;
- :func:`success_vs_error`: the same against the size of each drawn error of the controller's
  model, its sensor and the plant's contact (the robustness groups);
- :func:`success_map`: the 2-D map over lateral × tilt error for each controller (rows:
  robots), in the manner of Whitney's jamming/wedging diagrams for peg-in-hole insertion:
  cells coloured by the success rate of the draws in them (docked/jobs written in each),
  every draw a marker saying how it ended (docked, stuck short of the seat, over the
  force budget, another gate item, failed run).

Both pool the configurations that differ in anything but the controller (and the robot
for the map) and say so on the figure.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

import compliant_docking.results.figures.common as common
from compliant_docking.results.stats import wilson
from compliant_docking.results.tables import configuration_keys

#: misalignment components: (metrics.json key, axis label, scale to the shown unit)
MISALIGNMENT_AXES = (
    ("misalignment_lateral_m", "lateral error [mm]", 1e3),
    ("misalignment_yaw_deg", "yaw error, magnitude [deg]", 1.0),
    ("misalignment_tilt_deg", "tilt error [deg]", 1.0),
)
#: drawn errors of the robustness groups: (metrics.json key, axis label, scale to the shown
#: unit, the neutral value the size is measured from)
ERROR_AXES = (
    ("model_error_tool_mass_kg", "payload error |Δm| [g]", 1e3, 0.0),
    ("model_error_link_mass_scale", "link mass error [%]", 100.0, 1.0),
    ("sensor_force_bias_N", "F/T force bias |b| [N]", 1.0, 0.0),
    ("contact_friction", "contact friction μ", 1.0, 0.0),
    ("contact_timeconst", "contact time constant [ms]", 1e3, 0.0),
)
#: how a draw ended, with its marker: (name, marker, face colour)
OUTCOMES = {
    "docked": ("o", "#00B945"),
    "stuck short of the seat (jammed/wedged)": ("x", "k"),
    "over the force budget": ("^", "C3"),
    "another gate item": ("d", "0.4"),
    "run failed": ("s", "none"),
}


def _bins(values: np.ndarray, max_bins: int = 8, few: int = 4) -> np.ndarray:
    """Bin edges: one bin per distinct value when there are at most ``few`` of them, else
    about √(distinct values) bins (3 to ``max_bins``) holding about equally many draws (10
    draws: 3 bins, 30: 5), so that each rate pools several draws."""
    distinct = np.unique(np.round(values, 12))
    if len(distinct) <= few:
        if len(distinct) == 1:
            return np.array([distinct[0] - 0.5, distinct[0] + 0.5])
        mids = (distinct[1:] + distinct[:-1]) / 2
        return np.concatenate(
            [[distinct[0] - (mids[0] - distinct[0])], mids, [distinct[-1] + (distinct[-1] - mids[-1])]]
        )
    n = int(min(max_bins, max(3, round(math.sqrt(len(distinct))))))
    edges = np.unique(np.quantile(distinct, np.linspace(0.0, 1.0, n + 1)))
    return edges if len(edges) > 1 else np.array([values.min() - 0.5, values.max() + 0.5])


def misalignment_components(df: pd.DataFrame) -> list[tuple[str, str, float]]:
    """The misalignment components (lateral, yaw, tilt) that vary in ``df``; the yaw only
    for a keyed interface (``key_symmetry`` > 0) or without a tilt: a round socket has no
    yaw of its own, the yaw then only turns the direction of the tilt."""
    keyed = "key_symmetry" in df and (pd.to_numeric(df["key_symmetry"], errors="coerce") > 0).any()
    found = []
    for key, label, scale in MISALIGNMENT_AXES:
        if key in df and pd.to_numeric(df[key], errors="coerce").abs().round(12).nunique() > 1:
            found.append((key, label, scale))
    tilted = any(key == "misalignment_tilt_deg" for key, _, _ in found)
    return [c for c in found if c[0] != "misalignment_yaw_deg" or keyed or not tilted]


def _grid(values: np.ndarray, max_bins: int) -> np.ndarray:
    """Equal-width bin edges over the values (the map's cells), about √(distinct) of them."""
    distinct = len(np.unique(np.round(values, 12)))
    bins = int(np.clip(round(math.sqrt(distinct)), 2, max_bins))
    low, high = float(values.min()), float(values.max())
    if high <= low:
        low, high = low - 0.5, high + 0.5
    pad = 1e-9 * (high - low)
    return np.linspace(low - pad, high + pad, bins + 1)


def outcome(row) -> str:
    """How a job ended, for the map's markers (:data:`OUTCOMES`)."""
    if row.get("status") == "failed":
        return "run failed"
    if row.get("success") is True:
        return "docked"
    reason = str(row.get("gate_failures") or row.get("gate_verdict") or "").lower()
    if "depth" in reason or "not seated" in reason:
        return "stuck short of the seat (jammed/wedged)"
    if "force" in reason:
        return "over the force budget"
    return "another gate item"


def _series(df: pd.DataFrame) -> tuple[str | None, list[str], list[str]]:
    """(the controller column when it varies, its values, the pooled configuration keys)."""
    keys = configuration_keys(df)
    key = "controller" if "controller" in keys else None
    values = list(dict.fromkeys(df[key].astype(str))) if key else [""]
    return key, values, [k for k in keys if k != key]


def success_vs_misalignment(
    df: pd.DataFrame, out_dir: str | Path | None = None, stem: str = "success_vs_misalignment"
):
    """Success rate with Wilson intervals (top) and the strike force of every job (bottom)
    against each varying misalignment component; None when none varies (module doc)."""
    components = [(key, label, scale, 0.0) for key, label, scale in misalignment_components(df)]
    if not components:
        return None
    return _success_against(df, components, "docking against socket misalignment", out_dir, stem)


def error_components(df: pd.DataFrame) -> list[tuple[str, str, float, float]]:
    """The drawn model, sensor and contact errors (:data:`ERROR_AXES`) that vary in ``df``."""
    found = []
    for key, label, scale, neutral in ERROR_AXES:
        if key in df and pd.to_numeric(df[key], errors="coerce").round(12).nunique() > 1:
            found.append((key, label, scale, neutral))
    return found


def success_vs_error(df: pd.DataFrame, out_dir: str | Path | None = None, stem: str = "success_vs_error"):
    """As :func:`success_vs_misalignment`, against the size of each drawn error of the
    controller's model, its sensor and the plant's contact (``model_error``, ``sensor``,
    ``dynamics``); None when none varies."""
    components = error_components(df)
    if not components:
        return None
    return _success_against(
        df, components, "docking against what the controller does not know", out_dir, stem
    )


def _success_against(df, components, title: str, out_dir, stem: str):
    """The success-rate and force panels against each component (key, label, scale, neutral):
    x = |value − neutral| × scale."""
    plt = common.comparison_style()
    series_key, series, pooled = _series(df)
    force_key = "first_strike_force_N" if "first_strike_force_N" in df else "peak_axial_force_N"
    force_label = "first-strike force [N]" if force_key == "first_strike_force_N" else "peak axial force [N]"
    # one panel (misalignment_keyed: the yaw only) still gets room for the legend and the note
    width, height = max(2.3 * len(components) + 0.6, 4.4), 4.1
    fig, axes = plt.subplots(2, len(components), figsize=(width, height), squeeze=False, sharex="col")
    fig.subplots_adjust(left=0.55 / width, right=1 - 0.1 / width, bottom=0.95 / height, top=1 - 0.35 / height,
                        wspace=0.3, hspace=0.12)  # fmt: skip
    palette = common.colors(plt)
    docked_all = (df["success"] == True).to_numpy()  # noqa: E712
    force_all = (
        pd.to_numeric(df[force_key], errors="coerce").to_numpy()
        if force_key in df
        else np.full(len(df), np.nan)
    )
    for c, (key, label, scale, neutral) in enumerate(components):
        x_all = (pd.to_numeric(df[key], errors="coerce") - neutral).abs().to_numpy() * scale
        finite = np.isfinite(x_all)
        edges = _bins(x_all[finite])
        width_bin = np.min(np.diff(edges))
        for s, name in enumerate(series):
            mask = (df[series_key].astype(str) == name).to_numpy() if series_key else np.ones(len(df), bool)
            mask = mask & finite
            x, docked = x_all[mask], docked_all[mask]
            idx = np.clip(np.digitize(x, edges) - 1, 0, len(edges) - 2)
            centres, rates, lows, highs = [], [], [], []
            for b in range(len(edges) - 1):
                sel = idx == b
                if sel.any():
                    k, n = int(docked[sel].sum()), int(sel.sum())
                    low, high = wilson(k, n)
                    centres.append(x[sel].mean() + (s - (len(series) - 1) / 2) * 0.06 * width_bin)
                    rates.append(100.0 * k / n)
                    lows.append(max(100.0 * (k / n - low), 0.0))  # ≥ 0: round-off at 0 and n
                    highs.append(max(100.0 * (high - k / n), 0.0))
            color = palette[s % len(palette)]
            axes[0][c].errorbar(centres, rates, yerr=[lows, highs], fmt="o-", color=color, ms=2.5, lw=0.8,
                                elinewidth=0.6, capsize=1.5, label=name or None)  # fmt: skip
            force = force_all[mask]
            axes[1][c].scatter(x[docked], force[docked], s=7, color=color, lw=0.5)
            axes[1][c].scatter(x[~docked], force[~docked], s=7, facecolors="none", edgecolors=color, lw=0.5)
        axes[0][c].set_ylim(-5, 105)
        axes[1][c].set_xlabel(label)
    axes[0][0].set_ylabel("success rate [%]")
    axes[1][0].set_ylabel(force_label)
    fig.align_ylabels(axes[:, 0])
    if series_key:
        fig.legend(*axes[0][0].get_legend_handles_labels(), loc="lower center", ncols=min(len(series), 4),
                   bbox_to_anchor=(0.5, 0.2 / height))  # fmt: skip
    budget = common.budget_of(df)
    if budget is not None:
        for ax in axes[1]:
            if budget <= 3 * max(np.nanmax(force_all, initial=0.0), 1e-9):
                ax.axhline(budget, color="C3", lw=0.7, ls="--")
    common.note(
        fig,
        [
            f"{len(df)} jobs; bins of the drawn error, whiskers: Wilson 95 % interval of the success rate; "
            "bottom: every job, filled = docked",
            f"pooled over: {', '.join(pooled)}" if pooled else "",
        ],
    )
    fig.suptitle(title)
    common.save_figure(fig, out_dir, stem)
    return fig


def success_map(df: pd.DataFrame, out_dir: str | Path | None = None, stem: str = "success_map"):
    """Success over lateral × tilt error per controller (rows: robots when they vary); None
    unless both vary (module doc)."""
    names = [k for k, _, _ in misalignment_components(df)]
    if "misalignment_lateral_m" not in names or "misalignment_tilt_deg" not in names:
        return None
    plt = common.comparison_style()
    row, rows, col, cols, rest = common.facets(df)
    lateral = pd.to_numeric(df["misalignment_lateral_m"], errors="coerce").to_numpy() * 1e3
    tilt = pd.to_numeric(df["misalignment_tilt_deg"], errors="coerce").abs().to_numpy()
    x_edges = _grid(lateral[np.isfinite(lateral)], max_bins=6)
    y_edges = _grid(tilt[np.isfinite(tilt)], max_bins=5)
    ends = df.apply(outcome, axis=1).to_numpy()
    docked = ends == "docked"
    width = 2.1 * len(cols) + 0.7
    height = 1.9 * len(rows) + 1.15
    fig, axes = plt.subplots(
        len(rows), len(cols), figsize=(width, height), squeeze=False, sharex=True, sharey=True
    )
    fig.subplots_adjust(left=0.55 / width, right=1 - 0.1 / width, bottom=1.0 / height, top=1 - 0.4 / height,
                        wspace=0.12, hspace=0.3)  # fmt: skip
    cmap = plt.get_cmap("RdYlGn")
    for r, row_value in enumerate(rows):
        for c, col_value in enumerate(cols):
            ax = axes[r][c]
            mask = (
                common.select(df, row, row_value, col, col_value).to_numpy()
                & np.isfinite(lateral)
                & np.isfinite(tilt)
            )
            ix = np.clip(np.digitize(lateral[mask], x_edges) - 1, 0, len(x_edges) - 2)
            iy = np.clip(np.digitize(tilt[mask], y_edges) - 1, 0, len(y_edges) - 2)
            rate = np.full((len(y_edges) - 1, len(x_edges) - 1), np.nan)
            for i in range(len(x_edges) - 1):
                for j in range(len(y_edges) - 1):
                    sel = (ix == i) & (iy == j)
                    if sel.any():
                        rate[j, i] = docked[mask][sel].mean()
                        ax.text((x_edges[i] + x_edges[i + 1]) / 2, (y_edges[j] + y_edges[j + 1]) / 2,
                                f"{int(docked[mask][sel].sum())}/{int(sel.sum())}", ha="center", va="center",
                                fontsize=common.FONT - 1.5, color="0.15")  # fmt: skip
            ax.pcolormesh(x_edges, y_edges, rate, cmap=cmap, vmin=0.0, vmax=1.0, alpha=0.45, shading="flat")
            for name, (marker, face) in OUTCOMES.items():
                sel = ends[mask] == name
                if not sel.any():
                    continue
                if marker == "x":  # an unfilled marker takes a colour, no edge
                    style = {"color": face}
                elif face == "none":
                    style = {"facecolors": "none", "edgecolors": "k"}
                else:
                    style = {"facecolors": face, "edgecolors": "k"}
                ax.scatter(
                    lateral[mask][sel], tilt[mask][sel], s=10, marker=marker, lw=0.5, label=name, **style
                )
            ax.set_title(common.facet_title(row, row_value, col, col_value) or "all runs")
            if r == len(rows) - 1:
                ax.set_xlabel("lateral error [mm]")
            if c == 0:
                ax.set_ylabel("tilt error [deg]")
            ax.set_xlim(x_edges[0], x_edges[-1])
            ax.set_ylim(y_edges[0], y_edges[-1])
    fig.align_ylabels(axes[:, 0])
    handles: dict = {}
    for ax in axes.flat:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    fig.legend(list(handles.values()), list(handles), loc="lower center", ncols=min(len(handles), 3),
               bbox_to_anchor=(0.5, 0.2 / height))  # fmt: skip
    common.note(
        fig,
        [
            f"{len(df)} draws; cells: docked/jobs, colour = success rate (red 0, green 1)",
            f"pooled over: {', '.join(rest)}" if rest else "",
        ],
    )
    fig.suptitle("success over lateral × tilt error (jamming/wedging map)")
    common.save_figure(fig, out_dir, stem)
    return fig
