"""The figures of one run: ``figures/`` of a run directory (docs/run_directory.md), what
they show and who draws them.

What they show (:func:`plot_run`): the TCP against the reference (``tcp_tracking``), the
tracking errors (``tracking_error``), the contact force and moment zoomed on the contact
(``contact_force``, docking runs), the joint torques with their clip (``joint_torques``)
and, for the tracking test, each curve's path (``tracking_path``); :class:`RunMarks` says
what they mark beyond the time series (force budget, docking time, the tracking gate).

Who draws them: a single run does; a sweep job does not unless asked (:func:`wanted`), so
a job's time goes to simulating. ``python -m compliant_docking.report PATH --runs`` draws
them later for every finished run under PATH (:func:`redraw`), from the run's time series
and its composed config.

matplotlib is imported only when something is drawn (:mod:`compliant_docking.viz.style`).
Long series are thinned for drawing with a min/max envelope, so short force peaks stay
visible. What drawing costs (4 figures of a default run, CPU time,
benchmarks/figure_cost.py): 0.39 s as drawn here; 1.75 s with what was dropped — a PDF
copy of each figure, mathtext tick labels, the constrained-layout engine and tight
bounding boxes (each alone adds 0.15-0.3 s, together they compound). So the figures are
laid out on fixed margins in inches (their labels have a known size), saved without a
tight box, with plain-text tick labels, as PNG; PDF (or SVG) on request
(``python -m compliant_docking.report PATH --runs --formats png pdf``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from compliant_docking.evaluation.contact import first_contact_state
from compliant_docking.run import rundir
from compliant_docking.sim.telemetry import FORCE, MOMENT, ORI_ERROR, QUATERNION, axial_force
from compliant_docking.viz.style import FORMATS, apply_style, check_formats, save

MAX_POINTS = 1200
#: figure width [in] and fixed margins [in]: left (tick labels + y label), right, bottom
#: (tick labels + x label), top (the title), and the gaps between panels
WIDTH = 3.5
LEFT, RIGHT, BOTTOM, TOP = 0.72, 0.1, 0.42, 0.26
HGAP, WGAP = 0.1, 0.62


def wanted(cfg: Any, *, sweep: bool) -> bool:
    """Whether a job draws its figures: the config key ``figures`` when true or false;
    when null (the default), a single run does and a sweep job does not."""
    value = cfg.get("figures") if hasattr(cfg, "get") else None
    return (not sweep) if value is None else bool(value)


def marks(cfg: Any, record: dict) -> RunMarks:
    """What the figures mark (:class:`RunMarks`) from the run's config (plain data or
    DictConfig) and its metrics record: the force budget and the docking time of a docking
    run; free space (no target); the segments and thresholds of the tracking test."""
    from compliant_docking.planning.tracking import segment_times

    task = cfg.get("task") or {}
    target = cfg.get("target") or {}
    trajectory = cfg.get("trajectory") or {}
    free_space = target.get("name") == "none"
    segments: tuple = ()
    thresholds: dict = {}
    if free_space and trajectory.get("name") == "tracking":
        try:
            segments = tuple(
                segment_times(
                    float(trajectory["transition_duration"]),
                    float(trajectory["circle_duration"]),
                    float(trajectory["figure8_duration"]),
                )
            )
            thresholds = {
                k: float(v) for k, v in dict(task.get("tracking_gate") or {}).items() if v is not None
            }
        except (KeyError, TypeError, ValueError):
            segments = ()
    budget = (task.get("gate") or {}).get("peak_force_budget_N")
    docked = record.get("docking_time_s")
    return RunMarks(
        budget=None if free_space or budget is None else float(budget),
        docking_time=None if docked is None else float(docked),
        free_space=free_space,
        segments=segments,
        thresholds=thresholds,
    )


def draw(
    job_dir: Path,
    ts,
    *,
    axis: np.ndarray,
    torque_limits: np.ndarray,
    title: str,
    formats: Sequence[str] | None = None,
    marks: RunMarks | None = None,
) -> list[Path]:
    """Draw the run's figures into ``job_dir/figures/`` (replacing the folder whole)."""
    files: list[Path] = []

    def plot(folder: Path) -> None:
        files.extend(
            plot_run(
                ts,
                folder,
                axis=axis,
                torque_limits=torque_limits,
                title=title,
                formats=formats or FORMATS,
                marks=marks,
            )
        )

    rundir.write_figures(job_dir, plot)
    final = Path(job_dir) / rundir.FIGURES_DIR
    return [final / f.name for f in files]


