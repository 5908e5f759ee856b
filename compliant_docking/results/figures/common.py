"""What the comparison figures share: their style, saving, facets and the notes that say what
a figure leaves out (no figure drops a configuration silently)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from compliant_docking.results.tables import configuration_keys, configuration_labels
from compliant_docking.viz.style import FORMATS, apply_style, save

#: one font size for labels, ticks and legends of the comparison figures [pt]
FONT = 7.0


def comparison_style():
    """The run figures' style with one readable size for labels, ticks, legends and titles
    (legends at the axes' font size), no offset notation; returns pyplot."""
    plt = apply_style()
    plt.rcParams.update(
        {
            "font.size": FONT,
            "axes.labelsize": FONT,
            "axes.titlesize": FONT,
            "xtick.labelsize": FONT - 0.5,
            "ytick.labelsize": FONT - 0.5,
            "legend.fontsize": FONT - 0.5,
            "figure.titlesize": FONT + 0.5,
            "axes.formatter.useoffset": False,
        }
    )
    return plt


def save_figure(fig, out_dir: str | Path | None, stem: str, formats: Sequence[str] = FORMATS) -> list[Path]:
    """Save ``fig`` as ``out_dir/stem.<format>`` for each of ``formats`` (nothing when
    out_dir is None)."""
    return [] if out_dir is None else save(fig, Path(out_dir), stem, formats)


def note(fig, lines: Sequence[str]) -> None:
    """Small text at the figure's bottom left: what the figure pools or leaves out."""
    lines = [line for line in lines if line]
    if lines:
        text = fig.text(
            0.005, 0.005, "\n".join(lines), fontsize=FONT - 1.5, va="bottom", ha="left", color="0.3"
        )
        fit_width(fig, text)


def fit_width(fig, text, margin: float = 0.995) -> None:
    """Shrink ``text``'s font until it fits the figure's width (a long note on a narrow
    figure, e.g. one panel): a saved figure would clip it otherwise."""
    renderer = fig.canvas.get_renderer()
    for _ in range(8):  # a glyph's width is not proportional to the size at small sizes
        extent = text.get_window_extent(renderer)
        room = fig.bbox.width * margin - extent.x0
        if extent.width <= room or room <= 0:
            return
        text.set_fontsize(text.get_fontsize() * max(room / extent.width, 0.5) * 0.97)


def facets(df: pd.DataFrame, rows_key: str = "robot", cols_key: str = "controller"):
    """(row key or None, row values, column key or None, column values, the remaining
    configuration keys): rows by ``rows_key`` and columns by ``cols_key`` when they vary."""
    keys = configuration_keys(df)
    row = rows_key if rows_key in keys else None
    col = cols_key if cols_key in keys else None
    rows = list(dict.fromkeys(df[row].astype(str))) if row else [""]
    cols = list(dict.fromkeys(df[col].astype(str))) if col else [""]
    rest = [k for k in keys if k not in (row, col)]
    return row, rows, col, cols, rest


def select(df: pd.DataFrame, row: str | None, row_value: str, col: str | None, col_value: str) -> pd.Series:
    """The rows of one facet."""
    mask = pd.Series(True, index=df.index)
    if row:
        mask &= df[row].astype(str) == row_value
    if col:
        mask &= df[col].astype(str) == col_value
    return mask


def series_labels(df: pd.DataFrame, keys: list[str]) -> pd.Series:
    """The label of each row over ``keys`` ('' when none: one series)."""
    return configuration_labels(df, keys) if keys else pd.Series("", index=df.index)


def colors(plt) -> list[str]:
    return plt.rcParams["axes.prop_cycle"].by_key().get("color", ["C0"])


def facet_title(row: str | None, row_value: str, col: str | None, col_value: str) -> str:
    return " · ".join(v for v in (row_value if row else "", col_value if col else "") if v)


def budget_of(df: pd.DataFrame) -> float | None:
    """The docking gate's peak force budget of the runs (their config column), if one."""
    column = "task.gate.peak_force_budget_N"
    if column not in df:
        return None
    values = pd.to_numeric(df[column], errors="coerce").dropna().unique()
    return float(np.max(values)) if len(values) else None
