"""The one registry of the metrics a run reports: key, section, label, unit and scale.

``metrics.json`` holds every metric under its ``key`` in SI units (or the unit its name
says: ``_pct``, ``_deg``); the console summary, ``summary.md``, ``comparison.csv`` and
the comparison figures all iterate over :data:`METRICS` and show ``value × scale`` in
``unit``. Adding a metric is one :class:`Metric` here plus the code that computes it.
The docking gate and the tracking gate have their own items (evaluation/docking.py,
evaluation/tracking_gate.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: sections, in the order they are shown
CONTACT, CONTACT_EVENTS, INTERNAL, TRACKING, SEAT, RUN = (
    "contact safety",
    "contact",
    "internal safety",
    "tracking accuracy",
    "seat (true socket pose)",
    "run",
)
SECTIONS = (CONTACT, CONTACT_EVENTS, INTERNAL, TRACKING, SEAT, RUN)
DEG_PER_RAD = 180.0 / math.pi


@dataclass(frozen=True)
class Metric:
    """One reported metric.

    ``key``: its metrics.json key. ``label``: what it is, without the unit. ``unit``: the
    unit it is shown in ("" for a pure number). ``scale``: metrics.json value → shown
    value. ``spec``: format of the shown value in the console. ``joint_key``: for a
    per-joint maximum, the key of its (0-based) joint index, shown 1-based.
    ``compared``: a row of the docking-metrics comparison (summary.md) and bars. ``interval``: a
    metric of the sweep statistics (results/compare.py): per configuration its mean and
    median with bootstrap 95 % intervals, and paired tests between controllers.
    """

    key: str
    section: str
    label: str
    unit: str
    scale: float = 1.0
    spec: str = ".3f"
    joint_key: str | None = None
    compared: bool = True
    interval: bool = False

    @property
    def heading(self) -> str:
        """The label with its unit, as a table row or an axis: ``peak axial force [N]``."""
        return f"{self.label} [{self.unit or '-'}]"

    def shown(self, value) -> float | None:
        """The value in the shown unit (None stays None)."""
        return None if value is None else value * self.scale

    def format(self, record: dict) -> str:
        """The console text of this metric in a run's record (``n/a`` when null)."""
        value = record.get(self.key)
        if value is None:
            return "n/a"
        text = f"{value * self.scale:{self.spec}} {self.unit}".rstrip()
        if self.joint_key is not None and record.get(self.joint_key) is not None:
            text += f" (joint {int(record[self.joint_key]) + 1})"
        return text


