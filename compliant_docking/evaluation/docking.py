"""The docking metrics (Table 10 of Ren & Shan 2026, Acta Astronautica; the research code's
``DockingMetrics``), seat state and the docking gate.

Computed after the loop from the run's time series (see :mod:`compliant_docking.sim.telemetry`).
Every value is a float, an int or None: None means it cannot be computed (no data, no
joint with a finite limit, …), never a made-up number; a non-finite value becomes None.

Conventions (docs/run_directory.md):
- ``axis`` is the unit docking axis (direction of insertion, world).
- axial force = −f·axis, with f the measured force ON the tool: positive when the plug
  presses along the insertion direction (the socket pushes back).
- the steady window is the last ``steady_window`` seconds of the run.
- joint indices (``*_joint``) are 0-based, as in the research code.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
import pinocchio as pin

from compliant_docking.evaluation.contact import ContactMetrics, first_contact_state
from compliant_docking.evaluation.registry import DOCKING_KEYS, finite_or_none
from compliant_docking.sim.geometry.fragment import ROUND, Key
from compliant_docking.sim.telemetry import (
    FORCE,
    ORI_ERROR,
    POSITION,
    POSITION_REF,
    QUATERNION,
    WRENCH,
    axial_force,
)

#: the values of :func:`compute_metrics` (registry keys), None = cannot be computed
DockingMetrics = dict[str, float | int | None]


def steady_mask(t: np.ndarray, window: float) -> np.ndarray:
    return t >= t[-1] - window if t.size else np.zeros(0, dtype=bool)


def compute_metrics(
    ts: pd.DataFrame,
    *,
    axis: np.ndarray,
    q_lower: np.ndarray,
    q_upper: np.ndarray,
    velocity_limits: np.ndarray,
    manipulability: np.ndarray | None,
    steady_window: float,
    force_window: float,
) -> DockingMetrics:
    """docking metrics of a run's time series, keyed as in the registry (``DOCKING_KEYS``).

    ``manipulability``: √det(J Jᵀ) per step (world Jacobian of the TCP), or None.
    ``force_window``: the averaging window of the filtered peak force [s]
    (:func:`filtered_peak`).
    """
    if ts.empty:
        return dict.fromkeys(DOCKING_KEYS)
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    t = ts["t"].to_numpy()
    steady = steady_mask(t, steady_window)
    nv = len(q_lower)

    axial = axial_force(ts[FORCE].to_numpy(), axis)
    wrench_norm = np.linalg.norm(ts[WRENCH].to_numpy(), axis=1)

    q = ts[[f"q{i + 1}" for i in range(nv)]].to_numpy()
    v = ts[[f"v{i + 1}" for i in range(nv)]].to_numpy()
    lower, upper = np.asarray(q_lower, float), np.asarray(q_upper, float)
    half_range = (upper - lower) / 2
    ranged = np.isfinite(half_range)  # an unlimited joint has no middle (no inf − inf)
    mid = np.zeros_like(half_range)
    mid[ranged] = (upper[ranged] + lower[ranged]) / 2
    pos_pct, pos_joint = _max_pct(np.abs(q - mid), half_range)
    vel_pct, vel_joint = _max_pct(np.abs(v), np.asarray(velocity_limits, dtype=float))

    pos_err = ts[POSITION].to_numpy() - ts[POSITION_REF].to_numpy()
    lateral = pos_err - np.outer(pos_err @ axis, axis)
    ori_norm = np.linalg.norm(ts[ORI_ERROR].to_numpy(), axis=1)
    approach = approach_rows(ts)

    values = dict(
        peak_axial_force_N=np.max(np.abs(axial)),
        filtered_peak_axial_force_N=filtered_peak(axial, t, force_window),
        peak_wrench_norm_N=np.max(wrench_norm),
        steady_axial_force_N=np.mean(axial[steady]),
        steady_wrench_norm_N=np.mean(wrench_norm[steady]),
        max_joint_pos_pct=pos_pct,
        max_joint_vel_pct=vel_pct,
        min_manipulability=None if manipulability is None else np.min(manipulability),
        pos_tracking_rms_m=np.sqrt(np.mean(ts["pos_error"].to_numpy() ** 2)),
        ori_tracking_rms_rad=np.sqrt(np.mean(ori_norm**2)),
        approach_pos_rms_m=_rms(ts["pos_error"].to_numpy()[approach]),
        approach_ori_rms_rad=_rms(ori_norm[approach]),
        press_depth_m=-np.mean((pos_err @ axis)[steady]),
        final_lateral_error_m=np.mean(np.linalg.norm(lateral, axis=1)[steady]),
        final_orientation_error_rad=np.mean(ori_norm[steady]),
        max_joint_pos_joint=pos_joint,
        max_joint_vel_joint=vel_joint,
    )
    assert set(values) == set(DOCKING_KEYS), "compute_metrics and the registry disagree"
    return {k: finite_or_none(values[k]) for k in DOCKING_KEYS}


def approach_rows(ts: pd.DataFrame) -> np.ndarray:
    """The rows of the motion before the plug first touched anything: those before the first
    contact's state (``first_contact_time_s``, :func:`~compliant_docking.evaluation.contact.first_contact_state`),
    every row when nothing touched (free space, or no ``contacts`` column)."""
    n = len(ts)
    state = first_contact_state(ts["contacts"].to_numpy()) if "contacts" in ts else None
    return np.arange(n) < (n if state is None else state)


def _rms(values: np.ndarray) -> float | None:
    """Root mean square; None for no values."""
    return float(np.sqrt(np.mean(values**2))) if values.size else None


def filtered_peak(force: np.ndarray, t: np.ndarray, window: float) -> float:
    """The largest |mean of ``force`` over ``window`` seconds| along the series: the peak a
    sensor averaging over the window would read (n = round(window / dt) consecutive
    samples, every full window; the whole series if it is shorter).

    Why: in a soft-contact simulation an impact's per-step peak is the momentum it stops
    divided by the contact's time constant (solref), a solver setting, while the mean
    over a window longer than the impact is that momentum over the window: the same for
    any time constant shorter than the window (docs/contact.md). Held forces are
    unchanged by the mean.
    """
    force = np.asarray(force, dtype=float)
    if force.size == 0:
        return float("nan")
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    n = min(max(int(round(window / dt)), 1), force.size)
    sums = np.cumsum(np.r_[0.0, force])
    return float(np.max(np.abs(sums[n:] - sums[:-n])) / n)


def _max_pct(values: np.ndarray, limits: np.ndarray) -> tuple[float | None, int | None]:
    """Largest values/limit in % over joints with a finite positive limit, and its joint."""
    valid = np.isfinite(limits) & (limits > 0.0)
    if not valid.any() or values.size == 0:
        return None, None
    pct = np.where(valid, values / np.where(valid, limits, 1.0), -np.inf) * 100.0
    peak_per_joint = pct.max(axis=0)
    joint = int(np.argmax(peak_per_joint))
    return float(peak_per_joint[joint]), joint


def manipulability_series(arm, q: np.ndarray) -> np.ndarray:
    """√det(J Jᵀ) of the TCP's world Jacobian at each row of q.

    The Jacobians step by step (Pinocchio), the products and determinants batched (the
    same LAPACK call per matrix, so the same numbers as one step at a time).
    """
    data = arm.model.createData()
    jacobians = np.empty((len(q), 6, arm.nv))
    jacobian = arm.world_jacobian
    for k, qk in enumerate(q):
        jacobians[k] = jacobian(qk, data)
    gram = np.matmul(jacobians, jacobians.transpose(0, 2, 1))
    return np.sqrt(np.maximum(np.linalg.det(gram), 0.0)) if len(q) else np.empty(0)


# --------------------------------------------------------------------------- docking gate
@dataclass(frozen=True)
class SeatState:
    """The plug tip relative to the TRUE socket seat, over the steady window (maxima)."""

    depth_error_m: float | None  # |axial distance tip ↔ seat|
    lateral_error_m: float | None  # distance of the tip from the socket axis
    tilt_deg: float | None  # angle between plug axis and socket axis
    seated_time_s: float | None  # first time the tip came within depth tolerance of the seat
    key_yaw_deg: float | None = None  # roll error against the socket's key (None: round interface)
    docking_time_s: float | None = None  # :func:`docking_row`'s time (None: never docked)
    docking_time_after_contact_s: float | None = None  # the same, from the first contact


#: added to a key's yaw play to make the default key-yaw tolerance of the gate [deg]
KEY_YAW_MARGIN_DEG = 0.1


def seat_state(
    ts: pd.DataFrame,
    seat: pin.SE3,
    steady_window: float,
    depth_tolerance: float,
    key: Key = ROUND,
    lateral_tolerance: float | None = None,
) -> SeatState:
    """Where the plug ended up, measured on the physics' (true) socket pose; for a keyed
    interface also the roll error against the socket's key (:meth:`Key.yaw_error_deg`);
    with ``lateral_tolerance`` (and a ``contacts`` column) the docking time
    (:func:`docking_row`)."""
    if ts.empty:
        return SeatState(None, None, None, None)
    t = ts["t"].to_numpy()
    steady = steady_mask(t, steady_window)
    rel = (ts[POSITION].to_numpy() - seat.translation) @ seat.rotation  # seat frame
    quat = ts[QUATERNION].to_numpy()
    plug_axis = _quat_z_axis(quat)
    # inserted plug: its +z is the socket's −z
    cos_tilt = np.clip(-(plug_axis @ seat.rotation[:, 2]), -1.0, 1.0)
    tilt = np.degrees(np.arccos(cos_tilt))
    depth = np.abs(rel[:, 2])
    lateral = np.linalg.norm(rel[:, :2], axis=1)
    seated = np.flatnonzero(depth <= depth_tolerance)
    docked = None
    if lateral_tolerance is not None and "contacts" in ts:
        contact = first_contact_state(ts["contacts"].to_numpy())
        inside = (depth <= depth_tolerance) & (lateral <= lateral_tolerance)
        docked = docking_row(inside, contact)
    return SeatState(
        depth_error_m=finite_or_none(depth[steady].max()),
        lateral_error_m=finite_or_none(lateral[steady].max()),
        tilt_deg=finite_or_none(tilt[steady].max()),
        seated_time_s=float(t[seated[0]]) if seated.size else None,
        key_yaw_deg=_key_yaw(quat[steady], seat.rotation, key),
        docking_time_s=None if docked is None else float(t[docked]),
        docking_time_after_contact_s=None if docked is None else float(t[docked] - t[contact]),
    )


def docking_row(seated: np.ndarray, first_contact: int | None) -> int | None:
    """The row at which the plug docked: the first row, at or after the first contact's
    state row, from which it is ``seated`` on every row to the end of the series. None
    when it never touched or is not seated on the last row.

    Why these parts: from the first contact, because a plug that has touched nothing rests
    on nothing (a plug carried to the seat without touching is the planner's arrival, not a
    docking); to the end, because a plug that leaves the seat again had not docked when it
    first got there.
    """
    seated = np.asarray(seated, dtype=bool)
    if first_contact is None or not seated.size or not seated[-1]:
        return None
    outside = np.flatnonzero(~seated)
    stays_from = int(outside[-1]) + 1 if outside.size else 0
    return max(stays_from, first_contact)


def _key_yaw(quat_wxyz: np.ndarray, seat: np.ndarray, key: Key) -> float | None:
    if not key.keyed or not len(quat_wxyz):
        return None
    return finite_or_none(key.yaw_error_deg(seat, _quat_matrices(quat_wxyz)).max())


def key_yaw_limit(gate, key: Key) -> float | None:
    """The gate's key-yaw tolerance [deg]: ``gate.key_yaw_tolerance_deg`` if set, else the
    key's yaw play + :data:`KEY_YAW_MARGIN_DEG` (a seated plug cannot turn further), else
    None (not checked: a round interface, or a key that declares no play)."""
    if not key.keyed:
        return None
    tolerance = getattr(gate, "key_yaw_tolerance_deg", None)
    if tolerance is not None:
        return float(tolerance)
    return None if key.yaw_play_deg is None else key.yaw_play_deg + KEY_YAW_MARGIN_DEG


def _quat_matrices(quat_wxyz: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of unit wxyz quaternions."""
    w, x, y, z = np.asarray(quat_wxyz, dtype=float).T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


