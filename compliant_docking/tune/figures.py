"""Figures of a tuning study, from its trials table (:func:`~compliant_docking.tune.outputs.trials_frame`).

- :func:`plot_history`: each trial's value against its number, penalised trials marked
  along the top edge, and the best value so far (one panel per objective value);
- :func:`plot_pareto`: two objectives against each other, the Pareto front joined.

Each is saved as PNG and PDF in the style of every figure (viz/style.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from compliant_docking.tune.objectives import Objective
from compliant_docking.viz.style import apply_style, save

HISTORY, PARETO = "optimisation_history", "pareto_front"
LABELS = {"force_N": "force [N]", "time_s": "docking time [s]"}
#: a study's figures are few and go into papers: PDF beside the PNG
FORMATS = ("png", "pdf")


def plot_history(frame: pd.DataFrame, objective: Objective, out_dir: Path, metric: str = "") -> list[Path]:
    """The optimisation history (see the module docstring); the files written."""
    plt = apply_style()
    told = frame[frame[objective.value_names[0]].notna()] if len(frame) else frame
    names = objective.value_names
    fig, axes = plt.subplots(len(names), 1, figsize=(5.0, 2.4 * len(names)), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        good = told[told["feasible"].astype(bool)]
        bad = told[~told["feasible"].astype(bool)]
        if len(good):
            ax.plot(good["number"], good[name], "o", ms=4, color="C0", label="trial (every draw docked)")
            best = np.minimum.accumulate(good[name].to_numpy())
            ax.step(good["number"], best, where="post", color="C3", lw=1.2, label="best so far")
            top, low = float(good[name].max()), float(good[name].min())
            # a single value (or equal ones) gets ±10 % of its size (at least ±0.5), not a 1e-9 span
            span = top - low if top > low else max(0.2 * abs(top), 1.0)
            ax.set_ylim(low - 0.1 * span, top + 0.25 * span)
        else:  # nothing to scale: no invented value axis
            ax.set_yticks([])
            ax.text(0.5, 0.5, f"no trial docked on every draw ({len(bad)} penalised)", transform=ax.transAxes,
                    ha="center", va="center", fontsize=8, color="0.3")  # fmt: skip
        if len(bad):  # along the panel's top edge (axes coordinates): a penalty is not a value
            ax.plot(bad["number"], [1.0] * len(bad), "x", color="0.4", clip_on=False, label="penalised",
                    transform=ax.get_xaxis_transform())  # fmt: skip
        ax.set_xlim(-0.5, max(float(told["number"].max()) if len(told) else 0.0, 1.0) + 0.5)
        ax.set_ylabel(f"{metric} [N]" if metric and name == "force_N" else LABELS.get(name, name))
        ax.legend(loc="upper right", fontsize=7)
    axes[-1, 0].set_xlabel("trial")
    fig.suptitle(f"Optimisation history: {objective.name} (values over the draws)", fontsize=9)
    fig.tight_layout()
    paths = save(fig, Path(out_dir), HISTORY, FORMATS)
    plt.close(fig)
    return paths


def plot_pareto(frame: pd.DataFrame, objective: Objective, out_dir: Path, metric: str = "") -> list[Path]:
    """The Pareto front of a two-value objective (nothing for one value)."""
    if len(objective.value_names) != 2 or not len(frame):
        return []
    plt = apply_style()
    x, y = objective.value_names
    good = frame[frame["feasible"].astype(bool) & frame[x].notna()]
    fig, ax = plt.subplots(figsize=(4.5, 3.4))
    penalised = int((~frame["feasible"].astype(bool)).sum())
    if not len(good):  # nothing to plot: say so rather than an empty frame
        ax.set_xticks([])
        ax.set_yticks([])
        ax.text(0.5, 0.5, f"no trial docked on every draw\n({penalised} penalised): no front yet",
                transform=ax.transAxes, ha="center", va="center", fontsize=8, color="0.3")  # fmt: skip
    else:
        ax.plot(good[x], good[y], "o", ms=4, color="0.6", label="trial (every draw docked)")
    values = good[[x, y]].to_numpy()
    front = [i for i, p in enumerate(values) if not any((q <= p).all() and (q < p).any() for q in values)]
    if front:
        pts = good.iloc[front].sort_values(x)
        ax.step(pts[x], pts[y], where="post", color="C3", lw=1.0)
        ax.plot(pts[x], pts[y], "o", ms=5, color="C3", label="Pareto front")
        for _, row in pts.iterrows():
            ax.annotate(
                str(int(row["number"])),
                (row[x], row[y]),
                textcoords="offset points",
                xytext=(3, 3),
                fontsize=6,
            )
    ax.set_xlabel(f"mean {metric} [N]" if metric and x == "force_N" else LABELS.get(x, x))
    ax.set_ylabel(LABELS.get(y, y))
    ax.set_title(f"Pareto front ({penalised} penalised trials not shown)", fontsize=9)
    if len(good):
        ax.legend(fontsize=7)
    fig.tight_layout()
    paths = save(fig, Path(out_dir), PARETO, FORMATS)
    plt.close(fig)
    return paths