def redraw(job_dir: Path, formats: Sequence[str] | None = None) -> list[Path]:
    """Draw the figures of a finished run from its files; ValueError saying what is missing."""
    job_dir = Path(job_dir)
    if not rundir.has_timeseries(job_dir):
        raise ValueError(
            "no timeseries.parquet (the run failed before its time series was written, "
            "or ran with output.timeseries=false: metrics only)"
        )
    cfg = rundir.read_config(job_dir)
    if cfg is None:
        raise ValueError("no readable .hydra/config.yaml (needed for the torque limits and the docking axis)")
    try:
        torque_limits = np.asarray(cfg["robot"]["max_torque"], dtype=float)
        names = [str(cfg[group]["name"]) for group in ("robot", "controller", "trajectory")]
    except (KeyError, TypeError) as exc:
        raise ValueError(f".hydra/config.yaml lacks {exc}") from None
    ts = rundir.read_timeseries(job_dir)
    record = rundir.read_metrics(job_dir)[0] or {}
    return draw(
        job_dir,
        ts,
        axis=docking_axis(cfg, ts),
        torque_limits=torque_limits,
        title=" · ".join(names),
        formats=formats,
        marks=marks(cfg, record),
    )


def docking_axis(cfg: dict, ts) -> np.ndarray:
    """The run's docking axis: its unit ``task.stroke`` (as the run had it), or, for a zero
    stroke (free space), the tool's z axis at the start (as the run had it)."""
    stroke = np.asarray(cfg.get("task", {}).get("stroke") or [0.0, 0.0, 0.0], dtype=float)
    norm = float(np.linalg.norm(stroke))
    if norm > 0.0:
        return stroke / norm
    w, x, y, z = ts[QUATERNION].to_numpy()[0]
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


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


def _min_span(ax, span: float) -> None:
    """At least ``span`` on the y axis (a held coordinate would otherwise show µm noise with
    long tick labels), centred on the data."""
    low, high = ax.get_ylim()
    if high - low < span:
        mid = (low + high) / 2
        ax.set_ylim(mid - span / 2, mid + span / 2)


def first_contact_time(ts: pd.DataFrame) -> float | None:
    """The metrics' ``first_contact_time_s`` read from a saved series: the time of
    :func:`~compliant_docking.evaluation.contact.first_contact_state`, or None without contact."""
    if "contacts" not in ts or not len(ts):
        return None
    state = first_contact_state(ts["contacts"].to_numpy())
    return None if state is None else float(ts["t"].iloc[state])


@dataclass(frozen=True)
class RunMarks:
    """What a run's figures mark beyond its time series (all optional).

    ``budget``: the docking gate's peak force budget [N]; ``docking_time``: when the plug
    docked (``docking_time_s``) [s]; ``free_space``: no target (no contact-force figure);
    ``segments``: the planner's ``(name, t0, t1)``; ``thresholds``: the tracking gate's
    (``task.tracking_gate``: ``circle_position_rms_m``, …), drawn for the tracking test.
    """

    budget: float | None = None
    docking_time: float | None = None
    free_space: bool = False
    segments: tuple[tuple[str, float, float], ...] = ()
    thresholds: dict = field(default_factory=dict)


#: tracking-gate segments drawn as paths: name → (plane axes, label)
PATH_SEGMENTS = {
    "circle": (("y", "z"), "circle (y–z plane)"),
    "figure8": (("x", "y"), "figure-8 (x–y plane)"),
}
#: what the contact-force figure shows before the first contact [s]
BEFORE_CONTACT = 0.3
#: the force budget is drawn when at most this multiple of the largest force shown (else named)
BUDGET_SHOWN = 3.0