METRICS: tuple[Metric, ...] = (
    # contact safety (Ren & Shan 2026, Table 10)
    # the per-step peak is the paper's metric: in a soft-contact simulation an impact's
    # per-step peak scales with the contact time constant (solref), so the docking gate
    # judges the filtered peak, the peak of the mean over task.force_window
    Metric("peak_axial_force_N", CONTACT, "peak axial force (raw, per step)", "N", interval=True),
    Metric("filtered_peak_axial_force_N", CONTACT, "peak axial force (filtered)", "N", interval=True),
    Metric("peak_wrench_norm_N", CONTACT, "peak wrench norm", "N"),
    Metric("steady_axial_force_N", CONTACT, "steady axial force", "N", interval=True),
    Metric("steady_wrench_norm_N", CONTACT, "steady wrench norm", "N"),
    # what the contact did (docking runs; evaluation/contact.py): first contact, the first
    # strike, and how calm the hold is over the steady window
    Metric("first_contact_time_s", CONTACT_EVENTS, "first contact at", "s"),
    Metric("first_strike_force_N", CONTACT_EVENTS, "first strike peak", "N", spec=".2f", interval=True),
    Metric("first_contact_lateral_offset_m", CONTACT_EVENTS, "offset at first contact", "mm", 1e3),
    Metric("first_contact_speed_m_s", CONTACT_EVENTS, "speed at first contact", "mm/s", 1e3, spec=".2f"),
    Metric("steady_force_mean_N", CONTACT_EVENTS, "steady force mean", "N"),
    Metric("steady_force_std_N", CONTACT_EVENTS, "steady force std", "N"),
    Metric("steady_contact_events_per_s", CONTACT_EVENTS, "steady make/break", "events/s", spec=".1f"),
    # internal safety (Ren & Shan 2026, Table 10)
    Metric(
        "max_joint_pos_pct",
        INTERNAL,
        "max joint position use",
        "%",
        spec=".1f",
        joint_key="max_joint_pos_joint",
    ),
    Metric(
        "max_joint_vel_pct", INTERNAL, "max joint speed use", "%", spec=".1f", joint_key="max_joint_vel_joint"
    ),
    Metric("min_manipulability", INTERNAL, "min manipulability", "", spec=".4g"),
    # tracking accuracy (Ren & Shan 2026, Table 10: over the whole run, so a docking run's RMS is mostly the
    # intentional press of the reference past the seat); the motion before the first
    # contact and the press apart, under names that say so
    Metric("pos_tracking_rms_m", TRACKING, "position RMS, whole run", "mm", 1e3),
    Metric("ori_tracking_rms_rad", TRACKING, "orientation RMS, whole run", "deg", DEG_PER_RAD),
    Metric("approach_pos_rms_m", TRACKING, "position RMS before contact", "mm", 1e3, spec=".4f"),
    Metric(
        "approach_ori_rms_rad", TRACKING, "orientation RMS before contact", "deg", DEG_PER_RAD, spec=".4f"
    ),
    Metric("press_depth_m", TRACKING, "press depth", "mm", 1e3),
    Metric("final_lateral_error_m", TRACKING, "final lateral error", "mm", 1e3),
    Metric("final_orientation_error_rad", TRACKING, "final orientation error", "deg", DEG_PER_RAD),
    # where the plug ended up, on the true socket pose (docking runs)
    Metric("seat_depth_error_m", SEAT, "depth error", "mm", 1e3, interval=True),
    Metric("seat_lateral_error_m", SEAT, "lateral error", "mm", 1e3, interval=True),
    Metric("seat_tilt_deg", SEAT, "tilt", "deg", interval=True),
    Metric("seat_key_yaw_deg", SEAT, "key yaw", "deg"),  # keyed interfaces only (else null)
    # docking time: from the first contact on, the first time the tip is within the gate's
    # depth and lateral tolerances of the true seat and stays there to the end of the run
    Metric(
        "docking_time_s", SEAT, "docking time (docked at)", "s", spec=".2f", compared=False, interval=True
    ),
    Metric(
        "docking_time_after_contact_s",
        SEAT,
        "docking time after contact",
        "s",
        spec=".2f",
        compared=False,
        interval=True,
    ),
    # kept for older readers: the first time the tip came within the depth tolerance, even
    # before touching anything (the planner's arrival) and even if it left again
    Metric("seated_time_s", SEAT, "within depth tolerance at", "s", spec=".2f", compared=False),
    # the run
    Metric("sim_time_s", RUN, "simulated", "s", spec=".2f", compared=False),
    Metric("real_time_factor", RUN, "loop speed", "× real time", spec=".1f"),
    Metric("wall_time_s", RUN, "wall time", "s", spec=".2f"),
)

BY_KEY: dict[str, Metric] = {m.key: m for m in METRICS}
#: the research code's docking metrics (DockingMetrics; with the tracking before contact and
#: the press depth, computed with them) and the joint of each per-joint maximum
TABLE10_KEYS: tuple[str, ...] = tuple(m.key for m in METRICS if m.section in (CONTACT, INTERNAL, TRACKING))
DOCKING_KEYS: tuple[str, ...] = TABLE10_KEYS + tuple(
    m.joint_key for m in METRICS if m.section in (CONTACT, INTERNAL, TRACKING) and m.joint_key
)
SEAT_KEYS: tuple[str, ...] = tuple(m.key for m in METRICS if m.section == SEAT)
#: the contact metrics (evaluation/contact.py), docking runs only
CONTACT_KEYS: tuple[str, ...] = tuple(m.key for m in METRICS if m.section == CONTACT_EVENTS)


def in_section(section: str, *, compared_only: bool = False) -> list[Metric]:
    """The metrics of one section, in registry order."""
    return [m for m in METRICS if m.section == section and (m.compared or not compared_only)]


def compared() -> list[Metric]:
    """The metrics of the comparison table (summary.md, comparison.csv), in order."""
    return [m for m in METRICS if m.compared]


def with_intervals() -> list[Metric]:
    """The metrics of the sweep statistics (``interval``), in registry order."""
    return [m for m in METRICS if m.interval]


def finite_or_none(value) -> float | int | None:
    """Python scalar if finite, else None (JSON null)."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    value = float(value)
    return value if np.isfinite(value) else None
