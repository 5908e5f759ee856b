"""One job, from a composed config to a finished run directory.

Whatever happens, :func:`execute` ends the run directory with a ``metrics.json`` whose
``status`` is "ok", "incomplete" (shorter than its trajectory), "failed" (with ``error``:
a one-line reason) or "interrupted" (Ctrl-C, SIGTERM, SIGHUP: the time series so far is kept,
and the interruption is raised again once the record is written). Every file is written atomically
(temporary name, then rename), and ``metrics.json`` last, so a directory holding a
``metrics.json`` is finished. See docs/run_directory.md for the layout.
"""

from __future__ import annotations

import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import DictConfig, OmegaConf

from compliant_docking import exit_codes
from compliant_docking.evaluation.registry import CONTACT_KEYS, DOCKING_KEYS
from compliant_docking.run import figures as run_figures
from compliant_docking.run import interrupt, provenance, rundir
from compliant_docking.run.summary import display_path, format_summary
from compliant_docking.sim import dynamics, model_error, sensor
from compliant_docking.sim.misalignment import record_for as misalignment_record

#: exit status of ``python -m compliant_docking`` (the table: compliant_docking/exit_codes.py)
EXIT_SUCCESS, EXIT_FAILED, EXIT_GATE = exit_codes.OK, exit_codes.FAILED, exit_codes.NOT_DOCKED


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().replace("\n", " ") or type(exc).__name__
    return text if isinstance(exc, (ValueError, RuntimeError)) else f"{type(exc).__name__}: {text}"


@dataclass
class Episode:
    """A simulation stepped elsewhere (a Gymnasium episode, compliant_docking/env/), for
    :func:`execute` to record instead of simulating: ``simulation`` (prepared from the
    config given to execute and run as far as it went), ``error`` (the :class:`Diverged`
    that ended it, or None), ``overrides`` (the job's overrides, written to
    ``.hydra/overrides.yaml`` with the config), ``fields`` (more record fields, given
    the record so far: an episode's return counts the gate's bonus) and
    ``mujoco_warnings`` (MuJoCo's warnings while it was stepped: ``sim.mjlog.captured``)."""

    simulation: Any
    error: Exception | None = None
    overrides: list[str] = field(default_factory=list)
    fields: Callable[[dict], dict[str, Any]] | None = None
    mujoco_warnings: list[str] = field(default_factory=list)


