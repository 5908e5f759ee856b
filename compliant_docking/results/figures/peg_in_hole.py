"""Figures of the peg-in-hole comparison (:mod:`compliant_docking.results.peg_in_hole`): per
group of cases, one panel per case with the insertion force F_z and the lateral force
−F_x against the tip's depth below the bore's lip, simulation (solid: the run at the
comparison's speed; thin: its quasi-static extrapolation) against the theory (dashed),
and the theory's two-point onset and wedging depth (vertical lines)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

import compliant_docking.results.figures.common as common
from compliant_docking.evaluation.insertion_statics import TWO_POINT, WEDGED, InsertionCurve

#: forces below this [N] are drawn on a linear scale, above it logarithmically (a panel whose
#: forces stay below ten times this is linear throughout)
LINEAR_BELOW = 0.05
COLUMNS = 3


def draw(panels: Sequence, out_dir: Path) -> list[Path]:
    """One figure per group of ``panels``: (case, the binned run, its quasi-static
    extrapolation, the theory's curve) tuples.  Returns the files written."""
    plt = common.comparison_style()
    groups: dict[str, list] = {}
    for panel in panels:
        groups.setdefault(panel[0].group, []).append(panel)
    written: list[Path] = []
    for group, members in groups.items():
        rows = math.ceil(len(members) / COLUMNS)
        cols = min(COLUMNS, len(members))
        height = 1.9 * rows + 0.7
        fig, axes = plt.subplots(rows, cols, figsize=(max(2.4 * cols, 4.8), height), squeeze=False)
        for ax, member in zip(axes.flat, members):
            _panel(ax, *member)
        for ax in list(axes.flat)[len(members) :]:
            ax.set_visible(False)
        handles, labels = axes.flat[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="upper center", ncol=3, frameon=False)
        fig.supxlabel("tip depth below the bore's lip [mm]")
        fig.tight_layout(rect=(0, 0, 1, 1 - 0.55 / height))
        written += common.save_figure(
            fig, out_dir, f"peg_in_hole_{group.replace(' + ', '_').replace(' ', '_')}"
        )
        plt.close(fig)
    return written


def _panel(ax, case, base, qs, curve: InsertionCurve) -> None:
    ok = np.array(curve.phase) != WEDGED
    mm = 1e3
    ax.plot(mm * base["depth"], base["F_z"], color="C0", lw=1.0, label="F_z, simulation")
    ax.plot(
        mm * qs["depth"], qs["F_z"], color="C0", lw=0.5, alpha=0.6, label="F_z, quasi-static extrapolation"
    )
    ax.plot(mm * curve.depth[ok], curve.insertion_force[ok], color="C0", lw=1.0, ls="--", label="F_z, theory")
    ax.plot(mm * base["depth"], -base["F_x"], color="C1", lw=1.0, label="−F_x, simulation")
    ax.plot(mm * curve.depth[ok], -curve.lateral_force[ok], color="C1", lw=1.0, ls="--", label="−F_x, theory")
    onset = curve.onset(TWO_POINT)
    if math.isfinite(onset):
        ax.axvline(mm * onset, color="0.4", lw=0.6, ls=":")
    wedge = curve.onset(WEDGED)
    if math.isfinite(wedge):
        ax.axvline(mm * wedge, color="C3", lw=0.8, ls="-.")
        ax.text(
            mm * wedge,
            0.9,
            " wedged (theory)",
            color="C3",
            fontsize=common.FONT - 1.5,
            transform=ax.get_xaxis_transform(),
        )
    peak = np.nanmax(np.abs(np.concatenate([base["F_z"], base["F_x"]])))
    if peak > 10.0 * LINEAR_BELOW:  # small forces stay linear (and legible)
        ax.set_yscale("symlog", linthresh=LINEAR_BELOW)
    ax.set_ylim(bottom=0.0)
    ax.set_title(case.name)
    ax.set_ylabel("force [N]")
    ax.set_xlim(mm * float(base["depth"].min()), mm * float(base["depth"].max()))
