"""The docking time, the tracking before contact and the press depth, pinned part by part.

Definitions (docs/run_directory.md):

- ``docking_time_s``: the time of the first row, at or after the first contact's state row,
  from which the tip is within the gate's depth tolerance of the seat (along the TRUE
  socket axis) and within its lateral tolerance of that axis on every row to the end;
  null when the plug never touched or is not within both on the last row.
  ``docking_time_after_contact_s`` is that time minus ``first_contact_time_s``.
- the first contact's state row: the row before the first with ``contacts`` > 0 (row 0
  when that is the first).
- ``approach_pos_rms_m`` / ``approach_ori_rms_rad``: RMS over the rows before that state
  row (every row without contact; null when there is none).
- ``press_depth_m``: mean over the steady window of (x_ref − x)·axis.

Each test builds a series whose answer follows from these sentences by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest

from compliant_docking.evaluation.contact import contact_metrics, first_contact_state
from compliant_docking.evaluation.docking import approach_rows, compute_metrics, docking_row, seat_state
from compliant_docking.sim.telemetry import (
    FORCE,
    MOMENT,
    ORI_ERROR,
    POSITION,
    POSITION_REF,
    QUATERNION,
    TWIST,
)

T, F = True, False


# --------------------------------------------------------------------------- docking_row
@pytest.mark.parametrize(
    ("seated", "contact", "row"),
    [
        ([F, F, T, T, T], 0, 2),  # seated from row 2 on, touched from the start
        ([F, F, T, T, T], 3, 3),  # in place before touching: docks at the first contact
        ([F, F, T, T, T], 4, 4),  # a first contact on the last row: that row
        ([T, T, T, T, T], 0, 0),  # in place and touching from row 0
        ([F, F, F, F, T], 1, 4),  # seated on the last row only: the last row
        ([F, T, T, F, T, T], 0, 4),  # seated, leaves, comes back: the return counts
        ([F, T, T, F, T, T], 5, 5),  # ... and the first contact still bounds it
    ],
)
def test_docking_row_is_the_first_row_from_contact_that_stays_seated(seated, contact, row):
    assert docking_row(np.array(seated), contact) == row


@pytest.mark.parametrize(
    ("seated", "contact"),
    [
        ([F, F, F, F], 0),  # never seated
        ([F, T, T, F], 0),  # seated, then left for good: not docked at the end
        ([T, T, T, T], None),  # in place but never touched anything: the planner's arrival
        ([], 0),  # no rows
    ],
)
def test_docking_row_is_none_when_never_docked(seated, contact):
    assert docking_row(np.array(seated, dtype=bool), contact) is None


def test_the_first_contact_state_is_the_row_before_the_first_contact_row():
    """The contacts of row k come from the step taken from row k − 1's state."""
    assert first_contact_state(np.array([0, 0, 0, 1, 1])) == 2
    assert first_contact_state(np.array([0, 2, 0, 0])) == 0
    assert first_contact_state(np.array([3, 3])) == 0  # touching on row 0: row 0, not −1
    assert first_contact_state(np.array([0, 0, 0])) is None


# --------------------------------------------------------------------------- seat_state
#: an oblique true seat: a tolerance read in world axes, or depth and lateral swapped, gives
#: other rows
SEAT = pin.SE3(pin.exp3(np.array([0.3, -0.5, 0.2])), np.array([0.5, 0.1, 0.2]))
DT = 0.01
DEPTH_TOL, LATERAL_TOL = 1e-3, 0.5e-3


def tip_series(
    rel_mm: list[tuple[float, float, float]], contacts: list[int], seat: pin.SE3 = SEAT
) -> pd.DataFrame:
    """The tip at ``rel_mm`` (seat frame, mm) row by row, plug upright in the socket, at rest."""
    rel = np.array(rel_mm) * 1e-3
    pos = seat.translation + rel @ seat.rotation.T
    flip = pin.exp3(np.array([math.pi, 0.0, 0.0]))  # inserted: the plug's +z along the socket's −z
    quat = np.roll(pin.Quaternion(seat.rotation @ flip).coeffs(), 1)
    n = len(rel)
    cols = {"t": np.arange(n) * DT, **{c: pos[:, i] for i, c in enumerate(POSITION)}}
    cols.update({c: np.full(n, quat[i]) for i, c in enumerate(QUATERNION)})
    cols.update({c: np.zeros(n) for c in (*FORCE, *TWIST)})
    cols["contacts"] = np.array(contacts)
    return pd.DataFrame(cols)


