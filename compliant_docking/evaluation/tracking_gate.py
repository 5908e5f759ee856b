"""The free-space tracking gate: may this robot/controller go on to contact work?

Computed after the loop from the run's time series (columns: docs in
:data:`compliant_docking.sim.telemetry.COLUMN_DOCS`: ``t``, ``pos_error`` [m],
``ori_error_x/y/z`` [rad], ``tau1…`` [N·m], ``torque_saturated``, ``contacts``) and the
planner's named segments ``(name, t_start, t_end)``.

Statistics (docs/control_laws.md §5; seed ``compute_tracking_metrics``):

- per segment, over t ∈ [t_start, t_end): position error RMS and peak [m], orientation
  error (‖log3(R_ref Rᵀ)‖) RMS and peak [rad];
- overall, over the planned motion [first start, last end) (the hold after it is not
  part of the test): the same four, the peak |joint torque| [N·m] and the share of steps
  whose command hit the torque clip;
- max contacts: over the WHOLE run (free space means no contact at any time).

Gate (:class:`~compliant_docking.config.TrackingThresholds`): circle and figure-8
position RMS, overall position peak, overall orientation RMS, saturation ratio, max
contacts, each ≤ its threshold. Verdict: ``PASS``; ``FAIL`` listing every failing item;
``INCOMPLETE`` when the run is shorter than the trajectory (nothing else judged). A
missing segment, an empty window or a non-finite value (NaN/inf) anywhere in the
statistics fails (fail closed), even for a statistic without a threshold.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from compliant_docking.sim.telemetry import ORI_ERROR

PASS, FAIL, INCOMPLETE = "PASS", "FAIL", "INCOMPLETE"
#: segments the thresholds name (threshold field → segment name)
GATED_SEGMENTS = {"circle_position_rms_m": "circle", "figure8_position_rms_m": "figure8"}
#: fields of a threshold object the gate reads
THRESHOLD_FIELDS = (
    "circle_position_rms_m",
    "figure8_position_rms_m",
    "position_peak_m",
    "orientation_rms_rad",
    "torque_saturation_ratio",
    "max_contacts",
)


@dataclass(frozen=True)
class ErrorStats:
    """Position [m] and orientation [rad] error RMS and peak over a window (None: no data)."""

    position_rms_m: float | None = None
    position_peak_m: float | None = None
    orientation_rms_rad: float | None = None
    orientation_peak_rad: float | None = None


@dataclass(frozen=True)
class TrackingMetrics:
    segments: tuple[tuple[str, ErrorStats], ...] = ()
    overall: ErrorStats = field(default_factory=ErrorStats)
    peak_joint_torque_Nm: float | None = None  # over the planned motion
    torque_saturation_ratio: float | None = None  # over the planned motion, in [0, 1]
    max_contacts: int | float | None = None  # over the whole run

    def segment(self, name: str) -> ErrorStats | None:
        return next((stats for seg, stats in self.segments if seg == name), None)


@dataclass(frozen=True)
class TrackingGateResult:
    metrics: TrackingMetrics
    status: str  # PASS | FAIL | INCOMPLETE
    failures: tuple[str, ...] = ()

    @property
    def success(self) -> bool:
        return self.status == PASS

    def record(self) -> dict:
        """Flat ``metrics.json`` fields: ``tracking_gate`` (the verdict),
        ``tracking_<segment>_{pos,ori}_{rms,peak}_{m,rad}``, ``tracking_{pos,ori}_…`` overall,
        ``tracking_peak_torque_Nm``, ``tracking_saturation_ratio``, ``tracking_contacts_max``.
        Non-finite numbers stay as they are here; ``write_metrics`` turns them into null."""
        out: dict = {"tracking_gate": self.status}
        for name, stats in self.metrics.segments:
            out.update(_stats_fields(f"tracking_{name}_", stats))
        out.update(_stats_fields("tracking_", self.metrics.overall))
        out["tracking_peak_torque_Nm"] = self.metrics.peak_joint_torque_Nm
        out["tracking_saturation_ratio"] = self.metrics.torque_saturation_ratio
        out["tracking_contacts_max"] = self.metrics.max_contacts
        out["tracking_segments"] = ",".join(name for name, _ in self.metrics.segments) or None
        return out


def _stats_fields(prefix: str, stats: ErrorStats) -> dict:
    return {
        f"{prefix}pos_rms_m": stats.position_rms_m,
        f"{prefix}pos_peak_m": stats.position_peak_m,
        f"{prefix}ori_rms_rad": stats.orientation_rms_rad,
        f"{prefix}ori_peak_rad": stats.orientation_peak_rad,
    }


def _error_stats(pos: np.ndarray, ori: np.ndarray, mask: np.ndarray) -> ErrorStats:
    if not mask.any():
        return ErrorStats()
    p, o = pos[mask], ori[mask]
    # plain float arithmetic: NaN/inf propagate into the statistics (and fail the gate)
    return ErrorStats(
        float(np.sqrt(np.mean(p * p))), float(np.max(p)), float(np.sqrt(np.mean(o * o))), float(np.max(o))
    )


def compute_tracking_metrics(
    ts: pd.DataFrame, segments: Sequence[tuple[str, float, float]]
) -> TrackingMetrics:
    """Tracking statistics of a run's time series over the planner's segments (module doc)."""
    t = ts["t"].to_numpy(dtype=float)
    pos = ts["pos_error"].to_numpy(dtype=float)
    ori = np.linalg.norm(ts[ORI_ERROR].to_numpy(dtype=float), axis=1)
    seg_stats = tuple((name, _error_stats(pos, ori, (t >= t0) & (t < t1))) for name, t0, t1 in segments)
    max_contacts = None
    if "contacts" in ts and len(ts):
        contacts = ts["contacts"].to_numpy(dtype=float)
        max_contacts = float(np.max(contacts))
        if math.isfinite(max_contacts) and max_contacts == int(max_contacts):
            max_contacts = int(max_contacts)
    if not segments:
        return TrackingMetrics(seg_stats, ErrorStats(), None, None, max_contacts)
    window = (t >= min(s[1] for s in segments)) & (t < max(s[2] for s in segments))
    overall = _error_stats(pos, ori, window)
    tau_cols = [c for c in ts.columns if c.startswith("tau") and c[3:].isdigit()]
    peak_torque = saturation = None
    if window.any():
        if tau_cols:
            peak_torque = float(np.max(np.abs(ts.loc[window, tau_cols].to_numpy(dtype=float))))
        if "torque_saturated" in ts:
            saturation = float(np.mean(ts.loc[window, "torque_saturated"].to_numpy(dtype=float)))
    return TrackingMetrics(seg_stats, overall, peak_torque, saturation, max_contacts)


def _finite(value) -> bool:
    try:
        return value is not None and math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


def evaluate_tracking_gate(metrics: TrackingMetrics, thresholds, *, complete: bool) -> TrackingGateResult:
    """PASS / FAIL (every failing item) / INCOMPLETE (``complete`` false: nothing judged).

    ``thresholds``: a :class:`~compliant_docking.config.TrackingThresholds` or any object
    (a DictConfig) with the same fields.
    """
    if not complete:
        return TrackingGateResult(metrics, INCOMPLETE)
    failures: list[str] = []
    limits = {}
    for name in THRESHOLD_FIELDS:
        value = getattr(thresholds, name)
        if not _finite(value):
            failures.append(f"threshold {name} = {value!r} is not a finite number")
        limits[name] = value

    # Fail closed: a non-finite statistic fails even where no threshold reads it.
    def nonfinite(label: str, value) -> None:
        if value is not None and not _finite(value):
            failures.append(f"{label} is not finite ({value})")

    gated = set(GATED_SEGMENTS.values())
    for name, stats in metrics.segments:
        for attr, value in vars(stats).items():
            if not (name in gated and attr == "position_rms_m"):  # judged below
                nonfinite(f"{name} {attr}", value)
    for attr, value in vars(metrics.overall).items():
        if attr not in ("position_peak_m", "orientation_rms_rad"):  # judged below
            nonfinite(f"overall {attr}", value)
    nonfinite("peak joint torque", metrics.peak_joint_torque_Nm)

    def at_most(label: str, value, limit_name: str, scale: float, unit: str) -> None:
        limit = limits[limit_name]
        if value is None:
            failures.append(f"{label} not available (no data)")
        elif not _finite(value):
            failures.append(f"{label} is not finite ({value})")
        elif _finite(limit) and value > limit:
            unit_ = f" {unit}" if unit else ""
            failures.append(f"{label} {value * scale:.4g}{unit_} > {limit * scale:.4g}{unit_}")

    for limit_name, segment in GATED_SEGMENTS.items():
        segment_stats = metrics.segment(segment)
        at_most(
            f"{segment} position RMS",
            None if segment_stats is None else segment_stats.position_rms_m,
            limit_name,
            1e3,
            "mm",
        )
    at_most("overall position peak", metrics.overall.position_peak_m, "position_peak_m", 1e3, "mm")
    at_most(
        "overall orientation RMS",
        metrics.overall.orientation_rms_rad,
        "orientation_rms_rad",
        180.0 / math.pi,
        "deg",
    )
    at_most("torque saturation ratio", metrics.torque_saturation_ratio, "torque_saturation_ratio", 100.0, "%")
    at_most("max contacts", metrics.max_contacts, "max_contacts", 1.0, "")
    return TrackingGateResult(metrics, FAIL if failures else PASS, tuple(failures))


def tracking_gate(
    ts: pd.DataFrame, segments: Sequence[tuple[str, float, float]], thresholds, *, complete: bool
) -> TrackingGateResult:
    """:func:`compute_tracking_metrics` then :func:`evaluate_tracking_gate`."""
    return evaluate_tracking_gate(compute_tracking_metrics(ts, segments), thresholds, complete=complete)


# --------------------------------------------------------------------------- printing
def _fmt(value, scale: float, unit: str, spec: str = ".3f") -> str:
    if value is None or not _finite(value):
        return "n/a"
    return f"{float(value) * scale:{spec}} {unit}"


def summary_rows(record: dict) -> list[tuple[str, str | None]]:
    """Rows ``(label, value)`` for the console summary, from a metrics record holding
    :meth:`TrackingGateResult.record` fields (``(label, None)`` is a heading)."""
    r = record.get
    names = (r("tracking_segments") or "").split(",")
    rows: list[tuple[str, str | None]] = [(f"[tracking gate: {r('tracking_gate')}]", None)]
    for prefix, label in [(f"tracking_{n}_", n) for n in names if n] + [("tracking_", "overall")]:
        rows.append(
            (
                label,
                f"pos RMS {_fmt(r(prefix + 'pos_rms_m'), 1e3, 'mm')}, "
                f"peak {_fmt(r(prefix + 'pos_peak_m'), 1e3, 'mm')}; "
                f"ori RMS {_fmt(r(prefix + 'ori_rms_rad'), 180 / math.pi, 'deg')}, "
                f"peak {_fmt(r(prefix + 'ori_peak_rad'), 180 / math.pi, 'deg')}",
            )
        )
    contacts = r("tracking_contacts_max")
    rows += [
        ("peak joint torque", _fmt(r("tracking_peak_torque_Nm"), 1.0, "N·m", ".2f")),
        ("torque saturation", _fmt(r("tracking_saturation_ratio"), 100.0, "%", ".2f")),
        ("max contacts", "n/a" if contacts is None else f"{contacts}"),
    ]
    return rows


def format_tracking_gate(result: TrackingGateResult) -> str:
    """A standalone, auditable text block of a gate result."""
    record = result.record()
    rows = summary_rows(record)
    width = max(len(label) for label, value in rows if value is not None)
    lines = ["=" * 64, f"free-space tracking gate: {result.status}", "=" * 64]
    lines += [f"  {label:<{width}} : {value}" for label, value in rows[1:]]
    if result.status == INCOMPLETE:
        lines.append("  result: INCOMPLETE (the run is shorter than the trajectory; not judged)")
    elif result.failures:
        lines.append("  failing: " + "; ".join(result.failures))
    else:
        lines.append("  result: PASS (ready for compliant contact tests)")
    return "\n".join(lines)
