"""Mutation score of the tests: introduce one deliberate bug at a time into the metrics,
the gates, the sensor chain, the control laws and the provenance, and see whether the
tests that guard that code fail.

Each mutation is a text replacement in one source file (it must match exactly once).
The code under test is a copy of the checkout in a temporary directory (the checkout is
never touched); each mutation is applied to the copy, the listed test files run there
with ``pytest -x`` (stop at the first failure), and the file is restored. A mutation is
*killed* when pytest reports a failing test, *survived* when every test passes.

    python benchmarks/mutation_score.py                 # every mutation, a Markdown table
    python benchmarks/mutation_score.py --only M1 G5    # some of them
    python benchmarks/mutation_score.py --list          # what each one does
    python benchmarks/mutation_score.py --ref main      # the tests and code of a commit

``--ref`` takes the tree of a commit instead of the working tree (mutations whose text
is not in that tree are reported as n/a). Run from the repository root with the
project's interpreter (``.venv/bin/python``); it takes about 15 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

DOCKING = "compliant_docking/evaluation/docking.py"
CONTACT = "compliant_docking/evaluation/contact.py"
TRACKING = "compliant_docking/evaluation/tracking_gate.py"
SENSOR = "compliant_docking/sim/sensor.py"
IMPEDANCE = "compliant_docking/control/impedance.py"
SE3_LIE = "compliant_docking/control/se3_lie.py"
HQP_KERNEL = "compliant_docking/control/hqp/kernel.py"
SE3_KERNEL = "compliant_docking/control/se3_kernel.py"
KERNEL_BLOCKS = "compliant_docking/control/kernel_blocks.py"
BASE = "compliant_docking/control/base.py"
SHAPING = "compliant_docking/control/shaping.py"
INTEGRAL = "compliant_docking/control/integral.py"
PROVENANCE = "compliant_docking/run/provenance.py"
RUNNER = "compliant_docking/run/runner.py"
EXIT_CODES = "compliant_docking/exit_codes.py"
TABLES = "compliant_docking/results/tables.py"
MISALIGNMENT = "compliant_docking/sim/misalignment.py"
VALIDATE = "compliant_docking/config/validate.py"
SCHEMAS = "compliant_docking/config/schemas.py"
BOUNDARIES = "compliant_docking/evaluation/map_boundaries.py"
LEAD = "compliant_docking/planning/lead.py"
TASK_CONF = "conf/task/docking.yaml"

METRIC_TESTS = ("tests/evaluation/test_docking.py", "tests/run/test_runner.py")
GATE_TESTS = (
    "tests/evaluation/test_docking.py",
    "tests/evaluation/test_contact.py",
    "tests/run/test_runner.py",
)
CONTACT_TESTS = ("tests/evaluation/test_contact.py",)
FILTERED_TESTS = ("tests/evaluation/test_filtered_peak.py", "tests/evaluation/test_docking.py")
FILTERED_RUN_TESTS = ("tests/sim/test_misalignment.py",)
MISALIGNMENT_TESTS = ("tests/sim/test_misalignment.py",)
MISALIGNMENT_RULE_TESTS = ("tests/sim/test_misalignment.py", "tests/config/test_validate.py")
DOCKING_TIME_TESTS = ("tests/evaluation/test_docking_time.py", "tests/evaluation/test_docking.py")
BOUNDARY_TESTS = ("tests/evaluation/test_map_boundaries.py",)
LEAD_TESTS = ("tests/planning/test_lead.py",)
HQP_KERNEL_TESTS = ("tests/control/test_hqp_kernel.py",)
SE3_KERNEL_TESTS = ("tests/control/test_se3_kernel.py",)
YIELD_TESTS = ("tests/control/test_base.py", "tests/control/test_friction_push.py")
TRACKING_TESTS = ("tests/evaluation/test_tracking_gate.py",)
SENSOR_TESTS = ("tests/sim/test_sensor.py", "tests/control/test_impedance.py")
LAW_TESTS = (
    "tests/control/test_transients.py",
    "tests/control/test_impedance.py",
    "tests/control/test_base.py",
    "tests/control/test_se3_lie.py",
    "tests/control/test_hqp.py",
    "tests/sim/test_robots.py",
)
PROVENANCE_TESTS = ("tests/run/test_provenance.py",)
RESULTS_TESTS = ("tests/results/test_load.py",)


@dataclass(frozen=True)
class Mutation:
    key: str
    path: str
    old: str
    new: str
    what: str
    tests: tuple[str, ...]


MUTATIONS = (
    # ---------------------------------------------------------------- docking metrics
    Mutation(
        "M1",
        DOCKING,
        "np.min(manipulability)",
        "np.max(manipulability)",
        "maximum instead of minimum manipulability",
        METRIC_TESTS,
    ),
    Mutation(
        "M2",
        DOCKING,
        "_max_pct(np.abs(v), np.asarray(velocity_limits, dtype=float))",
        "_max_pct(np.abs(v), 2.0 * np.asarray(velocity_limits, dtype=float))",
        "velocity % against twice the limit",
        METRIC_TESTS,
    ),
    Mutation(
        "M3",
        DOCKING,
        "lateral = pos_err - np.outer(pos_err @ axis, axis)",
        "lateral = pos_err",
        "lateral error not projected off the axis",
        METRIC_TESTS,
    ),
    Mutation(
        "M4",
        DOCKING,
        "final_orientation_error_rad=np.mean(ori_norm[steady])",
        "final_orientation_error_rad=np.mean(ori_norm)",
        "final orientation error over the whole run",
        METRIC_TESTS,
    ),
    Mutation(
        "M5",
        DOCKING,
        'np.sqrt(np.mean(ts["pos_error"].to_numpy() ** 2))',
        'np.mean(ts["pos_error"].to_numpy())',
        "position RMS replaced by the mean",
        METRIC_TESTS,
    ),
    Mutation(
        "M6",
        DOCKING,
        "np.sqrt(np.mean(ori_norm**2))",
        "np.mean(ori_norm)",
        "orientation RMS replaced by the mean",
        METRIC_TESTS,
    ),
    Mutation(
        "M7",
        DOCKING,
        "steady_axial_force_N=np.mean(axial[steady])",
        "steady_axial_force_N=np.mean(axial)",
        "steady axial force over the whole run",
        METRIC_TESTS,
    ),
    Mutation(
        "M8",
        DOCKING,
        "np.max(np.abs(axial))",
        "np.max(axial)",
        "peak axial force ignores pulls",
        METRIC_TESTS,
    ),
    Mutation(
        "M9",
        DOCKING,
        "wrench_norm = np.linalg.norm(ts[WRENCH]",
        "wrench_norm = np.linalg.norm(ts[FORCE]",
        "wrench norm of the force alone",
        METRIC_TESTS,
    ),
    Mutation(
        "M10",
        DOCKING,
        "half_range = (upper - lower) / 2",
        "half_range = upper - lower",
        "joint position use against the full range",
        METRIC_TESTS,
    ),
    Mutation(
        "M11",
        DOCKING,
        "    axis = axis / np.linalg.norm(axis)\n    t = ",
        "    t = ",
        "docking axis not normalised",
        METRIC_TESTS,
    ),
    Mutation(
        "M12",
        DOCKING,
        "return t >= t[-1] - window",
        "return t <= t[0] + window",
        "steady window at the start of the run",
        METRIC_TESTS,
    ),
    Mutation(
        "M13",
        DOCKING,
        "(ts[POSITION].to_numpy() - seat.translation) @ seat.rotation",
        "(ts[POSITION].to_numpy() - seat.translation)",
        "seat offsets not in the seat frame",
        METRIC_TESTS,
    ),
    Mutation(
        "M14",
        DOCKING,
        "cos_tilt = np.clip(-(plug_axis",
        "cos_tilt = np.clip((plug_axis",
        "tilt measured against the wrong end of the axis",
        METRIC_TESTS,
    ),
    Mutation(
        "M15",
        DOCKING,
        "depth_error_m=finite_or_none(depth[steady].max())",
        "depth_error_m=finite_or_none(depth[steady].mean())",
        "seat depth: mean instead of the maximum",
        METRIC_TESTS,
    ),
    Mutation(
        "M16",
        DOCKING,
        "float(t[seated[0]])",
        "float(t[seated[-1]])",
        "seated time: the last instead of the first",
        METRIC_TESTS,
    ),
    Mutation(
        "M17",
        DOCKING,
        "return np.sqrt(np.maximum(np.linalg.det(gram), 0.0)) if len(q)",
        "return np.maximum(np.linalg.det(gram), 0.0) if len(q)",
        "manipulability without the square root",
        METRIC_TESTS,
    ),
    # ---------------------------------------------------------------- docking gate
    Mutation(
        "G1",
        DOCKING,
        "            gate.peak_force_budget_N,\n",
        "            np.inf,\n",
        "peak-force check removed",
        GATE_TESTS,
    ),
    Mutation(
        "G2",
        DOCKING,
        "            gate.tilt_tolerance_deg,\n",
        "            np.inf,\n",
        "tilt check removed",
        GATE_TESTS,
    ),
    Mutation(
        "G3",
        DOCKING,
        "        elif value > limit:",
        "        elif value > 3 * limit:",
        "every tolerance × 3",
        GATE_TESTS,
    ),
    Mutation(
        "G4",
        DOCKING,
        "            gate.depth_tolerance_m,\n",
        "            np.inf,\n",
        "depth check removed",
        GATE_TESTS,
    ),
    Mutation(
        "G5",
        DOCKING,
        "            gate.lateral_tolerance_m,\n",
        "            np.inf,\n",
        "lateral check removed",
        GATE_TESTS,
    ),
    Mutation(
        "G6",
        DOCKING,
        "        elif value > limit:",
        "        elif value >= limit:",
        "a value at the tolerance fails",
        GATE_TESTS,
    ),
    Mutation(
        "G7",
        DOCKING,
        "if value is None or not np.isfinite(value):",
        "if value is None:",
        "a NaN passes the gate",
        GATE_TESTS,
    ),
    Mutation(
        "G8",
        DOCKING,
        "        elif seat.key_yaw_deg > key_yaw_limit_deg:",
        "        elif seat.key_yaw_deg > 3 * key_yaw_limit_deg:",
        "key-yaw tolerance × 3",
        GATE_TESTS,
    ),
    Mutation(
        "G9",
        DOCKING,
        "                gate.max_contact_events_per_s,\n",
        "                np.inf,\n",
        "contact-chatter check removed",
        GATE_TESTS,
    ),
    Mutation(
        "G10",
        DOCKING,
        "max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean)",
        "max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean) * 3",
        "force-spread limit × 3",
        GATE_TESTS,
    ),
    Mutation(
        "G11",
        DOCKING,
        "max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean)",
        "min(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean)",
        "force-spread limit: the smaller of the floor and the ratio",
        GATE_TESTS,
    ),
    Mutation(
        "G12",
        DOCKING,
        "max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean)",
        "float(gate.max_force_std_ratio) * mean",
        "force-spread limit without its absolute floor",
        GATE_TESTS,
    ),
    Mutation(
        "G13",
        DOCKING,
        "max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean)",
        "float(gate.max_force_std_N)",
        "force-spread limit without its share of the mean",
        GATE_TESTS,
    ),
    Mutation(
        "G14",
        DOCKING,
        'contact["steady_force_std_N"] if mean is not None else None',
        'contact["steady_force_std_N"]',
        "force spread judged although its mean is missing",
        GATE_TESTS,
    ),
    # ---------------------------------------------------------------- filtered peak force
    Mutation(
        "F1",
        DOCKING,
        "int(round(window / dt))",
        "int(window / dt)",
        "filtered peak: the window's rows floored, not rounded",
        FILTERED_TESTS,
    ),
    Mutation(
        "F2",
        DOCKING,
        "int(round(window / dt))",
        "int(np.ceil(window / dt))",
        "filtered peak: the window's rows rounded up",
        FILTERED_TESTS,
    ),
    Mutation(
        "F3",
        DOCKING,
        "min(max(int(round(window / dt)), 1), force.size)",
        "min(int(round(window / dt)), force.size)",
        "filtered peak: a window shorter than half a step has no row",
        FILTERED_TESTS,
    ),
    Mutation(
        "F4",
        DOCKING,
        "min(max(int(round(window / dt)), 1), force.size)",
        "max(int(round(window / dt)), 1)",
        "filtered peak: a series shorter than the window is not averaged whole",
        FILTERED_TESTS,
    ),
    Mutation(
        "F5",
        DOCKING,
        "min(max(int(round(window / dt)), 1), force.size)",
        "min(max(int(round(window / dt)), 1) + 1, force.size)",
        "filtered peak: the window one row longer",
        FILTERED_TESTS,
    ),
    Mutation(
        "F6",
        DOCKING,
        "dt = float(t[1] - t[0]) if len(t) > 1 else 1.0",
        "dt = 0.001",
        "filtered peak: the window counted in 1 ms rows whatever the time step",
        FILTERED_TESTS,
    ),
    Mutation(
        "F7",
        DOCKING,
        "sums = np.cumsum(np.r_[0.0, force])",
        "sums = np.cumsum(np.r_[0.0, np.abs(force)])",
        "filtered peak: the mean of |f|, not |mean f|",
        FILTERED_TESTS,
    ),
    Mutation(
        "F8",
        DOCKING,
        "np.max(np.abs(sums[n:] - sums[:-n])) / n",
        "np.max(sums[n:] - sums[:-n]) / n",
        "filtered peak: signed (a pull reads nothing)",
        FILTERED_TESTS,
    ),
    Mutation(
        "F9",
        DOCKING,
        "np.max(np.abs(sums[n:] - sums[:-n])) / n",
        "np.max(np.abs(sums[n:] - sums[:-n]))",
        "filtered peak: the sum over the window, not the mean",
        FILTERED_TESTS,
    ),
    Mutation(
        "F10",
        DOCKING,
        "np.max(np.abs(sums[n:] - sums[:-n])) / n",
        "np.max(np.abs(sums[n + 1 :] - sums[1:-n])) / n",
        "filtered peak: the first full window skipped",
        FILTERED_TESTS,
    ),
    Mutation(
        "F11",
        DOCKING,
        "np.max(np.abs(sums[n:] - sums[:-n])) / n",
        "np.max(np.abs(sums[n:-1] - sums[: -n - 1])) / n",
        "filtered peak: the last full window skipped",
        FILTERED_TESTS,
    ),
    Mutation(
        "F12",
        DOCKING,
        '        return float("nan")\n    dt = ',
        "        return 0.0\n    dt = ",
        "filtered peak of an empty series: 0 N, not unknown",
        FILTERED_TESTS,
    ),
    Mutation(
        "F13",
        DOCKING,
        "filtered_peak(axial, t, force_window)",
        "filtered_peak(np.linalg.norm(ts[FORCE].to_numpy(), axis=1), t, force_window)",
        "filtered peak of |f|, not of the axial force",
        FILTERED_TESTS,
    ),
    Mutation(
        "F14",
        DOCKING,
        "filtered_peak(axial, t, force_window)",
        "filtered_peak(axial[steady], t[steady], force_window)",
        "filtered peak over the steady window only",
        FILTERED_TESTS,
    ),
    Mutation(
        "F15",
        DOCKING,
        "filtered_peak(axial, t, force_window)",
        "filtered_peak(axial, t, steady_window)",
        "filtered peak over the steady window's length",
        FILTERED_TESTS,
    ),
    Mutation(
        "F16",
        RUNNER,
        "force_window=float(cfg.task.force_window)",
        "force_window=float(cfg.task.strike_window)",
        "the runner filters over task.strike_window",
        FILTERED_RUN_TESTS,
    ),
    Mutation(
        "F17",
        DOCKING,
        '            metrics["filtered_peak_axial_force_N"],\n',
        '            metrics["peak_axial_force_N"],\n',
        "the gate judges the raw per-step peak",
        GATE_TESTS + ("tests/evaluation/test_filtered_peak.py",),
    ),
    Mutation(
        "F18",
        TASK_CONF,
        "force_window: 0.05\n",
        "force_window: 0.5\n",
        "the default force window 0.5 s",
        FILTERED_TESTS,
    ),
    # ---------------------------------------------------------------- contact metrics
    Mutation(
        "K1",
        CONTACT,
        "return None if first is None else max(first - 1, 0)",
        "return first",
        "first contact read on the row after the state that found it",
        CONTACT_TESTS,
    ),
    Mutation(
        "K2",
        CONTACT,
        "    free = np.flatnonzero(contacts[start:stop] <= 0)",
        "    free = np.flatnonzero(contacts[start:stop] < 0)",
        "first strike never ends at the first opening",
        CONTACT_TESTS,
    ),
    Mutation(
        "K3",
        CONTACT,
        "    return int(np.count_nonzero(np.diff(touching)))",
        "    return int(np.count_nonzero(np.diff(touching) > 0))",
        "make/break events count the makes only",
        CONTACT_TESTS,
    ),
    # the definitions of the contact metrics (docs/run_directory.md, "contact"): every part
    # of them, so a change to a row, a component, a window or a range fails a test
    Mutation(
        "K4",
        CONTACT,
        "    return int(touching[0]) if touching.size else None",
        "    return int(touching[-1]) if touching.size else None",
        "first contact: the last touching row instead of the first",
        CONTACT_TESTS,
    ),
    Mutation(
        "K5",
        CONTACT,
        "    touching = np.flatnonzero(np.asarray(contacts) > 0)",
        "    touching = np.flatnonzero(np.asarray(contacts) >= 0)",
        "first contact: a row without contacts counts as touching",
        CONTACT_TESTS,
    ),
    Mutation(
        "K6",
        CONTACT,
        "return None if first is None else max(first - 1, 0)",
        "return None if first is None else first - 1",
        "first contact on row 0: the state row wraps to the last row",
        CONTACT_TESTS,
    ),
    Mutation(
        "K7",
        CONTACT,
        "np.asarray(axial)[start : strike_end(contacts, start, max_rows)]",
        "np.asarray(axial)[start + 1 : strike_end(contacts, start, max_rows)]",
        "first strike skips the first contact row",
        CONTACT_TESTS,
    ),
    Mutation(
        "K8",
        CONTACT,
        "np.asarray(axial)[start : strike_end(contacts, start, max_rows)]",
        "np.asarray(axial)[start : strike_end(contacts, start, max_rows - 1)]",
        "first strike's cap one row short",
        CONTACT_TESTS,
    ),
    Mutation(
        "K9",
        CONTACT,
        "    stop = min(start + max(int(max_rows), 1), len(contacts))",
        "    stop = len(contacts)",
        "first strike without its cap",
        CONTACT_TESTS,
    ),
    Mutation(
        "K10",
        CONTACT,
        "max_rows = max(int(round(strike_window / dt)), 1)",
        "max_rows = max(int(strike_window / dt), 1)",
        "strike cap: strike_window / dt truncated, not rounded",
        CONTACT_TESTS,
    ),
    Mutation(
        "K11",
        CONTACT,
        "    stop = min(start + max(int(max_rows), 1), len(contacts))",
        "    stop = min(start + int(max_rows), len(contacts))",
        "strike cap may hold no row",
        CONTACT_TESTS,
    ),
    Mutation(
        "K12",
        CONTACT,
        "np.asarray(axial)[start : strike_end",
        "np.abs(axial)[start : strike_end",
        "first strike: peak of |axial| instead of the push",
        CONTACT_TESTS,
    ),
    Mutation(
        "K13",
        CONTACT,
        "        axial = -(force @ insertion)",
        "        axial = force @ insertion",
        "strike force: pulls count as positive",
        CONTACT_TESTS,
    ),
    Mutation(
        "K14",
        CONTACT,
        "        insertion = -seat.rotation[:, 2]",
        "        insertion = -seat.rotation[2, :]",
        "insertion axis: a row of the seat rotation, not its z column",
        CONTACT_TESTS,
    ),
    Mutation(
        "K15",
        CONTACT,
        "        insertion = -seat.rotation[:, 2]",
        "        insertion = np.array([0.0, 0.0, -1.0])",
        "insertion axis: world −z, not the TRUE socket's",
        CONTACT_TESTS,
    ),
    Mutation(
        "K16",
        CONTACT,
        "        rel = (ts[POSITION].to_numpy()[state] - seat.translation) @ seat.rotation",
        "        rel = ts[POSITION].to_numpy()[state] - seat.translation",
        "lateral offset at first contact in world axes",
        CONTACT_TESTS,
    ),
    Mutation(
        "K17",
        CONTACT,
        "        rel = (ts[POSITION].to_numpy()[state] - seat.translation) @ seat.rotation",
        "        rel = (ts[POSITION].to_numpy()[state] - seat.translation) @ seat.rotation.T",
        "lateral offset at first contact with the inverse seat rotation",
        CONTACT_TESTS,
    ),
    Mutation(
        "K18",
        CONTACT,
        "        rel = (ts[POSITION].to_numpy()[state] - seat.translation) @ seat.rotation",
        "        rel = ts[POSITION].to_numpy()[state] @ seat.rotation",
        "lateral offset from the world origin, not the seat",
        CONTACT_TESTS,
    ),
    Mutation(
        "K19",
        CONTACT,
        "first_contact_lateral_offset_m=np.hypot(rel[0], rel[1])",
        "first_contact_lateral_offset_m=np.linalg.norm(rel)",
        "lateral offset includes the height above the seat",
        CONTACT_TESTS,
    ),
    Mutation(
        "K20",
        CONTACT,
        "ts[POSITION].to_numpy()[state]",
        "ts[POSITION].to_numpy()[first]",
        "lateral offset read on the contact row, not the state that found it",
        CONTACT_TESTS,
    ),
    Mutation(
        "K21",
        CONTACT,
        "        velocity = ts[TWIST[:3]].to_numpy()[state]",
        "        velocity = ts[TWIST[:3]].to_numpy()[first]",
        "speed at first contact read on the contact row",
        CONTACT_TESTS,
    ),
    Mutation(
        "K22",
        CONTACT,
        "first_contact_speed_m_s=velocity @ insertion",
        "first_contact_speed_m_s=np.linalg.norm(velocity)",
        "speed at first contact: the whole speed, not along the insertion axis",
        CONTACT_TESTS,
    ),
    Mutation(
        "K23",
        CONTACT,
        "        velocity = ts[TWIST[:3]].to_numpy()[state]",
        "        velocity = ts[TWIST[3:]].to_numpy()[state]",
        "speed at first contact from the angular velocity",
        CONTACT_TESTS,
    ),
    Mutation(
        "K24",
        CONTACT,
        "    steady = t >= t[-1] - steady_window",
        "    steady = t > t[-1] - steady_window",
        "steady window excludes its first instant",
        CONTACT_TESTS,
    ),
    Mutation(
        "K25",
        CONTACT,
        "    steady = t >= t[-1] - steady_window",
        "    steady = t <= t[0] + steady_window",
        "steady window at the start of the run",
        CONTACT_TESTS,
    ),
    Mutation(
        "K26",
        CONTACT,
        "magnitude.std(ddof=1)",
        "magnitude.std()",
        "steady force std with ddof 0",
        CONTACT_TESTS,
    ),
    Mutation(
        "K27",
        CONTACT,
        "    magnitude = np.linalg.norm(force[steady], axis=1)",
        "    magnitude = np.abs(force[steady] @ seat.rotation[:, 2])",
        "steady force: the axial component instead of |f|",
        CONTACT_TESTS,
    ),
    Mutation(
        "K28",
        CONTACT,
        "steady_force_mean_N=magnitude.mean() if",
        "steady_force_mean_N=np.median(magnitude) if",
        "steady force: median instead of the mean",
        CONTACT_TESTS,
    ),
    Mutation(
        "K29",
        CONTACT,
        "make_break_events(contacts[steady])",
        "make_break_events(contacts)",
        "make/break events counted over the whole run",
        CONTACT_TESTS,
    ),
    Mutation(
        "K30",
        CONTACT,
        "make_break_events(contacts[steady])",
        "make_break_events(contacts[max(int(np.argmax(steady)) - 1, 0) :])",
        "make/break events count the change into the window",
        CONTACT_TESTS,
    ),
    Mutation(
        "K31",
        CONTACT,
        "make_break_events(contacts[steady]) / span if span > 0",
        "make_break_events(contacts[steady]) / steady_window if span > 0",
        "event rate per second of the window setting, not of its rows' span",
        CONTACT_TESTS,
    ),
    Mutation(
        "K32",
        CONTACT,
        "/ span if span > 0 else None",
        "/ span if span > 0 else 0.0",
        "a one-row window reports no events instead of none measurable",
        CONTACT_TESTS,
    ),
    Mutation(
        "K33",
        CONTACT,
        "    touching = (np.asarray(contacts) > 0).astype(np.int8)",
        "    touching = (np.asarray(contacts) > 1).astype(np.int8)",
        "make/break: a single contact counts as not touching",
        CONTACT_TESTS,
    ),
    Mutation(
        "K34",
        CONTACT,
        "    return {k: finite_or_none(values[k]) for k in CONTACT_KEYS}",
        "    return {k: values[k] for k in CONTACT_KEYS}",
        "non-finite contact metrics reported as numbers",
        CONTACT_TESTS,
    ),
    Mutation(
        "K35",
        CONTACT,
        "    free = np.flatnonzero(contacts[start:stop] <= 0)\n    return start + int(free[0])",
        "    free = np.flatnonzero(contacts[start:stop] <= 0)\n    return start + int(free[0]) + 1",
        "first strike includes the row where the contact opened",
        CONTACT_TESTS,
    ),
    Mutation(
        "K36",
        CONTACT,
        "    if ts.empty:\n        return values",
        "    if False:\n        return values",
        "an empty time series is not reported as all null",
        CONTACT_TESTS,
    ),
    Mutation(
        "K37",
        RUNNER,
        "        contact = contact_metrics(\n            ts,\n            sim.scene.socket.true,",
        "        contact = contact_metrics(\n            ts,\n            sim.scene.socket.believed,",
        "contact metrics measured against the believed socket, not the true one",
        MISALIGNMENT_TESTS,
    ),
    # ---------------------------------------------------------------- misalignment draws
    Mutation(
        "D1",
        MISALIGNMENT,
        "        return believed * offset",
        "        return offset * believed",
        "misalignment in world axes, not in the believed socket frame",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D2",
        MISALIGNMENT,
        "        return rz @ rx",
        "        return rx @ rz",
        "tilt before the yaw (Rx · Rz)",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D3",
        MISALIGNMENT,
        "[0.0, ct, -st], [0.0, st, ct]",
        "[0.0, ct, st], [0.0, -st, ct]",
        "tilt leans towards +y instead of −y",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D4",
        MISALIGNMENT,
        "[[cy, -sy, 0.0], [sy, cy, 0.0]",
        "[[cy, sy, 0.0], [-sy, cy, 0.0]",
        "yaw turns clockwise about the socket axis",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D5",
        MISALIGNMENT,
        "pin.SE3(self.rotation(), np.array([self.x, self.y, 0.0]))",
        "pin.SE3(self.rotation(), self.rotation() @ np.array([self.x, self.y, 0.0]))",
        "lateral offset after the rotation (in the true socket's axes)",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D6",
        MISALIGNMENT,
        "pin.SE3(self.rotation(), np.array([self.x, self.y, 0.0]))",
        "pin.SE3(self.rotation(), np.array([self.y, self.x, 0.0]))",
        "x and y offsets swapped",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D7",
        MISALIGNMENT,
        "ct, st = math.cos(math.radians(self.tilt_deg)), math.sin(math.radians(self.tilt_deg))",
        "ct, st = math.cos(self.tilt_deg), math.sin(self.tilt_deg)",
        "tilt taken in radians",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D8",
        MISALIGNMENT,
        "return low + (high - low) * float(stream_rng(seed, stream).random())",
        "return low + high * float(stream_rng(seed, stream).random())",
        "draw: low + high·u instead of low + (high − low)·u",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D9",
        MISALIGNMENT,
        "return low + (high - low) * float(stream_rng(seed, stream).random())",
        "return high - (high - low) * float(stream_rng(seed, stream).random())",
        "draw measured from the upper end of the range",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D10",
        MISALIGNMENT,
        "np.random.SeedSequence([int(seed), stream])",
        "np.random.SeedSequence([int(seed), 0])",
        "one random stream shared by every component",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D11",
        MISALIGNMENT,
        "np.random.SeedSequence([int(seed), stream])",
        "np.random.SeedSequence([stream, int(seed)])",
        "streams keyed (component, seed) instead of (seed, component)",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D12",
        MISALIGNMENT,
        'COMPONENTS = ("x", "y", "yaw_deg", "tilt_deg")',
        'COMPONENTS = ("y", "x", "yaw_deg", "tilt_deg")',
        "x and y draw from each other's stream",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D13",
        MISALIGNMENT,
        "return low + (high - low) * float(stream_rng(seed, stream).random())",
        "return low + (high - low) * float(stream_rng(seed, stream + int(1e6 * (high - low))).random())",
        "the stream depends on the range (no common random numbers across ranges)",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D14",
        VALIDATE,
        "        if bounds is not None and settings.get(name):",
        "        if False:",
        "a fixed value and a range both set: the range wins silently",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D15",
        MISALIGNMENT,
        "values[name] = float(given.get(name, 0.0))",
        "values[name] = 0.0",
        "a fixed component is dropped",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D16",
        VALIDATE,
        "len(bounds) == 2 and bounds[0] > bounds[1]:",
        "len(bounds) == 2 and bounds[0] > bounds[1] + 1.0:",
        "a reversed range is accepted",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D17",
        VALIDATE,
        "len(bounds) == 2 and bounds[0] > bounds[1]:",
        "len(bounds) == 2 and bounds[0] >= bounds[1]:",
        "a range of one value ([a, a]) is refused",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D18",
        SCHEMAS,
        '    tilt_deg: float = inside(-60, 60, unit="deg")',
        '    tilt_deg: float = within(-60, 60, unit="deg")',
        "a tilt of exactly 60° is accepted",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D19",
        SCHEMAS,
        '    tilt_deg: float = inside(-60, 60, unit="deg")',
        '    tilt_deg: float = inside(-1e9, 60, unit="deg")',
        "a large negative tilt is accepted",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D20",
        SCHEMAS,
        '    tilt_deg: float = inside(-60, 60, unit="deg")',
        '    tilt_deg: float = inside(-90, 90, unit="deg")',
        "tilt limit 90° instead of 60°",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D21",
        MISALIGNMENT,
        '    require(MisalignmentConfig, "task.misalignment", **given)',
        "    pass",
        "the draw skips the schema's ranges (a non-finite value, a wrong-sized range, a negative seed)",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D22",
        SCHEMAS,
        '    x_range: Optional[List[float]] = within(-1.0, 1.0, unit="m", size=2)',
        '    x_range: Optional[List[float]] = within(-1.0, 1.0, unit="m")',
        "a range of other than two values is accepted",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D23",
        SCHEMAS,
        "    seed: int = integers(0, 2**63 - 1)",
        "    seed: int = integers(-(2**63), 2**63 - 1)",
        "a negative seed is accepted",
        MISALIGNMENT_RULE_TESTS,
    ),
    Mutation(
        "D24",
        MISALIGNMENT,
        "        if seed is None:  # a draw needs its seed",
        "        if False:",
        "a range without a seed is drawn from None",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D25",
        MISALIGNMENT,
        "        return math.hypot(self.x, self.y)",
        "        return abs(self.x) + abs(self.y)",
        "recorded lateral misalignment |x| + |y| instead of √(x² + y²)",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D26",
        MISALIGNMENT,
        '            "misalignment_y_m": self.y,',
        '            "misalignment_y_m": self.x,',
        "x recorded under the y key",
        MISALIGNMENT_TESTS,
    ),
    Mutation(
        "D27",
        MISALIGNMENT,
        "seed=int(seed) if drawn else None",
        "seed=int(seed)",
        "a seed recorded although nothing was drawn",
        MISALIGNMENT_TESTS,
    ),
    # ---------------------------------------------------------------- tracking gate
    Mutation(
        "T1",
        TRACKING,
        "float(np.sqrt(np.mean(p * p)))",
        "float(np.mean(p))",
        "segment position RMS replaced by the mean",
        TRACKING_TESTS,
    ),
    Mutation(
        "T2",
        TRACKING,
        '            saturation = float(np.mean(ts.loc[window, "torque_saturated"]',
        '            saturation = float(np.mean(ts.loc[:, "torque_saturated"]',
        "saturation ratio over the whole run",
        TRACKING_TESTS,
    ),
    Mutation(
        "T3",
        TRACKING,
        '    at_most("max contacts", metrics.max_contacts, "max_contacts", 1.0, "")\n',
        "",
        "contacts not judged",
        TRACKING_TESTS,
    ),
    Mutation(
        "T4",
        TRACKING,
        "elif _finite(limit) and value > limit:",
        "elif _finite(limit) and value > 3 * limit:",
        "tracking thresholds × 3",
        TRACKING_TESTS,
    ),
    Mutation(
        "T5",
        TRACKING,
        "        if value is not None and not _finite(value):\n            failures.append",
        "        if False:\n            failures.append",
        "a non-finite statistic passes",
        TRACKING_TESTS,
    ),
    Mutation(
        "T6",
        TRACKING,
        "window = (t >= min(s[1] for s in segments)) & (t < max(s[2] for s in segments))",
        "window = t >= min(s[1] for s in segments)",
        "the hold after the motion is judged",
        TRACKING_TESTS,
    ),
    # ---------------------------------------------------------------- sensor chain
    Mutation(
        "S1",
        SENSOR,
        "out[3:] -= weight_moment.dot",
        "out[3:] += weight_moment.dot",
        "weight-moment sign flipped",
        SENSOR_TESTS,
    ),
    Mutation("S2", SENSOR, "            out[:3] -= weight\n", "", "tool weight not removed", SENSOR_TESTS),
    Mutation(
        "S3",
        SENSOR,
        "r = -(true_tool.sensor.actInv(true_tool.tcp)).translation",
        "r = (true_tool.sensor.actInv(true_tool.tcp)).translation",
        "moment moved to the TCP with the wrong lever",
        SENSOR_TESTS,
    ),
    Mutation(
        "S4",
        SENSOR,
        "to_tcp = -np.block(",
        "to_tcp = np.block(",
        "reaction instead of the wrench on the tool",
        SENSOR_TESTS,
    ),
    # ---------------------------------------------------------------- control laws
    Mutation(
        "C1",
        IMPEDANCE,
        "D = np.array([d] * 3 + [d_rot] * 3, dtype=float)",
        "D = np.array([0.5 * d] * 3 + [d_rot] * 3, dtype=float)",
        "impedance damping halved",
        LAW_TESTS,
    ),
    Mutation(
        "C2",
        IMPEDANCE,
        "D = np.array([d] * 3 + [d_rot] * 3, dtype=float)",
        "D = np.array([d] * 3 + [0.5 * d_rot] * 3, dtype=float)",
        "impedance rotational damping halved",
        LAW_TESTS,
    ),
    Mutation(
        "C3",
        IMPEDANCE,
        "W_inv = 1.0 / np.array([m] * 3",
        "W_inv = 0.5 / np.array([m] * 3",
        "impedance apparent mass doubled",
        LAW_TESTS,
    ),
    Mutation(
        "C4",
        IMPEDANCE,
        "K = np.array([k] * 3 + [k_rot] * 3, dtype=float)",
        "K = np.array([0.9 * k] * 3 + [k_rot] * 3, dtype=float)",
        "impedance stiffness −10 %",
        LAW_TESTS,
    ),
    Mutation(
        "C5",
        IMPEDANCE,
        "            force -= wrench\n",
        "",
        "the push counted twice (no −Jᵀw, as the research code)",
        LAW_TESTS,
    ),
    Mutation(
        "C6",
        IMPEDANCE,
        "        a += JMinv.dot(bv)\n",
        "",
        "null-space damping leaks into the task",
        LAW_TESTS,
    ),
    Mutation(
        "C7",
        SE3_LIE,
        "self.D = _matrix(D_diag if D is None else D",
        "self.D = 0.5 * _matrix(D_diag if D is None else D",
        "SE(3) impedance damping halved",
        LAW_TESTS,
    ),
    Mutation(
        "C8",
        SE3_LIE,
        "self.K = _matrix(K_diag if K is None else K",
        "self.K = 0.9 * _matrix(K_diag if K is None else K",
        "SE(3) impedance stiffness −10 %",
        LAW_TESTS,
    ),
    Mutation(
        "C9",
        HQP_KERNEL,
        "one_minus_alpha = 1.0 / (1.0 + math.exp(x))",
        "one_minus_alpha = 1.0 / (1.0 + math.exp(-x))",
        "HQP stiffness rises with force (α for 1 − α)",
        LAW_TESTS,
    ),
    Mutation(
        "C10",
        HQP_KERNEL,
        "return min(max(one_minus_alpha, K_min_ratio), 1.0)",
        "return min(one_minus_alpha, 1.0)",
        "HQP K_min clip removed",
        LAW_TESTS,
    ),
    Mutation(
        "C11",
        HQP_KERNEL,
        "            DK[i, j] *= ws.sqrt_s\n",
        "            DK[i, j] *= 0.5 * ws.sqrt_s\n",
        "HQP damping halved",
        LAW_TESTS,
    ),
    Mutation(
        "C12",
        BASE,
        "            tau_pre, v, v if bias is None else bias, self.f,",
        "            tau_pre, v, v if bias is None else bias, -self.f,",
        "friction feed-forward against the motion",
        LAW_TESTS,
    ),
    Mutation(
        "C13",
        SHAPING,
        "        c[m] = min(mu[m] * inv_ratio, 1.0)",
        "        c[m] = min(mu[m] * ratio, 1.0)",
        "apparent-inertia floor at 1/ratio instead of ratio",
        ("tests/control/test_shaping.py",),
    ),
    Mutation(
        "C14",
        INTEGRAL,
        "    if it.latched or f0 * f0 + f1 * f1 + f2 * f2 > it.freeze_sq:",
        "    if False:",
        "integral action never frozen in contact",
        ("tests/control/test_integral.py",),
    ),
    Mutation(
        "C15",
        KERNEL_BLOCKS,
        "            x = (tau_pre[i] - h[i]) * scale[i]",
        "            x = (tau_pre[i] + 0.0 * h[i]) * scale[i]",
        "torque_unbiased ignores the bias torques",
        LAW_TESTS,
    ),
    # the compiled steps: each is checked against a numpy evaluation
    Mutation(
        "C16",
        KERNEL_BLOCKS,
        "        out[i] = y * f[i] + b[i] * v[i]",
        "        out[i] = -y * f[i] + b[i] * v[i]",
        "compiled friction feed-forward against the motion",
        ("tests/control/test_kernel_blocks.py", *LAW_TESTS),
    ),
    Mutation(
        "C17",
        SE3_KERNEL,
        "        tau[c] = s + h[c] - bn * mv",
        "        tau[c] = s + h[c] + bn * mv",
        "compiled SE(3) step: null-space damping pumps energy in",
        ("tests/control/test_se3_kernel.py", *LAW_TESTS),
    ),
    Mutation(
        "C18",
        HQP_KERNEL,
        "                a_null[i] += gain * direction[i]",
        "                a_null[i] -= gain * direction[i]",
        "compiled HQP step: singularity avoidance steers toward the singularity",
        ("tests/control/test_hqp_kernel.py", *LAW_TESTS),
    ),
    # ---------------------------------------------------------------- provenance, exit status
    Mutation(
        "P1",
        PROVENANCE,
        "            dirty = True",
        "            dirty = False",
        "git_dirty never true",
        PROVENANCE_TESTS,
    ),
    Mutation(
        "P2",
        PROVENANCE,
        'commit = oid if oid != "(initial)" else None',
        "commit = oid[::-1]",
        "git_commit not HEAD",
        PROVENANCE_TESTS,
    ),
    Mutation(
        "R2",
        TABLES,
        "means = values.groupby(by, sort=False).mean()",
        "means = values.groupby(by, sort=False).median()",
        "comparison table: median instead of the mean",
        RESULTS_TESTS,
    ),
    Mutation(
        "R3",
        TABLES,
        'totals["success rate"] = totals["docked"] / totals["jobs"]',
        'totals["success rate"] = totals["docked"] / (totals["jobs"] - totals["failed"])',
        "success rate over the jobs that did not fail",
        RESULTS_TESTS,
    ),
    # ------------------------------------- the motion apart from the press, docking time
    Mutation(
        "M18",
        DOCKING,
        "return np.arange(n) < (n if state is None else state)",
        "return np.arange(n) <= (n if state is None else state)",
        "the approach includes the first contact's state row",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M19",
        DOCKING,
        'state = first_contact_state(ts["contacts"].to_numpy()) if "contacts" in ts else None',
        "state = None",
        "the approach runs to the end of the series (press included)",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M20",
        DOCKING,
        "press_depth_m=-np.mean((pos_err @ axis)[steady])",
        "press_depth_m=np.mean((pos_err @ axis)[steady])",
        "press depth with the wrong sign (out of the socket positive)",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M21",
        DOCKING,
        "press_depth_m=-np.mean((pos_err @ axis)[steady])",
        "press_depth_m=-np.mean(pos_err @ axis)",
        "press depth averaged over the whole run, not the steady window",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M22",
        DOCKING,
        "return max(stays_from, first_contact)",
        "return stays_from",
        "docking time may come before the first contact (the planner's arrival)",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M23",
        DOCKING,
        "stays_from = int(outside[-1]) + 1 if outside.size else 0",
        "stays_from = int(outside[0]) + 1 if outside.size else 0",
        "docking time after the first excursion, not the last",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M24",
        DOCKING,
        "if first_contact is None or not seated.size or not seated[-1]:",
        "if first_contact is None or not seated.size:",
        "a plug that left the seat again still counts as docked",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M25",
        DOCKING,
        "inside = (depth <= depth_tolerance) & (lateral <= lateral_tolerance)",
        "inside = depth <= depth_tolerance",
        "docked without the lateral tolerance",
        DOCKING_TIME_TESTS,
    ),
    Mutation(
        "M26",
        DOCKING,
        "docking_time_after_contact_s=None if docked is None else float(t[docked] - t[contact]),",
        "docking_time_after_contact_s=None if docked is None else float(t[docked] - t[0]),",
        "docking time after contact measured from the start",
        DOCKING_TIME_TESTS,
    ),
    # ---------------------------------------- the jamming map's theoretical boundaries
    Mutation(
        "B1",
        BOUNDARIES,
        "centre, half = -height * math.sin(theta), capture * math.cos(theta)",
        "centre, half = height * math.sin(theta), capture * math.cos(theta)",
        "capture band shifted the wrong way with the tilt",
        BOUNDARY_TESTS,
    ),
    Mutation(
        "B2",
        BOUNDARIES,
        "centre, half = -height * math.sin(theta), capture * math.cos(theta)",
        "centre, half = -height * math.sin(theta), capture",
        "capture half-width not foreshortened by cos θ",
        BOUNDARY_TESTS,
    ),
    Mutation(
        "B3",
        BOUNDARIES,
        "math.degrees((big_r - r) / big_r / peg.friction) if peg.friction > 0 else math.inf",
        "math.degrees((big_r - r) / r / peg.friction) if peg.friction > 0 else math.inf",
        "Whitney's clearance ratio c over the plug's radius, not the bore's",
        BOUNDARY_TESTS,
    ),
    Mutation(
        "B4",
        BOUNDARIES,
        "two_point_tilt(big_r, r, peg.bore_depth - peg.chamfer_length)",
        "two_point_tilt(big_r, r, peg.bore_depth)",
        "two-point line at the bore's full depth (the chamfer counted as cylinder)",
        BOUNDARY_TESTS,
    ),
    Mutation(
        "B5",
        BOUNDARIES,
        "        if tilt_deg > self.wedging_tilt_deg:\n"
        '            return "wedged"\n'
        "        if tilt_deg > self.two_point_tilt_deg:\n"
        '            return "two-point"\n',
        "        if tilt_deg > self.two_point_tilt_deg:\n"
        '            return "two-point"\n'
        "        if tilt_deg > self.wedging_tilt_deg:\n"
        '            return "wedged"\n',
        "wedging never reported (two-point checked first)",
        BOUNDARY_TESTS,
    ),
    # ------------------------------------------------------------ the bounded reference
    Mutation(
        "L1",
        LEAD,
        "if ahead > self.limit and self.axial[j] > self.axial[j - 1]:",
        "if ahead > 2.0 * self.limit and self.axial[j] > self.axial[j - 1]:",
        "the reference may lead by twice the limit",
        LEAD_TESTS,
    ),
    Mutation(
        "L2",
        LEAD,
        "if ahead > self.limit and self.axial[j] > self.axial[j - 1]:",
        "if ahead > self.limit:",
        "the reference also held where the plan does not advance along the axis",
        LEAD_TESTS,
    ),
    Mutation(
        "L3",
        LEAD,
        "            live.pos[k] = (t0 + gap * u0, t1 + gap * u1, t2 + gap * u2)",
        "            live.pos[k] = planned.pos[j]",
        "held reference stiff laterally (not following the plug)",
        LEAD_TESTS,
    ),
    Mutation(
        "L4",
        LEAD,
        """            live.twist[k] = 0.0
            live.accel[k] = 0.0""",
        """            live.twist[k] = planned.twist[j]
            live.accel[k] = planned.accel[j]""",
        "a held reference keeps its planned velocity",
        LEAD_TESTS,
    ),
    Mutation(
        "L5",
        LEAD,
        '    require(QuinticConfig, "trajectory", lead_limit=limit)',
        "    pass",
        "the reference's lead limit not checked (0 m or a negative limit accepted)",
        LEAD_TESTS,
    ),
    # ------------------------------------------- the integral's latch and orientation part
    Mutation(
        "I1",
        INTEGRAL,
        "        it.latched = it.latch",
        "        it.latched = False",
        "the integral never latched: it integrates again when the contact is lost",
        ("tests/control/test_integral.py",),
    ),
    Mutation(
        "I2",
        INTEGRAL,
        "it.rot_state, it.torque, r0, r1, r2, it.dt, it.rot_gain, it.rot_limit)",
        "it.rot_state, it.torque, r0, r1, r2, it.dt, it.rot_gain, 1e9)",
        "the orientation integral never clamped",
        ("tests/control/test_integral.py",),
    ),
    Mutation(
        "I3",
        INTEGRAL,
        "        r0, r1, r2 = rot_err[0], rot_err[1], rot_err[2]",
        "        r0, r1, r2 = -rot_err[0], -rot_err[1], -rot_err[2]",
        "the orientation integral pushes with the error, not against it",
        ("tests/control/test_integral.py",),
    ),
    Mutation(
        "I4",
        HQP_KERNEL,
        "            F_r[3 + i] += M_i[i]",
        "            F_r[3 + i] -= M_i[i]",
        "compiled HQP: the integral moment subtracted",
        HQP_KERNEL_TESTS,
    ),
    Mutation(
        "I5",
        SE3_KERNEL,
        "    i3, i4, i5 = body(Fi[3], Fi[4], Fi[5])",
        "    i3, i4, i5 = 0.0, 0.0, 0.0",
        "compiled se3_lie: the integral moment dropped",
        SE3_KERNEL_TESTS,
    ),
    Mutation(
        "I6",
        HQP_KERNEL,
        "        F_r[i] += F_i[i] + preload * axis[i]",
        "        F_r[i] += preload * axis[i]",
        "compiled HQP: the integral force dropped",
        HQP_KERNEL_TESTS,
    ),
    Mutation(
        "I7",
        INTEGRAL,
        "    if it.lateral:",
        "    if False:",
        "lateral_only ignored: the integral winds up along the docking axis too",
        ("tests/control/test_integral.py",),
    ),
    Mutation(
        "E1",
        SE3_KERNEL,
        "            acc += K[i, j] * lam[j]",
        "            acc += K[i, j] * lam[j] if i == j else 0.0",
        "compiled se3_lie: a general stiffness K read as its diagonal",
        SE3_KERNEL_TESTS,
    ),
    Mutation(
        "E2",
        SE3_KERNEL,
        "            w += G[j, 6 + m] * V_tilde[m]",
        "            w += G[j, 6 + m] * V_tilde[m] if j == m else 0.0",
        "compiled se3_lie: a general A⁻¹D read as its diagonal",
        SE3_KERNEL_TESTS,
    ),
    Mutation(
        "E3",
        SE3_KERNEL,
        "                a[:] = base + floor.P.dot(a - base)",
        "                pass",
        "se3_lie lambda_space: the apparent-inertia floor not applied",
        SE3_KERNEL_TESTS,
    ),
    # ------------------------------------------- the yielding friction feed-forward
    Mutation(
        "Y1",
        KERNEL_BLOCKS,
        "if mode == 3 and v[i] * y < 0.0:",
        "if mode == 3 and v[i] * y > 0.0:",
        "yielding fades the feed-forward on joints moving with it, not against it",
        YIELD_TESTS,
    ),
    Mutation(
        "Y2",
        KERNEL_BLOCKS,
        "y *= 1.0 - min(abs(v[i]) / YIELD_SPEED, 1.0)",
        "y *= 1.0 - 0.5 * min(abs(v[i]) / YIELD_SPEED, 1.0)",
        "yielding only halves the feed-forward against fast motion",
        YIELD_TESTS,
    ),
    Mutation(
        "Y3",
        KERNEL_BLOCKS,
        "YIELD_SPEED = 0.02",
        "YIELD_SPEED = 0.2",
        "the feed-forward is off only from 0.2 rad/s",
        YIELD_TESTS,
    ),
    Mutation(
        "R1",
        EXIT_CODES,
        "NOT_DOCKED = 3",
        "NOT_DOCKED = 1",
        "a gate failure exits 1",
        ("tests/test_exit_codes.py",),
    ),
)


def source_tree(ref: str | None, into: Path) -> None:
    """The checkout's files (tracked and untracked, not ignored), or the tree of ``ref``."""
    if ref is None:
        listed = (
            subprocess.run(
                ["git", "-C", str(ROOT), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                capture_output=True,
                check=True,
            )
            .stdout.decode()
            .split("\0")
        )
        for name in filter(None, listed):
            src = ROOT / name
            if src.is_file():
                (into / name).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(src, into / name)
    else:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(into)], input=archive.stdout, check=True)