def docking_times(ts: pd.DataFrame, seat: pin.SE3 = SEAT) -> tuple[float | None, float | None]:
    state = seat_state(ts, seat, 0.02, DEPTH_TOL, lateral_tolerance=LATERAL_TOL)
    return state.docking_time_s, state.docking_time_after_contact_s


def test_seat_state_docking_time_in_the_true_seat_frame():
    """Row 0 far above, row 1 in place but not touching, row 2's contacts make row 1 the first
    contact's state (t = 0.01 s); rows 3 and 4 within both tolerances, row 2 0.6 mm off the
    axis (over the 0.5 mm lateral tolerance, within the 1 mm depth one): docked at row 3,
    t = 0.03 s, 0.02 s after the first contact."""
    ts = tip_series(
        [(0, 0, 20), (0.1, 0, 0.5), (0.6, 0, 0.2), (0, 0.4, -0.9), (0.3, 0.3, 0.1)], [0, 0, 1, 1, 1]
    )
    docked, after = docking_times(ts)
    assert docked == pytest.approx(0.03, abs=1e-12)
    assert after == pytest.approx(0.02, abs=1e-12)
    contact = contact_metrics(ts, SEAT, steady_window=0.02, strike_window=0.1)
    assert after == pytest.approx(docked - contact["first_contact_time_s"], abs=1e-12)


def test_the_tolerances_are_inclusive_and_both_count():
    """Exactly on the tolerances counts as seated (≤; the seat at the origin, so no round-off
    moves the tip); 1.1 mm deep or 0.55 mm off the axis does not, whichever the other is."""
    origin = pin.SE3.Identity()
    on_edge = tip_series([(0.5, 0, 1.0), (0, 0.5, -1.0)], [1, 1], origin)
    assert docking_times(on_edge, origin) == (0.0, 0.0)
    too_deep = tip_series([(0, 0, 0)] * 2 + [(0, 0, -1.1)], [1, 1, 1])
    off_axis = tip_series([(0, 0, 0)] * 2 + [(0, 0.55, 0)], [1, 1, 1])
    assert docking_times(too_deep) == (None, None)
    assert docking_times(off_axis) == (None, None)


def test_in_place_before_contact_docks_at_the_first_contact():
    """The plug carried into place without touching (the default run: the planner arrives at
    the seat, the press makes the first contact later): the docking time is the contact's."""
    ts = tip_series([(0, 0, 0.2)] * 6, [0, 0, 0, 0, 1, 1])
    assert docking_times(ts) == (pytest.approx(0.03, abs=1e-12), 0.0)
    assert seat_state(ts, SEAT, 0.02, DEPTH_TOL).seated_time_s == 0.0  # the old key: the arrival


def test_without_a_lateral_tolerance_or_contacts_there_is_no_docking_time():
    ts = tip_series([(0, 0, 0)] * 3, [1, 1, 1])
    assert seat_state(ts, SEAT, 0.02, DEPTH_TOL).docking_time_s is None
    assert docking_times(ts.drop(columns="contacts")) == (None, None)
    assert docking_times(tip_series([(0, 0, 0)] * 3, [0, 0, 0])) == (None, None)


# --------------------------------------------------------------------------- approach, press
AXIS = np.array([0.0, 0.6, -0.8])  # the docking axis (unit)
PERP = np.array([1.0, 0.0, 0.0])