def execute(
    cfg: DictConfig,
    out_dir: Path,
    *,
    figures: bool | None = None,
    echo: bool = True,
    episode: Episode | None = None,
) -> dict:
    """Run the job of ``cfg`` into ``out_dir``; returns the metrics record.

    The record starts with the fields naming the job (config choices, overrides). A
    failure of any kind is recorded (status "failed" and the reason), never raised. An
    interruption (Ctrl-C, SIGTERM, SIGHUP: a KeyboardInterrupt, :mod:`.interrupt`) is
    recorded as status "interrupted" with the time series simulated so far, then raised
    again so the caller stops; one that came while the command held the signals (between
    the claim of the run directory and this call) is acted on first thing here, so the
    directory gets its record. ``figures``: draw the per-run figures; None: as the config's
    ``figures`` says for a single run (:func:`compliant_docking.run.figures.wanted`).
    ``episode``: record that simulation instead of simulating ``cfg`` (then ``.hydra/`` is
    written here, as Hydra writes it for a run).
    """
    from compliant_docking.config.validate import validate
    from compliant_docking.sim import mjlog
    from compliant_docking.sim.settings import sim_settings
    from compliant_docking.sim.simulate import Diverged, prepare

    if figures is None:
        figures = run_figures.wanted(cfg, sweep=False)
    started = time.perf_counter()
    started_at = provenance.now_iso()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    record: dict = {"status": "failed", "error": None, "success": False, **job_identity(cfg)}
    if episode is not None:
        rundir.write_hydra_files(out_dir, cfg, episode.overrides)
        record["overrides"] = " ".join(episode.overrides) or None
    record.update(dict.fromkeys(DOCKING_KEYS))
    record.update(dict.fromkeys(CONTACT_KEYS), gate_verdict=None)
    try:  # the simulation's typed settings, made once for the records and the simulation
        settings = sim_settings(cfg)
    except Exception:
        settings = None  # null records; the run fails below with the reason
    record.update(misalignment_record(settings))  # true vs believed socket pose (flat keys)
    # what the controller does not know: its model, its sensors; the plant's contact draw
    record.update(
        model_error.record_for(settings), **sensor.record_for(settings), **dynamics.record_for(settings)
    )
    sim = None
    interrupted: KeyboardInterrupt | None = None
    with mjlog.captured() as mujoco_warnings:  # never MUJOCO_LOG.TXT in the working directory
        if episode is not None:
            mujoco_warnings.extend(episode.mujoco_warnings)
        try:
            interrupt.release()  # a signal held since the run directory was claimed: recorded below
            validate(cfg)  # the command line did already; a run from Python gets the same checks
            show: Any = None
            if cfg.get("viewer"):  # MuJoCo's viewer at real time; refused in a sweep or without a display
                from compliant_docking.viz import viewer as show

                show.check_allowed()
            if episode is None:
                sim = prepare(cfg, settings)
                sim.run(
                    progress=bool(cfg.task.progress) and echo,
                    on_step=show.RealTimeViewer(sim) if show else None,
                )
            else:
                sim = episode.simulation
                if episode.error is not None:
                    raise episode.error
            record.update(evaluate(sim, out_dir, figures=figures))
        except Diverged as exc:
            record["error"] = str(exc)
        except Exception as exc:  # a job records its own failure; the sweep goes on
            record["error"] = _one_line(exc)
            if not isinstance(exc, ValueError):
                traceback.print_exc(file=sys.stderr)
        except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM: record what there is, then stop
            interrupted = exc
    with interrupt.deferred() as pending:  # a (second) Ctrl-C must not cut the record short
        if interrupted is not None:
            record.update(_interrupted(sim, out_dir, interrupted))
        if sim is not None:
            steps = sim.telemetry.count
            record["sim_time_s"] = steps * sim.scene.model.opt.timestep
            # the model error's keys again, with the believed − true tool mass
            record.update(model_error.record_for(sim.settings, sim.scene.arm.tool.mass))
            record["steps"] = steps
            record["real_time_factor"] = (
                record["sim_time_s"] / sim.loop_wall_time if sim.loop_wall_time > 0 else None
            )
            record["loop_wall_time_s"] = sim.loop_wall_time or None
            record.update(sim.controller.diagnostics())
            if sim.lead is not None:
                dt = sim.scene.model.opt.timestep
                record.update(sim.lead.diagnostics(dt))
                # the run extended by the held time (task.max_hold caps it)
                record["run_extended_s"] = max(steps - sim.planned_steps, 0) * dt
                record["run_extension_capped"] = sim.extension_capped
                if sim.extension_capped:
                    short = (sim.planned_steps + sim.lead.held_steps - sim.n_steps) * dt
                    record["run_notes"] = (
                        f"the reference was held {sim.lead.held_steps * dt:.3f} s, longer than "
                        f"task.max_hold = {cfg.task.max_hold:g} s extends the run: the settle time "
                        f"after the planner's end is {short:.3f} s shorter than task.settle_time"
                    )
        if episode is not None and episode.fields is not None:
            record.update(episode.fields(record))
        if interrupted is None and cfg.get("render") is not None and cfg.render.name != "none":
            from compliant_docking.viz.render import record_video

            record.update(record_video(sim, cfg, out_dir))  # never raises: video_error says why
        record["mujoco_warnings"] = len(mujoco_warnings)
        if mujoco_warnings:
            rundir.write_mujoco_log(out_dir, mujoco_warnings)
        record["wall_time_s"] = time.perf_counter() - started
        record.update(provenance.collect(cfg, started_at=started_at))  # versions, git, config hash
        record = rundir.consistent(record)  # a job that did not finish never counts as docked
        summary = format_summary(record, cfg) + f"\n  run directory: {display_path(out_dir)}"
        if record.get("run_notes"):  # a held reference cut the settle time short
            summary += f"\n  note: {record['run_notes']}"
        if "video_error" in record:  # render=video: the video, or why there is none
            from compliant_docking.viz.render import summary_line

            summary += summary_line(record)
        rundir.write_summary_text(out_dir, summary)
        rundir.write_metrics(out_dir, record)  # last: its presence means "finished"
    if echo:
        print(summary)
    if interrupted is not None:
        raise interrupted
    if pending:  # a signal while the record was written: the run is recorded, now stop
        raise interrupt.Stopped(pending[0])
    return record


def _interrupted(sim, out_dir: Path, exc: KeyboardInterrupt) -> dict:
    """The record's fields for a run stopped by ``exc``: status "interrupted", the reason,
    and the metrics and time series of the steps simulated so far."""
    how = interrupt.name(interrupt.signum_of(exc))
    fields: dict[str, Any] = {}
    when = " before the simulation started"
    if sim is not None and sim.telemetry.count:
        dt = sim.scene.model.opt.timestep
        when = f" at t = {sim.telemetry.count * dt:.3f} s of {sim.n_steps * dt:.3f} s"
        try:
            fields = evaluate(sim, out_dir, figures=False)  # the partial time series, no figures
        except Exception as error:
            when += f" (the metrics of the partial run could not be computed: {_one_line(error)})"
    fields.update(status="interrupted", success=False, gate_failures=None, gate_verdict=None)
    return {**fields, "error": f"interrupted by {how}{when}"}


