"""One job, from a composed config to a finished run directory.

:func:`execute` never raises: whatever happens, the run directory ends with a
``metrics.json`` whose ``status`` is "ok", "incomplete" (shorter than its trajectory)
or "failed" (with ``error``: a one-line reason). Every file is written atomically
(temporary name, then rename), and ``metrics.json`` last, so a directory holding a
``metrics.json`` is finished. See docs/run_directory.md for the layout.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
import traceback
from dataclasses import asdict
from pathlib import Path

import numpy as np
from omegaconf import DictConfig, OmegaConf

from compliant_docking import provenance
from compliant_docking.files import atomic_write, atomic_write_text
from compliant_docking.metrics import DockingMetrics, finite_or_none
from compliant_docking.misalignment import record_for as misalignment_record

METRICS_FILE = "metrics.json"
TIMESERIES_FILE = "timeseries.parquet"
SUMMARY_FILE = "summary.txt"
FIGURES_DIR = "figures"

#: exit status of ``python -m compliant_docking``
EXIT_SUCCESS, EXIT_FAILED, EXIT_GATE = 0, 1, 3


def write_metrics(path: Path, record: dict) -> None:
    """metrics.json: a flat JSON object; non-finite numbers become null."""
    clean = {k: finite_or_none(v) if isinstance(v, (float, np.floating, np.integer)) else v
             for k, v in record.items()}
    atomic_write_text(path, json.dumps(clean, indent=2, allow_nan=False) + "\n")


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().replace("\n", " ") or type(exc).__name__
    return text if isinstance(exc, (ValueError, RuntimeError)) else f"{type(exc).__name__}: {text}"


def execute(cfg: DictConfig, out_dir: Path, *, figures: bool = True, echo: bool = True) -> dict:
    """Run the job of ``cfg`` into ``out_dir``; returns the metrics record (never raises).

    The record starts with the fields naming the job (config choices, overrides).
    """
    from compliant_docking.simulate import Diverged, prepare

    started = time.perf_counter()
    started_at = provenance.now_iso()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    record: dict = {"status": "failed", "error": None, "success": False, **job_identity(cfg)}
    record.update({k: None for k in DockingMetrics.__dataclass_fields__})
    record.update(misalignment_record(cfg))  # true vs believed socket pose (flat keys)
    sim = None
    try:
        show = None
        if cfg.get("viewer"):  # MuJoCo's viewer at real time; refused in a sweep or without a display
            from compliant_docking import viewer as show

            show.check_allowed()
        sim = prepare(cfg)
        sim.run(progress=bool(cfg.task.progress) and echo,
                on_step=show.RealTimeViewer(sim) if show else None)
        record.update(_evaluate(sim, out_dir, figures=figures))
    except Diverged as exc:
        record["error"] = str(exc)
    except Exception as exc:  # a job records its own failure; the sweep goes on
        record["error"] = _one_line(exc)
        if not isinstance(exc, ValueError):
            traceback.print_exc(file=sys.stderr)
    if sim is not None:
        steps = sim.telemetry.count
        record["sim_time_s"] = steps * sim.scene.model.opt.timestep
        record["steps"] = steps
        record["real_time_factor"] = (record["sim_time_s"] / sim.loop_wall_time
                                      if sim.loop_wall_time > 0 else None)
        record["loop_wall_time_s"] = sim.loop_wall_time or None
        record.update(sim.controller.diagnostics())
    if cfg.get("render") is not None and cfg.render.name != "none":  # docking.mp4 (render.py)
        from compliant_docking.render import record_video

        record.update(record_video(sim, cfg, out_dir))  # never raises: video_error says why
    record["wall_time_s"] = time.perf_counter() - started
    record.update(provenance.collect(cfg, started_at=started_at))  # versions, git, config hash
    if record["status"] == "failed":
        record["success"] = False
    summary = format_summary(record, cfg) + f"\n  run directory: {_display_path(out_dir)}"
    if "video_error" in record:  # render=video: the video, or why there is none
        from compliant_docking.render import summary_line

        summary += summary_line(record)
    atomic_write_text(out_dir / SUMMARY_FILE, summary + "\n")
    write_metrics(out_dir / METRICS_FILE, record)  # last: its presence means "finished"
    if echo:
        print(summary)
    return record


def _evaluate(sim, out_dir: Path, *, figures: bool) -> dict:
    """Metrics, gate, time series and figures of a finished simulation."""
    from compliant_docking import metrics as M

    cfg, arm = sim.cfg, sim.scene.arm
    extras = sim.controller.timeseries()
    ts = sim.telemetry.frame(arm, sim.reference, np.asarray(cfg.robot.max_torque, float), extras)
    manip = M.manipulability_series(arm, sim.telemetry.q[:sim.telemetry.count])
    axis = sim.waypoints.axis
    docking = M.compute_metrics(
        ts, axis=axis, q_lower=arm.q_lower, q_upper=arm.q_upper,
        velocity_limits=np.asarray(cfg.robot.velocity_limits, float),
        manipulability=manip, steady_window=float(cfg.task.steady_window))
    result = asdict(docking)
    result["contacts_max"] = int(ts["contacts"].max()) if len(ts) else None
    result["torque_saturation_ratio"] = float(ts["torque_saturated"].mean()) if len(ts) else None

    # The gate: docking runs → the docking gate; free-space runs of the tracking planner →
    # the tracking gate; other free-space runs (hold, …) have no gate: success is null.
    from compliant_docking.trajectories.tracking import TrackingTrajectory

    failures: list[str] = []
    gated = True
    complete = sim.complete
    if sim.scene.socket is not None:
        seat = M.seat_state(ts, sim.scene.socket.true, float(cfg.task.steady_window),
                            float(cfg.task.gate.depth_tolerance_m))
        result.update(seat_depth_error_m=seat.depth_error_m,
                      seat_lateral_error_m=seat.lateral_error_m,
                      seat_tilt_deg=seat.tilt_deg, seated_time_s=seat.seated_time_s)
        failures = M.docking_gate(seat, docking, cfg.task.gate)
    elif isinstance(sim.trajectory, TrackingTrajectory):
        from compliant_docking.tracking_gate import tracking_gate

        gate = tracking_gate(ts, sim.trajectory.segments, cfg.task.tracking_gate,
                             complete=complete)
        result.update(gate.record())
        failures = list(gate.failures)
    else:
        gated = False
    if not complete:
        failures = sim.notes + failures
    result["status"] = "ok" if complete else "incomplete"
    result["success"] = (complete and not failures) if gated else None
    result["gate_failures"] = "; ".join(failures) or None

    atomic_write(out_dir / TIMESERIES_FILE,
                 lambda tmp: ts.to_parquet(tmp, index=False, compression="zstd"))
    if figures:
        from compliant_docking.plotting import plot_run

        tmp = out_dir / f".{FIGURES_DIR}.tmp"
        shutil.rmtree(tmp, ignore_errors=True)
        plot_run(ts, tmp, axis=axis, torque_limits=np.asarray(cfg.robot.max_torque, float),
                 title=f"{cfg.robot.name} · {cfg.controller.name} · {cfg.trajectory.name}")
        final = out_dir / FIGURES_DIR
        shutil.rmtree(final, ignore_errors=True)
        os.replace(tmp, final)
    return result


# --------------------------------------------------------------------------- summary
def _num(value, spec: str = ".4g", unit: str = "", scale: float = 1.0) -> str:
    if value is None:
        return "n/a"
    text = f"{value * scale:{spec}}"
    return f"{text} {unit}".rstrip()


def format_summary(record: dict, cfg: DictConfig | None = None) -> str:
    """A short aligned summary of a run for the console."""
    r = record.get
    title = ""
    if cfg is not None:
        title = f"{cfg.robot.name} · {cfg.controller.name} · {cfg.trajectory.name} · {cfg.physics.name}"

    def joint(pct, idx):
        return "n/a" if pct is None else f"{pct:.1f} % (joint {idx + 1})"

    rows = [
        ("[contact safety]", None),
        ("peak axial force", _num(r("peak_axial_force_N"), ".3f", "N")),
        ("peak wrench norm", _num(r("peak_wrench_norm_N"), ".3f", "N")),
        ("steady axial force", _num(r("steady_axial_force_N"), ".3f", "N")),
        ("steady wrench norm", _num(r("steady_wrench_norm_N"), ".3f", "N")),
        ("[internal safety]", None),
        ("max joint position use", joint(r("max_joint_pos_pct"), r("max_joint_pos_joint"))),
        ("max joint speed use", joint(r("max_joint_vel_pct"), r("max_joint_vel_joint"))),
        ("min manipulability", _num(r("min_manipulability"), ".4g")),
        ("[tracking accuracy]", None),
        ("position RMS", _num(r("pos_tracking_rms_m"), ".3f", "mm", 1e3)),
        ("orientation RMS", _num(r("ori_tracking_rms_rad"), ".3f", "deg", 180 / np.pi)),
        ("final lateral error", _num(r("final_lateral_error_m"), ".3f", "mm", 1e3)),
        ("final orientation error", _num(r("final_orientation_error_rad"), ".3f", "deg", 180 / np.pi)),
    ]
    if r("seat_depth_error_m") is not None or (r("gate_failures") and r("tracking_gate") is None):
        rows += [
            ("[seat, true socket pose]", None),
            ("depth error", _num(r("seat_depth_error_m"), ".3f", "mm", 1e3)),
            ("lateral error", _num(r("seat_lateral_error_m"), ".3f", "mm", 1e3)),
            ("tilt", _num(r("seat_tilt_deg"), ".3f", "deg")),
            ("seated at", _num(r("seated_time_s"), ".2f", "s")),
        ]
    if r("tracking_gate") is not None:  # printer hook: the free-space tracking gate
        from compliant_docking.tracking_gate import summary_rows

        rows += summary_rows(record)
    rows += [
        ("[run]", None),
        ("simulated", _num(r("sim_time_s"), ".2f", "s")),
        ("loop speed", _num(r("real_time_factor"), ".1f", "× real time")),
        ("wall time", _num(r("wall_time_s"), ".2f", "s")),
    ]
    width = max(len(label) for label, value in rows if value is not None)
    lines = ["=" * 64, f"compliant-docking: {title}".rstrip(": "), "=" * 64]
    for label, value in rows:
        lines.append(label if value is None else f"  {label:<{width}} : {value}")
    status = r("status")
    verdict = "success" if r("success") else ("FAILED" if status == "failed" else "not docked")
    if status != "failed" and r("tracking_gate") is not None:
        verdict = f"tracking gate {r('tracking_gate')}"
    elif status != "failed" and r("success") is None:
        verdict = "no gate"
    success = "null" if r("success") is None else str(bool(r("success"))).lower()
    lines.append("-" * 64)
    lines.append(f"  status {status} · success {success} ({verdict})")
    if r("error"):
        lines.append(f"  error: {r('error')}")
    if r("gate_failures"):
        lines.append(f"  gate: {r('gate_failures')}")
    return "\n".join(lines)


def _display_path(path: Path) -> str:
    """The path relative to the working directory when it lies below it."""
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def exit_status(record: dict) -> int:
    """0: succeeded, or finished with no gate to pass (success null); 1: failed; 3: gate not passed."""
    if record.get("status") == "failed":
        return EXIT_FAILED
    if record.get("status") == "ok" and record.get("success") is None:
        return EXIT_SUCCESS
    return EXIT_SUCCESS if record.get("success") else EXIT_GATE


def job_identity(cfg: DictConfig) -> dict:
    """The config choices and overrides that name a job (Hydra's runtime info if present)."""
    identity = {}
    try:
        from hydra.core.hydra_config import HydraConfig

        hc = HydraConfig.get()
        choices = OmegaConf.to_container(hc.runtime.choices)
        identity["overrides"] = " ".join(hc.overrides.task) or None
    except ValueError:  # not running under Hydra
        choices = {}
    for group in ("robot", "controller", "trajectory", "tool", "target", "physics", "task"):
        identity[group] = choices.get(group) or _name(cfg, group)
    return identity


def _name(cfg: DictConfig, group: str):
    node = cfg.get(group)
    return node.get("name") if node is not None else None