def motion_series(contact_from: int | None, n: int = 10) -> pd.DataFrame:
    """Position error 1 mm (even rows) / 3 mm (odd rows) across the axis up to row 5, then
    the tip 5 mm short of the reference along the axis plus 2 mm across; orientation error
    0.2 rad on rows 0–5, 0 after; ``contacts`` > 0 from ``contact_from``."""
    k = np.arange(n)
    err = np.outer(np.where(k % 2 == 0, 1e-3, 3e-3), PERP)
    err[k > 5] = -5e-3 * AXIS + 2e-3 * PERP
    ref = np.array([0.4, 0.0, 0.3]) + np.outer(k * 0.01, AXIS)
    ori = np.outer(np.where(k <= 5, 0.2, 0.0), [0.0, 0.6, 0.8])
    cols: dict = {"t": k * 0.1, "q1": np.zeros(n), "v1": np.zeros(n)}
    for block, names in ((ref + err, POSITION), (ref, POSITION_REF), (np.zeros((n, 3)), FORCE)):
        cols.update({c: block[:, i] for i, c in enumerate(names)})
    cols.update({c: np.zeros(n) for c in MOMENT})
    cols.update({c: ori[:, i] for i, c in enumerate(ORI_ERROR)})
    cols["pos_error"] = np.linalg.norm(err, axis=1)
    cols["contacts"] = np.zeros(n, int) if contact_from is None else np.where(k >= contact_from, 1, 0)
    return pd.DataFrame(cols)


def motion_metrics(ts: pd.DataFrame, steady_window: float = 0.25) -> dict:
    return compute_metrics(ts, axis=AXIS * 3.0, q_lower=np.array([-1.0]), q_upper=np.array([1.0]),
                           velocity_limits=np.array([1.0]), manipulability=None,
                           steady_window=steady_window, force_window=0.1)  # fmt: skip


def test_the_approach_is_the_rows_before_the_first_contact_state():
    """Contacts from row 5: the state is row 4, the approach rows 0–3 (1, 3, 1, 3 mm: RMS
    √5 mm, mean 2 mm; with row 4: √(21/5) mm)."""
    assert approach_rows(motion_series(5)).tolist() == [T, T, T, T] + [F] * 6
    m = motion_metrics(motion_series(5))
    assert m["approach_pos_rms_m"] == pytest.approx(math.sqrt(5.0) * 1e-3, rel=1e-12)
    assert m["approach_ori_rms_rad"] == pytest.approx(0.2, rel=1e-12)


def test_without_contact_the_approach_is_the_whole_run_and_at_row_zero_it_is_empty():
    """No contact: every row (position 1/3 mm on rows 0–5, √29 mm on 6–9: RMS
    √((5·6 + 29·4)/10) = √14.6 mm; orientation √(0.04·6/10)); a contact on row 0 or 1 (state
    row 0): no rows before it, null."""
    m = motion_metrics(motion_series(None))
    assert m["approach_pos_rms_m"] == pytest.approx(math.sqrt(14.6) * 1e-3, rel=1e-12)
    assert m["approach_ori_rms_rad"] == pytest.approx(math.sqrt(0.024), rel=1e-12)
    for first in (0, 1):
        m = motion_metrics(motion_series(first))
        assert m["approach_pos_rms_m"] is None and m["approach_ori_rms_rad"] is None


def test_press_depth_is_the_reference_past_the_tip_along_the_axis_over_the_steady_window():
    """Steady rows 7–9 (t ≥ 0.65 s): the tip 5 mm short of the reference along the axis, 2 mm
    across (not counted): +5 mm. Tip past the reference: −5 mm. A window reaching row 5
    (t ≥ 0.45 s: rows 5–9, one of them 0 along the axis): 4 mm."""
    ts = motion_series(3)
    assert motion_metrics(ts)["press_depth_m"] == pytest.approx(5e-3, rel=1e-12)
    assert motion_metrics(ts, steady_window=0.45)["press_depth_m"] == pytest.approx(4e-3, rel=1e-12)
    past = ts.copy()
    past[POSITION] = 2 * ts[POSITION_REF].to_numpy() - ts[POSITION].to_numpy()
    assert motion_metrics(past)["press_depth_m"] == pytest.approx(-5e-3, rel=1e-12)