def evaluate(sim, out_dir: Path | None, *, figures: bool) -> dict:
    """Metrics, gate, time series and figures of a finished simulation (the record's
    fields they fill); writes the time series and the figures into ``out_dir`` (None:
    nothing is written, e.g. an episode's metrics for its ``info``)."""
    from compliant_docking.evaluation import docking as M
    from compliant_docking.evaluation.contact import contact_metrics

    cfg, arm = sim.cfg, sim.scene.arm
    extras = sim.controller.timeseries()
    if sim.sensing is not None:  # the controller's F/T reading beside the exact wrench
        extras = {**extras, **sim.sensing.timeseries(sim.telemetry.count)}
    ts = sim.telemetry.frame(arm, sim.reference, np.asarray(cfg.robot.max_torque, float), extras)
    manip = M.manipulability_series(arm, sim.telemetry.q[: sim.telemetry.count])
    axis = sim.waypoints.axis
    docking = M.compute_metrics(
        ts,
        axis=axis,
        q_lower=arm.q_lower,
        q_upper=arm.q_upper,
        velocity_limits=np.asarray(cfg.robot.velocity_limits, float),
        manipulability=manip,
        steady_window=float(cfg.task.steady_window),
        force_window=float(cfg.task.force_window),
    )
    result: dict[str, Any] = dict(docking)
    result["contacts_max"] = int(ts["contacts"].max()) if len(ts) else None
    result["torque_saturation_ratio"] = float(ts["torque_saturated"].mean()) if len(ts) else None

    # The gate: docking runs → the docking gate; free-space runs of the tracking planner →
    # the tracking gate; other free-space runs (hold, …) have no gate: success is null.
    from compliant_docking.planning.tracking import TrackingPlanner

    failures: list[str] = []
    gated = True
    complete = sim.complete
    seat = None
    if sim.scene.socket is not None:
        key = sim.scene.key
        seat = M.seat_state(
            ts,
            sim.scene.socket.true,
            float(cfg.task.steady_window),
            float(cfg.task.gate.depth_tolerance_m),
            key,
            lateral_tolerance=float(cfg.task.gate.lateral_tolerance_m),
        )
        result.update(
            seat_depth_error_m=seat.depth_error_m,
            seat_lateral_error_m=seat.lateral_error_m,
            seat_tilt_deg=seat.tilt_deg,
            seat_key_yaw_deg=seat.key_yaw_deg,
            seated_time_s=seat.seated_time_s,
            docking_time_s=seat.docking_time_s,
            docking_time_after_contact_s=seat.docking_time_after_contact_s,
            key_symmetry=key.symmetry,
            key_yaw_play_deg=key.yaw_play_deg,
        )
        contact = contact_metrics(
            ts,
            sim.scene.socket.true,
            steady_window=float(cfg.task.steady_window),
            strike_window=float(cfg.task.strike_window),
        )
        result.update(contact)
        failures = M.docking_gate(
            seat, docking, cfg.task.gate, M.key_yaw_limit(cfg.task.gate, key), contact=contact
        )
    elif isinstance(sim.planner, TrackingPlanner):
        from compliant_docking.evaluation.tracking_gate import tracking_gate

        gate = tracking_gate(ts, sim.planner.segments, cfg.task.tracking_gate, complete=complete)
        result.update(gate.record())
        failures = list(gate.failures)
    else:
        gated = False
    if not complete:
        failures = sim.notes + failures
    if seat is not None:  # docking runs, one line: "docked", "seated; …" or "not docked: …"
        result["gate_verdict"] = M.docking_verdict(seat, cfg.task.gate, failures)
    result["status"] = "ok" if complete else "incomplete"
    result["success"] = (complete and not failures) if gated else None
    result["gate_failures"] = "; ".join(failures) or None

    if out_dir is None:
        return result
    saved = rundir.saved_timeseries(ts, cfg.output)
    result["timeseries_rows"] = None if saved is None else len(saved)
    if saved is not None:
        rundir.write_timeseries(out_dir, saved)
    if figures:
        run_figures.draw(
            out_dir,
            ts,
            axis=axis,
            torque_limits=np.asarray(cfg.robot.max_torque, float),
            title=f"{cfg.robot.name} · {cfg.controller.name} · {cfg.trajectory.name}",
            marks=run_figures.marks(cfg, result),
        )
    return result


def exit_status(record: dict) -> int:
    """0: succeeded, or finished with no gate to pass (success null); 1: failed or
    interrupted; 3: gate not passed."""
    if record.get("status") in rundir.FAILED_STATUSES:
        return EXIT_FAILED
    if record.get("status") == "ok" and record.get("success") is None:
        return EXIT_SUCCESS
    return EXIT_SUCCESS if record.get("success") else EXIT_GATE


def job_identity(cfg: DictConfig) -> dict:
    """The config choices and overrides that name a job (Hydra's runtime info if present)."""
    identity: dict[str, Any] = {}
    try:
        from hydra.core.hydra_config import HydraConfig

        hc = HydraConfig.get()
        choices: Any = OmegaConf.to_container(hc.runtime.choices)
        identity["overrides"] = " ".join(hc.overrides.task) or None
    except ValueError:  # not running under Hydra
        choices = {}
    for group in rundir.IDENTITY_GROUPS:
        identity[group] = choices.get(group) or _name(cfg, group)
    return identity


def _name(cfg: DictConfig, group: str):
    node = cfg.get(group)
    return node.get("name") if node is not None else None
