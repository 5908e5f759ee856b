"""Figures of one run, in SciencePlots style, saved as PNG (other formats on request).

matplotlib is imported lazily with the non-interactive Agg backend, so runs on machines
without a display work, and a job that draws nothing never imports it. Long series are
thinned for drawing with a min/max envelope, so short force peaks stay visible.

What drawing costs (4 figures of a default run, CPU time, benchmarks/figure_cost.py):
0.39 s as drawn here; 1.75 s with what was dropped — a PDF copy of each figure,
mathtext tick labels, the constrained-layout engine and tight bounding boxes (each
alone adds 0.15-0.3 s, together they compound). So the figures are laid out on fixed
margins in inches (their labels have a known size), saved without a tight box, with
plain-text tick labels, as PNG; PDF (or SVG) on request
(``python -m compliant_docking.report PATH --runs --formats png pdf``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from compliant_docking.sim.telemetry import FORCE, MOMENT, ORI_ERROR, axial_force

MAX_POINTS = 1200
PNG_DPI = 200
#: formats of a run's figures unless asked otherwise (file suffixes without the dot)
FORMATS = ("png",)
#: formats matplotlib's Agg-based backends write here
KNOWN_FORMATS = ("png", "pdf", "svg")
#: figure width [in] and fixed margins [in]: left (tick labels + y label), right, bottom
#: (tick labels + x label), top (the title), and the gaps between panels
WIDTH = 3.5
LEFT, RIGHT, BOTTOM, TOP = 0.72, 0.1, 0.42, 0.26
HGAP, WGAP = 0.1, 0.62


def apply_style():
    """SciencePlots' 'science' style without LaTeX, tuned for speed; returns pyplot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import scienceplots  # noqa: F401  (registers the styles)

    plt.style.use(["science", "no-latex"])
    plt.rcParams.update(
        {
            "figure.dpi": 100,
            "savefig.dpi": PNG_DPI,
            "savefig.bbox": None,  # a tight box lays every figure out twice; margins are fixed
            "axes.formatter.use_mathtext": False,  # mathtext tick labels: ~0.25 s per run
            "axes.grid": True,
            "grid.alpha": 0.3,
            "legend.frameon": False,
            # no minor ticks: laying them out was most of the plotting time
            "xtick.minor.visible": False,
            "ytick.minor.visible": False,
        }
    )
    return plt


def check_formats(formats: Sequence[str]) -> tuple[str, ...]:
    """The formats, lower case without dots; ValueError naming the allowed ones."""
    out = tuple(str(f).lower().lstrip(".") for f in formats)
    unknown = [f for f in out if f not in KNOWN_FORMATS]
    if unknown or not out:
        raise ValueError(
            f"figure formats must be some of {', '.join(KNOWN_FORMATS)}, got {', '.join(map(str, formats)) or 'none'}"
        )
    return out


def save(fig, out_dir: Path, stem: str, formats: Sequence[str] = FORMATS) -> list[Path]:
    """``fig`` as ``out_dir/stem.<format>`` for each format; returns the files."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for fmt in check_formats(formats):
        path = out_dir / f"{stem}.{fmt}"
        fig.savefig(path)
        paths.append(path)
    return paths


def panels(plt, rows: int, cols: int = 1, *, panel_height: float, top: float = TOP, hgap: float = HGAP):
    """A figure of rows × cols panels of ``panel_height`` inches on the fixed margins
    (``top``, ``hgap``: more room for an axis offset such as ``1e-5+5.5e-1``)."""
    height = top + BOTTOM + rows * panel_height + (rows - 1) * hgap
    panel_width = (WIDTH - LEFT - RIGHT - (cols - 1) * WGAP) / cols
    fig, axes = plt.subplots(rows, cols, sharex=True, figsize=(WIDTH, height), squeeze=False)
    fig.subplots_adjust(
        left=LEFT / WIDTH,
        right=1 - RIGHT / WIDTH,
        bottom=BOTTOM / height,
        top=1 - top / height,
        hspace=hgap / panel_height,
        wspace=WGAP / panel_width,
    )
    return fig, axes


def envelope(t: np.ndarray, y: np.ndarray, max_points: int = MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Thin (t, y) to about max_points, keeping each bucket's minimum and maximum."""
    n = len(t)
    if n <= max_points:
        return t, y
    buckets = max_points // 2
    size = int(np.ceil(n / buckets))
    pad = buckets * size - n
    tt = np.concatenate([t, np.full(pad, t[-1])]).reshape(buckets, size)
    yy = np.concatenate([y, np.full(pad, y[-1])]).reshape(buckets, size)
    lo, hi = yy.argmin(axis=1), yy.argmax(axis=1)
    first, second = np.minimum(lo, hi), np.maximum(lo, hi)
    rows = np.arange(buckets)
    t_out = np.column_stack([tt[rows, first], tt[rows, second]]).ravel()
    y_out = np.column_stack([yy[rows, first], yy[rows, second]]).ravel()
    return t_out, y_out