def plot_run(
    ts: pd.DataFrame,
    out_dir: Path,
    *,
    axis: np.ndarray,
    torque_limits: np.ndarray,
    title: str = "",
    formats: Sequence[str] = FORMATS,
    marks: RunMarks | None = None,
) -> list[Path]:
    """Tracking, errors, contact force (docking runs) and joint torques of one run, plus the
    paths of a tracking test; returns the files."""
    formats = check_formats(formats)
    marks = marks or RunMarks()
    plt = apply_style()
    out_dir.mkdir(parents=True, exist_ok=True)
    t = ts["t"].to_numpy()
    saved: list[Path] = []

    def finish(fig, axes, stem: str) -> None:
        for ax in axes[-1]:
            ax.set_xlabel("time [s]")
        fig.align_ylabels(axes[:, 0])
        if title:
            fig.suptitle(title, fontsize=7, y=1 - 0.06 / fig.get_figheight(), va="top")
        saved.extend(save(fig, out_dir, stem, formats))
        plt.close(fig)

    # 1. TCP position against the reference
    fig, axes = panels(plt, 3, panel_height=0.95, top=0.42, hgap=0.22)
    for ax, c in zip(axes[:, 0], "xyz"):
        ax.plot(*envelope(t, ts[f"{c}_ref"].to_numpy()), "--", label="reference")
        ax.plot(*envelope(t, ts[c].to_numpy()), "-", label="actual")
        ax.set_ylabel(f"{c} [m]")
        _min_span(ax, 2e-3)
    axes[0, 0].legend(ncols=2, loc="upper right")
    finish(fig, axes, "tcp_tracking")

    # 2. tracking errors (the tracking test: its segments and the gate's thresholds)
    fig, axes = panels(plt, 2, panel_height=1.25)
    axes[0, 0].semilogy(*envelope(t, np.clip(ts["pos_error"].to_numpy() * 1e3, 1e-6, None)))
    axes[0, 0].set_ylabel("position error [mm]")
    ori = np.degrees(np.linalg.norm(ts[ORI_ERROR].to_numpy(), axis=1))
    axes[1, 0].plot(*envelope(t, ori))
    axes[1, 0].set_ylabel("orientation err. [deg]")
    _min_span(axes[1, 0], 0.01)
    if marks.thresholds and marks.segments:
        _gate_marks(axes[:, 0], marks)
    finish(fig, axes, "tracking_error")

    # 3. contact force and wrench, zoomed on the contact (docking runs only)
    if not marks.free_space:
        _contact_figure(plt, ts, axis, marks, finish)

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

    # 5. the tracking test: each curve's path against its reference, in its own plane
    drawn = [(name, t0, t1) for name, t0, t1 in marks.segments if name in PATH_SEGMENTS]
    if drawn:
        saved.extend(_path_figure(plt, ts, drawn, marks.thresholds, title, out_dir, formats))
    return saved


#: short names of the tracking test's segments on the error figure
SEGMENT_LABELS = {"transition_1": "tr. 1", "circle": "circle", "transition_2": "tr. 2", "figure8": "figure-8"}


def _gate_marks(axes, marks: RunMarks) -> None:
    """Segment boundaries (dotted, named above the plot) and the tracking gate's thresholds
    (red: dashed the RMS limits over their segments, dotted the peak limit)."""
    limits = marks.thresholds
    for ax in axes:
        for _, t0, _ in marks.segments:
            ax.axvline(t0, color="0.55", lw=0.5, ls=":")
        ax.axvline(marks.segments[-1][2], color="0.55", lw=0.5, ls=":")
    for name, t0, t1 in marks.segments:
        axes[0].annotate(SEGMENT_LABELS.get(name, name), ((t0 + t1) / 2, 1.0), xycoords=("data", "axes fraction"),
                         xytext=(0, 1), textcoords="offset points", fontsize=6, ha="center", va="bottom",
                         color="0.35")  # fmt: skip
    rms_label: str | None = "RMS limit"
    for name, t0, t1 in marks.segments:
        limit = limits.get(f"{name}_position_rms_m")
        if limit is not None:
            axes[0].hlines(limit * 1e3, t0, t1, color="C3", lw=0.8, ls="--", label=rms_label)
            rms_label = None
    motion = (marks.segments[0][1], marks.segments[-1][2])
    if limits.get("position_peak_m") is not None:
        axes[0].hlines(
            limits["position_peak_m"] * 1e3, *motion, color="C3", lw=0.8, ls=":", label="peak limit"
        )
    if limits.get("orientation_rms_rad") is not None:
        axes[1].hlines(np.degrees(limits["orientation_rms_rad"]), *motion, color="C3", lw=0.8, ls="--",
                       label="RMS limit")  # fmt: skip
        axes[1].legend(loc="upper left")  # the transitions' errors are small: room there
    axes[0].legend(loc="lower right", ncols=2)