def run_tests(tree: Path, tests: tuple[str, ...], timeout: float) -> tuple[str, str, float]:
    """('killed' | 'survived' | 'error', detail, seconds) of pytest -x on ``tests`` in ``tree``."""
    present = [t for t in tests if (tree / t).exists()]
    if not present:
        return "n/a", "no such test files", 0.0
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": str(tree)}
    started = time.perf_counter()
    try:
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "pytest",
                "-x",
                "-q",
                "-p",
                "no:cacheprovider",
                "-m",
                "not slow",
                *present,
            ],
            cwd=tree,
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
        )
    except subprocess.TimeoutExpired:
        return "killed", "timed out", time.perf_counter() - started
    seconds = time.perf_counter() - started
    failed = re.findall(r"^(?:FAILED|ERROR) (.+?)(?: - .*)?$", proc.stdout, re.M)
    if proc.returncode == 0:
        return "survived", "", seconds
    if proc.returncode == 1 and failed:
        return "killed", failed[0], seconds
    return "error", (failed[0] if failed else proc.stdout.strip().splitlines()[-1:] or [""])[0], seconds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--only", nargs="*", help="mutation keys (default: all)")
    parser.add_argument("--list", action="store_true", help="list the mutations and exit")
    parser.add_argument("--ref", help="a commit whose tree to mutate (default: the working tree)")
    parser.add_argument("--timeout", type=float, default=900.0, help="per mutation [s]")
    parser.add_argument("--out", type=Path, help="also write the Markdown table here")
    args = parser.parse_args(argv)
    chosen = [m for m in MUTATIONS if not args.only or m.key in args.only]
    if args.list:
        for m in chosen:
            print(f"{m.key:4} {m.path}: {m.what}")
        return 0
    rows = []
    with tempfile.TemporaryDirectory(prefix="mutation_") as tmp:
        tree = Path(tmp)
        source_tree(args.ref, tree)
        # the config tree and the assets are the packages compliant_docking.conf and .assets,
        # mapped to the checkout's conf/ and assets/ by its editable install: link the copy's
        # own, found first on PYTHONPATH, so that a mutation of a config file is seen
        for data in ("conf", "assets"):
            if (tree / data).is_dir() and not (tree / "compliant_docking" / data).exists():
                (tree / "compliant_docking" / data).symlink_to(Path("..") / data)
        where = subprocess.run(
            [
                sys.executable,
                "-c",
                "import compliant_docking as c; print(c.__file__); print(c.CONF_DIR); print(c.ASSETS_DIR)",
            ],
            cwd=tree,
            capture_output=True,
            text=True,
            env={**os.environ, "PYTHONPATH": str(tree)},
        ).stdout.split()
        if len(where) != 3 or not all(w.startswith(str(tree)) for w in where):
            sys.exit(f"the copy does not import its own package, config and assets (got {where!r})")
        for m in chosen:
            target = tree / m.path
            original = target.read_text(encoding="utf-8") if target.is_file() else ""
            if original.count(m.old) != 1:
                rows.append((m, "n/a", f"text found {original.count(m.old)}×", 0.0))
            else:
                target.write_text(original.replace(m.old, m.new), encoding="utf-8")
                try:
                    rows.append((m, *run_tests(tree, m.tests, args.timeout)))
                finally:
                    target.write_text(original, encoding="utf-8")
            m_, status, detail, seconds = rows[-1]
            print(f"{m.key:4} {status:8} {seconds:6.1f} s  {m.what}  {detail}", flush=True)
    judged = [r for r in rows if r[1] in ("killed", "survived", "error")]
    killed = sum(r[1] in ("killed", "error") for r in judged)
    lines = [
        "| key | file | mutation | result | caught by | s |",
        "|---|---|---|---|---|---:|",
        *(
            f"| {m.key} | {Path(m.path).name} | {m.what} | {status} | "
            f"{detail.replace('|', '/')} | {seconds:.0f} |"
            for m, status, detail, seconds in rows
        ),
        "",
        f"Score: {killed}/{len(judged)} killed",
    ]
    table = "\n".join(lines)
    print("\n" + table)
    if args.out:
        args.out.write_text(table + "\n", encoding="utf-8")
    return 0 if killed == len(judged) else 1


if __name__ == "__main__":
    sys.exit(main())
