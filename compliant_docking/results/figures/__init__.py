"""Figures comparing runs, from a :func:`~compliant_docking.results.load_runs` frame (the
run figures' style, PNG; PDF on request). One module per what a figure shows:

- :mod:`.metrics`: :func:`metric_bars`, grouped bars of the docking metrics and the success
  rate across configurations (mean over repeats, whiskers: the bootstrap 95 % interval of
  the mean, Wilson's for the success rate);
- :mod:`.success`: :func:`success_vs_misalignment`, :func:`success_vs_error`,
  :func:`success_map`, success against the drawn socket misalignment and the drawn errors,
  binned with Wilson intervals, and the 2-D map over lateral × tilt error per controller;
- :mod:`.force`: :func:`force_overlay`, the axial contact force of every run aligned on
  its first contact, faceted robot × controller;
- :mod:`.peg_in_hole`: the peg-in-hole comparison's force curves against the theory;
- :mod:`.common`: what they share (style, saving, facets, the notes on each figure);
- :func:`plot_comparison` (here): those that have something to show into one folder (what
  the end of a sweep and ``python -m compliant_docking.report`` call).

No figure drops a configuration silently: what a figure pools or leaves out is written on it.

Every function returns the matplotlib Figure (for a notebook: ``display(fig)``) and,
given ``out_dir``, also saves it as ``<stem>.png`` (other formats: ``formats``, e.g.
``("png", "pdf")``; a PDF costs about as much as the PNG).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from compliant_docking.results.figures.common import comparison_style, save_figure
from compliant_docking.results.figures.force import force_overlay
from compliant_docking.results.figures.metrics import BAR_SECTIONS, metric_bars
from compliant_docking.results.figures.success import (
    MISALIGNMENT_AXES,
    misalignment_components,
    success_map,
    success_vs_error,
    success_vs_misalignment,
)
from compliant_docking.results.tables import configuration_keys
from compliant_docking.viz.style import FORMATS

__all__ = [
    "BAR_SECTIONS",
    "MISALIGNMENT_AXES",
    "force_overlay",
    "metric_bars",
    "misalignment_components",
    "plot_comparison",
    "save_figure",
    "success_map",
    "success_vs_error",
    "success_vs_misalignment",
]


def plot_comparison(df: pd.DataFrame, out_dir: str | Path, formats: Sequence[str] = FORMATS) -> list[Path]:
    """All comparison figures of ``df`` into ``out_dir`` (PNG, or ``formats``); returns the files.

    The bars only when there are configurations to compare (:func:`configuration_keys`:
    repeats of one configuration are one bar per panel, which the table says better);
    the success against the misalignment only when the misalignment varies, its 2-D map
    only when both the lateral and the tilt error vary; the force overlay when some run
    touched the socket.
    """
    plt = comparison_style()
    out = Path(out_dir)
    saved: list[Path] = []
    makers: list[tuple[Callable[[pd.DataFrame], Any], str]] = [
        (success_vs_misalignment, "success_vs_misalignment"),
        (success_vs_error, "success_vs_error"),
        (success_map, "success_map"),
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