def _quat_z_axis(quat_wxyz: np.ndarray) -> np.ndarray:
    """Third column of the rotation matrix of each wxyz quaternion."""
    w, x, y, z = quat_wxyz.T
    return np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=1)


def docking_gate(
    seat: SeatState,
    metrics: DockingMetrics,
    gate,
    key_yaw_limit_deg: float | None = None,
    contact: ContactMetrics | None = None,
) -> list[str]:
    """Failing items of the docking gate (empty: success), each saying what failed.

    ``key_yaw_limit_deg`` (:func:`key_yaw_limit`): also check the roll against the key.

    Missing or non-finite values fail. With ``contact`` (the runner always passes it) the
    steady hold must also be calm: at most ``gate.max_contact_events_per_s`` contact
    make/break events per second and a force standard deviation of at most
    max(``gate.max_force_std_N``, ``gate.max_force_std_ratio`` × mean |F|), so a plug
    bouncing on its seat is never reported as docked.
    """
    window = "over the steady window"
    checks: list[tuple[str, float | None, float, Callable[[float, float], str]]] = [
        (
            "seat depth error",
            seat.depth_error_m,
            gate.depth_tolerance_m,
            lambda v, lim: (
                f"not seated: tip up to {v * 1e3:.3g} mm from the seat {window} (tolerance {lim * 1e3:g} mm)"
            ),
        ),
        (
            "seat lateral error",
            seat.lateral_error_m,
            gate.lateral_tolerance_m,
            lambda v, lim: (
                f"off the axis: tip up to {v * 1e3:.3g} mm from the socket axis {window} "
                f"(tolerance {lim * 1e3:g} mm)"
            ),
        ),
        (
            "plug tilt",
            seat.tilt_deg,
            gate.tilt_tolerance_deg,
            lambda v, lim: f"tilted: plug up to {v:.3g}° off the socket axis (tolerance {lim:g}°)",
        ),
        (
            "peak axial force",
            metrics["filtered_peak_axial_force_N"],
            gate.peak_force_budget_N,
            lambda v, lim: f"peak force {v:.3g} N (filtered) over the {lim:g} N budget",
        ),
    ]
    if contact is not None:
        checks.append(
            (
                "steady contact events",
                contact["steady_contact_events_per_s"],
                gate.max_contact_events_per_s,
                lambda v, lim: f"contact chatter: {v:.3g} make/break events/s {window} (limit {lim:g}/s)",
            )
        )
        mean = contact["steady_force_mean_N"]
        spread = (
            max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean)
            if mean is not None
            else 0.0
        )
        checks.append(
            (
                "steady force spread",
                contact["steady_force_std_N"] if mean is not None else None,
                spread,
                lambda v, lim: (
                    f"unsteady hold: |F| {mean:.3g} ± {v:.3g} N {window} (std limit {lim:.3g} N "
                    f"= max({gate.max_force_std_N:g} N, {gate.max_force_std_ratio:.0%} of the mean))"
                ),
            )
        )
    failures = []
    for label, value, limit, message in checks:
        if value is None or not np.isfinite(value):  # fail closed
            failures.append(f"{label} not available (non-finite or no data)")
        elif value > limit:
            failures.append(message(value, limit))
    if key_yaw_limit_deg is not None:
        if seat.key_yaw_deg is None or not np.isfinite(seat.key_yaw_deg):  # fail closed
            failures.append("key yaw not available (non-finite or no data)")
        elif seat.key_yaw_deg > key_yaw_limit_deg:
            failures.append(
                f"key yaw {seat.key_yaw_deg:.4g} deg > {key_yaw_limit_deg:.3g} deg: the plug's key "
                "is not lined up with the socket's, so it cannot enter the bore"
            )
    return failures


def docking_verdict(seat: SeatState, gate, failures: list[str]) -> str:
    """One line for the console: "docked", or what failed, led by whether the plug is seated
    (e.g. "seated; peak force 63.6 N (filtered) over the 50 N budget")."""
    if not failures:
        return "docked"
    seated = (
        seat.depth_error_m is not None
        and seat.depth_error_m <= gate.depth_tolerance_m
        and seat.lateral_error_m is not None
        and seat.lateral_error_m <= gate.lateral_tolerance_m
    )
    return ("seated; " if seated else "not docked: ") + "; ".join(failures)
