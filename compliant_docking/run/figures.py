"""Per-run figures: ``figures/`` of a run directory (docs/run_directory.md).

A single run draws them; a sweep job does not unless asked (:func:`wanted`), so a job's
time goes to simulating. ``python -m compliant_docking.report PATH --runs`` draws them
later for every finished run under PATH (:func:`redraw`), from the run's time series
and its composed config. matplotlib is imported only when something is drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from compliant_docking.run import rundir
from compliant_docking.sim.telemetry import QUATERNION


def wanted(cfg: Any, *, sweep: bool) -> bool:
    """Whether a job draws its figures: the config key ``figures`` when true or false;
    when null (the default), a single run does and a sweep job does not."""
    value = cfg.get("figures") if hasattr(cfg, "get") else None
    return (not sweep) if value is None else bool(value)


def marks(cfg: Any, record: dict) -> Any:
    """What the figures mark (:class:`compliant_docking.viz.plotting.RunMarks`) from the run's
    config (plain data or DictConfig) and its metrics record: the force budget and the
    docking time of a docking run; free space (no target); the segments and thresholds of
    the tracking test."""
    from compliant_docking.planning.tracking import segment_times
    from compliant_docking.viz.plotting import RunMarks

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
    marks: Any = None,
) -> list[Path]:
    """Draw the run's figures into ``job_dir/figures/`` (replacing the folder whole)."""
    from compliant_docking.viz.plotting import FORMATS, plot_run

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
