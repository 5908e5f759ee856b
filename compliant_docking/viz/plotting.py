"""Figures of one run, in SciencePlots style, each saved as PNG and PDF.

matplotlib is imported lazily with the non-interactive Agg backend, so runs on machines
without a display work and importing this module stays cheap. Long series are thinned
for drawing with a min/max envelope, so short force peaks stay visible.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from compliant_docking.sim.telemetry import FORCE, MOMENT, ORI_ERROR, axial_force

MAX_POINTS = 1200
PNG_DPI = 200


def apply_style():
    """SciencePlots' 'science' style without LaTeX; returns pyplot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import scienceplots  # noqa: F401  (registers the styles)

    plt.style.use(["science", "no-latex"])
    # no minor ticks: laying them out was most of the plotting time
    plt.rcParams.update(
        {
            "figure.dpi": 100,
            "savefig.dpi": PNG_DPI,
            "axes.grid": True,
            "grid.alpha": 0.3,
            "legend.frameon": False,
            "xtick.minor.visible": False,
            "ytick.minor.visible": False,
        }
    )
    return plt


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
    ts: pd.DataFrame, out_dir: Path, *, axis: np.ndarray, torque_limits: np.ndarray, title: str = ""
) -> list[Path]:
    """Tracking, errors, contact force and joint torques of one run; returns the files."""
    plt = apply_style()
    out_dir.mkdir(parents=True, exist_ok=True)
    t = ts["t"].to_numpy()
    saved: list[Path] = []

    def save(fig, stem: str) -> None:
        if title:
            fig.suptitle(title, fontsize=7)
        for suffix in (".png", ".pdf"):
            path = out_dir / f"{stem}{suffix}"
            fig.savefig(path)
            saved.append(path)
            fig.set_layout_engine("none")  # laid out once, by the first save
        plt.close(fig)

    # 1. TCP position against the reference
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(3.5, 3.6), constrained_layout=True)
    for ax, c in zip(axes, "xyz"):
        ax.plot(*envelope(t, ts[f"{c}_ref"].to_numpy()), "--", label="reference")
        ax.plot(*envelope(t, ts[c].to_numpy()), "-", label="actual")
        ax.set_ylabel(f"{c} [m]")
    axes[0].legend(ncols=2, loc="best")
    axes[-1].set_xlabel("time [s]")
    save(fig, "tcp_tracking")

    # 2. tracking errors
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(3.5, 2.8), constrained_layout=True)
    axes[0].semilogy(*envelope(t, np.clip(ts["pos_error"].to_numpy() * 1e3, 1e-6, None)))
    axes[0].set_ylabel("position error [mm]")
    ori = np.degrees(np.linalg.norm(ts[ORI_ERROR].to_numpy(), axis=1))
    axes[1].plot(*envelope(t, ori))
    axes[1].set_ylabel("orientation error [deg]")
    axes[1].set_xlabel("time [s]")
    save(fig, "tracking_error")

    # 3. contact force and wrench
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    force = ts[FORCE].to_numpy()
    axial = axial_force(force, axis)
    lateral = np.linalg.norm(force + np.outer(axial, axis), axis=1)
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(3.5, 2.8), constrained_layout=True)
    axes[0].plot(*envelope(t, axial), label="axial (pressing +)")
    axes[0].plot(*envelope(t, lateral), label="lateral")
    axes[0].set_ylabel("contact force [N]")
    axes[0].legend(loc="best")
    axes[1].plot(*envelope(t, np.linalg.norm(ts[MOMENT].to_numpy(), axis=1)))
    axes[1].set_ylabel("contact moment [N m]")
    axes[1].set_xlabel("time [s]")
    save(fig, "contact_force")

    # 4. joint torques with the clip
    taus = sorted(
        (c for c in ts.columns if c.startswith("tau") and c[3:].isdigit()), key=lambda c: int(c[3:])
    )
    rows = (len(taus) + 1) // 2
    fig, axes = plt.subplots(rows, 2, sharex=True, figsize=(3.5, 0.9 * rows + 0.6), constrained_layout=True)
    for i, ax in enumerate(axes.flat):
        if i >= len(taus):
            ax.set_visible(False)
            continue
        ax.plot(*envelope(t, ts[taus[i]].to_numpy()), lw=0.8)
        for sign in (-1, 1):
            ax.axhline(sign * torque_limits[i], color="0.5", lw=0.5, ls=":")
        ax.set_ylabel(f"τ{i + 1} [N m]")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    save(fig, "joint_torques")
    return saved