def _contact_figure(plt, ts: pd.DataFrame, axis, marks: RunMarks, finish) -> None:
    t = ts["t"].to_numpy()
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    force = ts[FORCE].to_numpy()
    axial = axial_force(force, axis)
    lateral = np.linalg.norm(force + np.outer(axial, axis), axis=1)
    moment = np.linalg.norm(ts[MOMENT].to_numpy(), axis=1)
    contact = first_contact_time(ts)
    events = [v for v in (contact, marks.docking_time) if v is not None]
    start = max(t[0], min(events) - BEFORE_CONTACT) if events else t[0]
    window = t >= start
    fig, axes = panels(plt, 2, panel_height=1.25)
    ax = axes[0, 0]
    ax.plot(*envelope(t[window], axial[window]), label="axial (pressing +)")
    ax.plot(*envelope(t[window], lateral[window]), label="lateral")
    ax.set_ylabel("contact force [N]")
    axes[1, 0].plot(*envelope(t[window], moment[window]))
    axes[1, 0].set_ylabel("contact moment [N m]")
    ax.set_xlim(start, t[-1])
    top = float(max(axial[window].max(initial=0.0), lateral[window].max(initial=0.0)))
    if marks.budget is not None and marks.budget <= BUDGET_SHOWN * max(top, 1e-9):
        ax.axhline(marks.budget, color="C3", lw=0.8, ls="--", label=f"budget {marks.budget:g} N")
        ax.set_ylim(top=1.08 * max(marks.budget, top))  # the headroom to the budget in view
    elif marks.budget is not None:
        ax.annotate(f"budget {marks.budget:g} N: above the scale", (0.99, 0.97), xycoords="axes fraction",
                    ha="right", va="top", fontsize=7, color="C3")  # fmt: skip
    for a in axes[:, 0]:
        if contact is not None:
            a.axvline(contact, color="0.5", lw=0.6, ls=":")
        if marks.docking_time is not None:
            a.axvline(marks.docking_time, color="C2", lw=0.8, ls="-.")
    for when, text, color in ((contact, "first contact", "0.4"), (marks.docking_time, "docked", "C2")):
        if when is not None:
            axes[1, 0].annotate(text, (when, 0.97), xycoords=("data", "axes fraction"), xytext=(2, 0),
                                textcoords="offset points", fontsize=7, color=color, rotation=90,
                                va="top")  # fmt: skip
    if contact is None:
        ax.annotate("no contact in this run", (0.5, 0.5), xycoords="axes fraction", ha="center", fontsize=7)
    # legends at the tick labels' size; "best": where the strike and the press leave room
    ax.legend(loc="best", fontsize=plt.rcParams["ytick.labelsize"])
    finish(fig, axes, "contact_force")


def _path_figure(plt, ts, drawn, thresholds: dict, title: str, out_dir: Path, formats) -> list[Path]:
    t = ts["t"].to_numpy()
    width, height = WIDTH, 2.3
    fig, axes = plt.subplots(1, len(drawn), figsize=(width, height), squeeze=False)
    fig.subplots_adjust(left=0.16, right=0.98, bottom=0.19, top=0.76, wspace=0.45)
    for ax, (name, t0, t1) in zip(axes[0], drawn):
        (u, v), label = PATH_SEGMENTS[name]
        k = (t >= t0) & (t < t1)
        ax.plot(ts[f"{u}_ref"].to_numpy()[k], ts[f"{v}_ref"].to_numpy()[k], "--", lw=1.2, label="reference")
        ax.plot(ts[u].to_numpy()[k], ts[v].to_numpy()[k], "-", lw=0.7, label="actual")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{u} [m]")
        ax.set_ylabel(f"{v} [m]")
        rms = float(np.sqrt(np.mean(ts["pos_error"].to_numpy()[k] ** 2))) if k.any() else float("nan")
        limit = thresholds.get(f"{name}_position_rms_m")
        gate = f" (limit {limit * 1e3:g})" if limit is not None else ""
        ax.set_title(f"{label}\nRMS {rms * 1e3:.3g} mm{gate}", fontsize=7)
        ax.locator_params(nbins=4)
    axes[0, 0].legend(
        loc="center", fontsize=plt.rcParams["ytick.labelsize"], handlelength=1.2
    )  # in the circle
    fig.align_ylabels(axes[0])
    if title:
        fig.suptitle(title, fontsize=7, y=0.995, va="top")
    paths = save(fig, out_dir, "tracking_path", formats)
    plt.close(fig)
    return paths