def plot_run(
    ts: pd.DataFrame,
    out_dir: Path,
    *,
    axis: np.ndarray,
    torque_limits: np.ndarray,
    title: str = "",
    formats: Sequence[str] = FORMATS,
) -> list[Path]:
    """Tracking, errors, contact force and joint torques of one run; returns the files."""
    formats = check_formats(formats)
    plt = apply_style()
    out_dir.mkdir(parents=True, exist_ok=True)
    t = ts["t"].to_numpy()
    saved: list[Path] = []

    def finish(fig, axes, stem: str) -> None:
        for ax in axes[-1]:
            ax.set_xlabel("time [s]")
        if title:
            fig.suptitle(title, fontsize=7, y=1 - 0.06 / fig.get_figheight(), va="top")
        saved.extend(save(fig, out_dir, stem, formats))
        plt.close(fig)

    # 1. TCP position against the reference
    fig, axes = panels(plt, 3, panel_height=0.95, top=0.42, hgap=0.22)  # room for offsets
    for ax, c in zip(axes[:, 0], "xyz"):
        ax.plot(*envelope(t, ts[f"{c}_ref"].to_numpy()), "--", label="reference")
        ax.plot(*envelope(t, ts[c].to_numpy()), "-", label="actual")
        ax.set_ylabel(f"{c} [m]")
    axes[0, 0].legend(ncols=2, loc="upper right")
    finish(fig, axes, "tcp_tracking")

    # 2. tracking errors
    fig, axes = panels(plt, 2, panel_height=1.25)
    axes[0, 0].semilogy(*envelope(t, np.clip(ts["pos_error"].to_numpy() * 1e3, 1e-6, None)))
    axes[0, 0].set_ylabel("position error [mm]")
    ori = np.degrees(np.linalg.norm(ts[ORI_ERROR].to_numpy(), axis=1))
    axes[1, 0].plot(*envelope(t, ori))
    axes[1, 0].set_ylabel("orientation err. [deg]")
    finish(fig, axes, "tracking_error")

    # 3. contact force and wrench
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    force = ts[FORCE].to_numpy()
    axial = axial_force(force, axis)
    lateral = np.linalg.norm(force + np.outer(axial, axis), axis=1)
    fig, axes = panels(plt, 2, panel_height=1.25)
    axes[0, 0].plot(*envelope(t, axial), label="axial (pressing +)")
    axes[0, 0].plot(*envelope(t, lateral), label="lateral")
    axes[0, 0].set_ylabel("contact force [N]")
    axes[0, 0].legend(loc="upper left")
    axes[1, 0].plot(*envelope(t, np.linalg.norm(ts[MOMENT].to_numpy(), axis=1)))
    axes[1, 0].set_ylabel("contact moment [N m]")
    finish(fig, axes, "contact_force")

    # 4. joint torques with the clip
    taus = sorted(
        (c for c in ts.columns if c.startswith("tau") and c[3:].isdigit()), key=lambda c: int(c[3:])
    )
    rows = (len(taus) + 1) // 2
    fig, axes = panels(plt, rows, 2, panel_height=0.62)
    for i, ax in enumerate(axes.flat):
        if i >= len(taus):
            ax.set_visible(False)
            if i >= 2:  # the panel above it carries the time axis
                axes.flat[i - 2].xaxis.set_tick_params(labelbottom=True)
                axes.flat[i - 2].set_xlabel("time [s]")
            continue
        ax.plot(*envelope(t, ts[taus[i]].to_numpy()), lw=0.8)
        for sign in (-1, 1):
            ax.axhline(sign * torque_limits[i], color="0.5", lw=0.5, ls=":")
        ax.set_ylabel(f"τ{i + 1} [N m]")
    finish(fig, axes, "joint_torques")
    return saved
