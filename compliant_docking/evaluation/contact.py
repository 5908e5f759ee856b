"""What the contact did: first contact, the first strike, and how calm the held
contact is over the steady window. Definitions in docs/run_directory.md ("contact").

Rows of the time series: the ``contacts`` and wrench columns of row k come from the physics
step taken from row k−1's state (one step late, as the controller saw them); the first
contact's pose and speed are therefore read on row k−1, the state in which MuJoCo first
found the plug touching the socket, and its time is that row's.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pinocchio as pin

from compliant_docking.evaluation.registry import CONTACT_KEYS, finite_or_none
from compliant_docking.sim.telemetry import FORCE, POSITION, TWIST

#: the values of :func:`contact_metrics` (registry keys of the "contact" section), None =
#: cannot be computed (no contact, too short a series)
ContactMetrics = dict[str, float | None]


def first_contact_index(contacts: np.ndarray) -> int | None:
    """Row of the first step reporting a contact (contacts > 0), or None."""
    touching = np.flatnonzero(np.asarray(contacts) > 0)
    return int(touching[0]) if touching.size else None


def first_contact_state(contacts: np.ndarray) -> int | None:
    """Row of the first state in which MuJoCo found the plug touching: the row before the
    first with contacts > 0 (its contacts come from the step taken from that state), row 0
    when that is the first; None without contact. ``first_contact_time_s`` is its time."""
    first = first_contact_index(contacts)
    return None if first is None else max(first - 1, 0)


def strike_end(contacts: np.ndarray, start: int, max_rows: int) -> int:
    """End (exclusive) of the first strike starting at row ``start``: the first row without
    contact after it, or ``start + max_rows``, or the end of the series, whichever is first."""
    contacts = np.asarray(contacts)
    stop = min(start + max(int(max_rows), 1), len(contacts))
    free = np.flatnonzero(contacts[start:stop] <= 0)
    return start + int(free[0]) if free.size else stop


def strike_peak(axial: np.ndarray, contacts: np.ndarray, max_rows: int) -> float | None:
    """Peak axial force [N] of the first strike: from the first contact until the contact
    first opens again or ``max_rows`` rows have passed (the fixed cap keeps a plug that
    slides on from the funnel to the seat from counting its later seating as the strike)."""
    start = first_contact_index(contacts)
    if start is None:
        return None
    return float(np.max(np.asarray(axial)[start : strike_end(contacts, start, max_rows)]))


def make_break_events(contacts: np.ndarray) -> int:
    """Number of changes between touching (contacts > 0) and not touching along the series."""
    touching = (np.asarray(contacts) > 0).astype(np.int8)
    return int(np.count_nonzero(np.diff(touching)))


def contact_metrics(
    ts: pd.DataFrame, seat: pin.SE3, *, steady_window: float, strike_window: float
) -> ContactMetrics:
    """Contact metrics of a run's time series, keyed as in the registry (``CONTACT_KEYS``).

    ``seat``: the TRUE socket pose (origin at the seat, +z out of the socket);
    ``steady_window``: the last seconds of the run that count as the hold;
    ``strike_window``: the cap of the first strike [s].
    """
    values: dict = dict.fromkeys(CONTACT_KEYS)
    if ts.empty:
        return values
    t = ts["t"].to_numpy()
    contacts = ts["contacts"].to_numpy()
    force = ts[FORCE].to_numpy()
    steady = t >= t[-1] - steady_window
    magnitude = np.linalg.norm(force[steady], axis=1)
    span = t[steady][-1] - t[steady][0] if steady.sum() > 1 else 0.0
    dt = float(t[1] - t[0]) if len(t) > 1 else 0.0
    values.update(
        steady_force_mean_N=magnitude.mean() if magnitude.size else None,
        steady_force_std_N=magnitude.std(ddof=1) if magnitude.size > 1 else None,
        # transitions between the window's rows, over the time those rows span
        steady_contact_events_per_s=make_break_events(contacts[steady]) / span if span > 0 else None,
    )
    state = first_contact_state(contacts)
    if state is not None:
        insertion = -seat.rotation[:, 2]  # into the socket
        axial = -(force @ insertion)
        max_rows = max(int(round(strike_window / dt)), 1) if dt > 0 else 1
        rel = (ts[POSITION].to_numpy()[state] - seat.translation) @ seat.rotation
        velocity = ts[TWIST[:3]].to_numpy()[state]
        values.update(
            first_contact_time_s=t[state],
            first_strike_force_N=strike_peak(axial, contacts, max_rows),
            first_contact_lateral_offset_m=np.hypot(rel[0], rel[1]),
            first_contact_speed_m_s=velocity @ insertion,
        )
    assert set(values) == set(CONTACT_KEYS), "contact_metrics and the registry disagree"
    return {k: finite_or_none(values[k]) for k in CONTACT_KEYS}
