"""Contact metrics on synthetic time series (first contact, first strike, make/break events),
and the docking gate's calm-hold items and failure reasons."""

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest

from compliant_docking.config.schemas import DockingGateConfig
from compliant_docking.evaluation import registry
from compliant_docking.evaluation.contact import (
    contact_metrics,
    first_contact_index,
    make_break_events,
    strike_end,
    strike_peak,
)
from compliant_docking.evaluation.docking import SeatState, docking_gate, docking_verdict

SEAT = pin.SE3.Identity()  # the socket frame: origin at the seat, +z out of the socket


def synthetic_run(dt=0.001, duration=4.0):
    """A plug that touches at t = 1.000 s (first contact row 1000) with a 30 N strike over
    5 ms, opens at 1.020 s, lands again at 1.5 s and is then held at 2 N; 1 mm off the
    socket axis (x), arriving at 10 mm/s along −z (the socket's +z is up)."""
    t = np.arange(int(round(duration / dt))) * dt
    n = len(t)
    contacts = np.zeros(n, dtype=int)
    fz = np.zeros(n)  # force ON the tool: +z pushes the plug out of the socket
    contacts[1000:1020] = 2
    fz[1000:1005] = [5.0, 30.0, 20.0, 10.0, 4.0]
    fz[1005:1020] = 3.0
    contacts[1500:] = 3
    fz[1500:] = 2.0
    frame = {
        "t": t,
        "x": np.full(n, 0.001),
        "y": np.zeros(n),
        "z": np.zeros(n),
        "vx": np.zeros(n),
        "vy": np.zeros(n),
        "vz": np.full(n, -0.010),
        "fx": np.zeros(n),
        "fy": np.zeros(n),
        "fz": fz,
        "contacts": contacts,
    }
    return pd.DataFrame(frame)


def test_first_contact_strike_and_make_break_on_a_synthetic_series():
    ts = synthetic_run()
    assert first_contact_index(ts["contacts"].to_numpy()) == 1000
    assert first_contact_index(np.zeros(10)) is None
    assert make_break_events(ts["contacts"].to_numpy()) == 3  # make, break, make
    c = contact_metrics(ts, SEAT, steady_window=2.0, strike_window=0.1)
    assert set(c) == set(registry.CONTACT_KEYS)
    assert c["first_contact_time_s"] == pytest.approx(0.999)  # the state before row 1000
    assert c["first_strike_force_N"] == pytest.approx(30.0)  # the strike's peak, not the hold
    assert c["first_contact_lateral_offset_m"] == pytest.approx(0.001)
    assert c["first_contact_speed_m_s"] == pytest.approx(0.010)  # into the socket: positive
    assert c["steady_contact_events_per_s"] == 0.0
    assert c["steady_force_mean_N"] == pytest.approx(2.0) and c["steady_force_std_N"] == pytest.approx(0.0)


def test_no_contact_gives_no_first_contact_but_a_steady_window():
    ts = synthetic_run()
    ts["contacts"] = 0
    ts["fz"] = 0.0
    c = contact_metrics(ts, SEAT, steady_window=2.0, strike_window=0.1)
    assert c["first_contact_time_s"] is None and c["first_strike_force_N"] is None
    assert c["steady_contact_events_per_s"] == 0.0 and c["steady_force_mean_N"] == 0.0
    assert all(
        v is None for v in contact_metrics(ts.iloc[:0], SEAT, steady_window=2.0, strike_window=0.1).values()
    )


def test_strike_window_ends_at_the_first_opening_or_at_its_cap():
    contacts = np.array([0, 1, 1, 1, 0, 1, 1, 1, 1, 1])
    axial = np.array([0, 1, 5, 2, 0, 9, 9, 9, 9, 9], dtype=float)
    assert strike_end(contacts, 1, 100) == 4  # opens at row 4
    assert strike_peak(axial, contacts, 100) == 5.0  # the later 9 N is not the first strike
    held = np.array([0, 1, 1, 1, 1, 1, 1, 1])
    rising = np.arange(8, dtype=float)
    assert strike_end(held, 1, 3) == 4  # never opens: capped after 3 rows
    assert strike_peak(rising, held, 3) == 3.0
    assert strike_peak(rising, np.zeros(8), 3) is None  # no contact, no strike


def test_chatter_counts_make_and_break_per_second():
    ts = synthetic_run()
    # the held contact bounces: open every other row over the last second
    last = ts.index[-1000:]
    ts.loc[last[::2], "contacts"] = 0
    ts.loc[last[::2], "fz"] = 0.0
    c = contact_metrics(ts, SEAT, steady_window=2.0, strike_window=0.1)
    # 999 transitions in the last second, over a 2 s window
    assert c["steady_contact_events_per_s"] == pytest.approx(1000 / 2.0, abs=1.0)
    assert c["steady_force_std_N"] > 0.5


# --------------------------------------------------------------------------- definitions
# One test per part of the definitions in docs/run_directory.md ("contact"), each on a
# series whose answer is computed by hand; benchmarks/mutation_score.py (K*) changes each
# part and checks that one of these tests fails.

COLUMNS = ("t", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz", "fx", "fy", "fz", "contacts")


def series(t, **columns) -> pd.DataFrame:
    """A time series at times ``t`` with the given columns, every other one zero."""
    t = np.asarray(t, dtype=float)
    return pd.DataFrame(
        {c: np.asarray(columns.get(c, np.zeros(len(t))), dtype=float) for c in COLUMNS} | {"t": t}
    )


def rotation(yaw_deg: float, tilt_deg: float) -> np.ndarray:
    """Rz(yaw) · Rx(tilt)."""
    cy, sy = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    ct, st = np.cos(np.radians(tilt_deg)), np.sin(np.radians(tilt_deg))
    return np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, ct, -st], [0.0, st, ct]]
    )


def test_first_contact_is_the_state_before_the_first_touching_row_in_the_true_seat_frame():
    """A TRUE seat turned 30° and tilted 20° (R = Rz·Rx), at p0; in its frame the tip moves
    as r(t) = r0 + v0 t + ½ a t² with r0 = (3, −4, 50) mm, v0 = (10, 20, −100) mm/s,
    a = (0, 0, −1) m/s², and spins at ω = (3, −2, 5) rad/s (world). Rows every 10 ms; the
    first row with contacts > 0 is row 8, so the first contact is the state of row 7
    (t = 70 ms): lateral offset √(x² + y²) of r(0.07) = √(3.7² + 2.6²) mm (not its height,
    not in world axes), speed along the insertion axis −z_seat: −v_z(0.07) = 0.17 m/s.
    The socket pushes the plug out along +z_seat with s = 0 … 12 N: the axial force is
    f·z_seat = s, whatever the lateral components, and the strike's peak is 12 N."""
    dt, n, first = 0.01, 20, 8
    R, p0 = rotation(30.0, 20.0), np.array([0.4, -0.1, 0.3])
    seat = pin.SE3(R, p0)
    t = np.arange(n) * dt
    r0, v0, a = np.array([0.003, -0.004, 0.05]), np.array([0.01, 0.02, -0.1]), np.array([0.0, 0.0, -1.0])
    r = r0 + np.outer(t, v0) + 0.5 * np.outer(t**2, a)  # seat frame
    v = v0 + np.outer(t, a)
    contacts = (np.arange(n) >= first).astype(float)
    push = np.zeros(n)
    push[first:] = [3.0, 7.0, 12.0, 9.0, 4.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0]
    f_seat = np.column_stack([2.0 * contacts, -1.0 * contacts, push])  # force on the tool
    world = {
        **dict(zip(("x", "y", "z"), (p0 + r @ R.T).T)),
        **dict(zip(("vx", "vy", "vz"), (v @ R.T).T)),
        **dict(zip(("wx", "wy", "wz"), np.tile([3.0, -2.0, 5.0], (n, 1)).T)),
        **dict(zip(("fx", "fy", "fz"), (f_seat @ R.T).T)),
    }
    c = contact_metrics(series(t, **world, contacts=contacts), seat, steady_window=0.05, strike_window=1.0)
    assert c["first_contact_time_s"] == pytest.approx(0.07, abs=1e-12)
    assert c["first_contact_lateral_offset_m"] == pytest.approx(np.hypot(0.0037, 0.0026), rel=1e-9)
    assert c["first_contact_speed_m_s"] == pytest.approx(0.17, rel=1e-9)
    assert c["first_strike_force_N"] == pytest.approx(12.0, rel=1e-9)


def test_first_contact_on_the_first_row_is_read_on_that_row():
    """Touching from row 0: there is no earlier state, so row 0 is the first contact's
    state (time 0, its pose and its speed), not the last row."""
    t = np.arange(5) * 0.1
    ts = series(t, x=[0.002, 0.5, 0.5, 0.5, 0.5], vz=[-0.02, 1.0, 1.0, 1.0, 1.0], contacts=np.ones(5))
    c = contact_metrics(ts, SEAT, steady_window=0.1, strike_window=0.1)
    assert c["first_contact_time_s"] == 0.0
    assert c["first_contact_lateral_offset_m"] == pytest.approx(0.002)
    assert c["first_contact_speed_m_s"] == pytest.approx(0.02)


def test_the_strike_includes_its_first_row_and_not_the_row_where_it_opened():
    """Rows k (first contact) … until the first row without contact, exclusive: an impact
    peaking on its first row (9 N) is that peak; the reading of the row where the contact
    opened (7 N, the sensor's inertia on the rebound) is not part of the strike (6 N);
    the peak is the largest push, not the largest |axial| (a −8 N pull reading is not it);
    and the strike counts rows with contacts > 0, so one contact is touching."""
    assert strike_peak(np.array([0.0, 9.0, 5.0, 2.0, 0.0]), np.array([0, 1, 1, 1, 0]), 100) == 9.0
    assert strike_peak(np.array([0.0, 4.0, 6.0, 7.0, 0.0]), np.array([0, 1, 1, 0, 0]), 100) == 6.0
    assert strike_peak(np.array([0.0, 5.0, -8.0, 3.0, 0.0]), np.array([0, 1, 1, 1, 0]), 100) == 5.0
    assert strike_end(np.array([0, 1, 1, 1]), 1, 0) == 2  # a cap of 0 rows still holds one


def test_the_strike_cap_is_the_strike_window_over_dt_rounded_and_at_least_one_row():
    """Contact from row 5 on, never opening, the push rising 1 N per row (row k: k N), rows
    every 10 ms: a 36 ms window is round(3.6) = 4 rows (5 … 8: 8 N; truncating would give
    3 rows, 7 N); a 4 ms window rounds to 0 rows and holds one (5 N); a 1 s window is
    capped by the end of the series (19 N)."""
    n = 20
    ts = series(np.arange(n) * 0.01, fz=np.arange(n), contacts=(np.arange(n) >= 5))
    for window, peak in ((0.036, 8.0), (0.004, 5.0), (1.0, 19.0)):
        c = contact_metrics(ts, SEAT, steady_window=0.1, strike_window=window)
        assert c["first_strike_force_N"] == peak, window


#: the steady window's rows below (t = 2.0 … 3.0 s): force ON the tool with |f| = 4, 1,
#: 1, 3, 3 N, and contacts 1, 0, 1, 1, 0; before it, 10 N and a contact that opens and
#: closes on every row
WINDOW_FORCE = [(2.4, 0.0, 3.2), (0.0, 0.6, 0.8), (0.0, -0.8, 0.6), (1.0, 2.0, 2.0), (2.0, -1.0, 2.0)]
WINDOW_CONTACTS = [1, 0, 1, 1, 0]


def steady_series() -> pd.DataFrame:
    t = np.arange(13) * 0.25  # exact binary times: 0, 0.25, … 3.0
    force = np.array([(0.0, 0.0, 10.0)] * 8 + WINDOW_FORCE)
    contacts = [1, 0, 1, 0, 1, 0, 1, 0, *WINDOW_CONTACTS]
    return series(t, fx=force[:, 0], fy=force[:, 1], fz=force[:, 2], contacts=contacts)


def test_the_steady_window_statistics_on_a_series_computed_by_hand():
    """Window 1 s on a series ending at 3 s: the rows with t ≥ 2 s, the row at exactly 2 s
    included. |f| over it = 4, 1, 1, 3, 3 N (every component counts, not the axial one):
    mean 12/5 = 2.4 N, std with ddof 1 = √(7.2/4) = √1.8 N (ddof 0 would be 1.2 N).
    Make/break events: the changes between the window's rows only (1→0, 0→1, 1→0: 3; the
    opening and closing before it, and the change into its first row, do not count), per
    second of the span of those rows (3.0 − 2.0 = 1 s): 3/s."""
    c = contact_metrics(steady_series(), SEAT, steady_window=1.0, strike_window=0.1)
    assert c["steady_force_mean_N"] == pytest.approx(2.4, rel=1e-12)
    assert c["steady_force_std_N"] == pytest.approx(np.sqrt(1.8), rel=1e-12)
    assert c["steady_contact_events_per_s"] == pytest.approx(3.0, rel=1e-12)


def test_the_event_rate_is_per_second_of_the_rows_span_not_of_the_window_setting():
    """A 1.1 s window on the same series holds the same five rows (t = 2.0 … 3.0 s; there
    is no row at 1.9 s): 3 events over their 1 s span is 3/s, not 3/1.1 s."""
    c = contact_metrics(steady_series(), SEAT, steady_window=1.1, strike_window=0.1)
    assert c["steady_contact_events_per_s"] == pytest.approx(3.0, rel=1e-12)
    assert c["steady_force_mean_N"] == pytest.approx(2.4, rel=1e-12)


def test_a_window_of_one_row_has_a_mean_but_no_spread_and_no_event_rate():
    """A 0 s window holds the last row alone: the mean is its |f| = 3 N; a standard deviation
    (ddof 1) and a rate per second of a span need two rows, so both are None (not 0)."""
    c = contact_metrics(steady_series(), SEAT, steady_window=0.0, strike_window=0.1)
    assert c["steady_force_mean_N"] == pytest.approx(3.0, rel=1e-12)
    assert c["steady_force_std_N"] is None and c["steady_contact_events_per_s"] is None


def test_non_finite_contact_metrics_are_none():
    """A NaN force in the window and a NaN pose at the first contact's state: the values
    that depend on them are None, never NaN."""
    ts = steady_series()
    ts.loc[12, "fx"] = np.nan
    ts.loc[ts.index[-1] - 1, "x"] = np.nan  # the state before the last row (which touches)
    ts["contacts"] = [0] * 12 + [1]
    c = contact_metrics(ts, SEAT, steady_window=1.0, strike_window=0.1)
    assert c["steady_force_mean_N"] is None and c["steady_force_std_N"] is None
    assert c["first_contact_lateral_offset_m"] is None
    assert c["first_contact_time_s"] == pytest.approx(2.75)


def _gate(**overrides):
    values = dict(
        depth_tolerance_m=0.001,
        lateral_tolerance_m=0.001,
        tilt_tolerance_deg=2.0,
        peak_force_budget_N=50.0,
        key_yaw_tolerance_deg=None,
        max_contact_events_per_s=5.0,
        max_force_std_N=0.5,
        max_force_std_ratio=0.2,
    )
    return DockingGateConfig(**{**values, **overrides})


def _hold(mean, std, events):
    return {
        **dict.fromkeys(registry.CONTACT_KEYS),
        "steady_force_mean_N": mean,
        "steady_force_std_N": std,
        "steady_contact_events_per_s": events,
    }


SEATED = SeatState(depth_error_m=1e-4, lateral_error_m=2e-4, tilt_deg=0.5, seated_time_s=14.0)


def test_the_chatter_gate_item_fails_a_bouncing_hold():
    """A plug seated within every tolerance, under the force budget, but bouncing: the
    docking gate fails it, and says so; the same hold calm passes."""
    docking = {"filtered_peak_axial_force_N": 24.0}
    bouncing = _hold(3.13, 4.89, 203.0)
    failures = docking_gate(SEATED, docking, _gate(), contact=bouncing)
    assert len(failures) == 2
    assert failures[0].startswith("contact chatter: 203 make/break events/s")
    assert failures[1].startswith("unsteady hold: |F| 3.13 ± 4.89 N")
    assert docking_verdict(SEATED, _gate(), failures).startswith("seated; contact chatter")
    assert docking_gate(SEATED, docking, _gate(), contact=_hold(3.3, 0.01, 0.0)) == []
    # the thresholds are the config's: a looser gate lets the same bounce through
    loose = _gate(max_contact_events_per_s=500.0, max_force_std_N=5.0)
    assert docking_gate(SEATED, docking, loose, contact=bouncing) == []
    # the spread limit is relative above 0.5 N / 20 %: 4 ± 0.7 N passes, 4 ± 0.9 N fails
    for std, ok in ((0.7, True), (0.9, False)):
        assert (docking_gate(SEATED, docking, _gate(), contact=_hold(4.0, std, 0.0)) == []) is ok
    # a hold that cannot be measured fails as well
    assert "steady force spread not available" in "; ".join(
        docking_gate(SEATED, docking, _gate(), contact=_hold(None, None, 0.0))
    )


def test_the_force_spread_limit_is_the_larger_of_the_floor_and_the_share_of_the_mean():
    """std limit = max(max_force_std_N, max_force_std_ratio × mean) = max(0.5 N, 20 % of the
    mean), at most the limit passing: at a 1 N mean the floor governs (0.5 N passes, 0.51 N
    fails, though 20 % of it is 0.2 N), at a 4 N mean the share (0.8 N passes, 0.81 N
    fails). A spread whose mean is missing cannot be judged: it fails as not available."""
    docking = {"filtered_peak_axial_force_N": 24.0}
    for mean, std, ok in ((1.0, 0.5, True), (1.0, 0.51, False), (4.0, 0.8, True), (4.0, 0.81, False)):
        failures = docking_gate(SEATED, docking, _gate(), contact=_hold(mean, std, 0.0))
        assert (failures == []) is ok, (mean, std, failures)
    failures = docking_gate(SEATED, docking, _gate(), contact=_hold(None, 0.3, 0.0))
    assert failures == ["steady force spread not available (non-finite or no data)"]


def test_failure_reasons_say_what_failed():
    failures = docking_gate(SEATED, {"filtered_peak_axial_force_N": 63.6}, _gate())
    assert (
        docking_verdict(SEATED, _gate(), failures)
        == "seated; peak force 63.6 N (filtered) over the 50 N budget"
    )
    short = SeatState(depth_error_m=0.0102, lateral_error_m=2e-4, tilt_deg=0.5, seated_time_s=None)
    failures = docking_gate(short, {"filtered_peak_axial_force_N": 30.0}, _gate())
    assert docking_verdict(short, _gate(), failures) == (
        "not docked: not seated: tip up to 10.2 mm from the seat over the steady window (tolerance 1 mm)"
    )
    assert docking_verdict(SEATED, _gate(), []) == "docked"


def test_metric_labels_fit_in_a_markdown_table_and_a_figure():
    """Labels go into summary.md's tables, where a "|" splits the cell, and onto axes, where
    the style's serif font draws "|" like an "l" ("steady |F| mean" did both)."""
    from compliant_docking.evaluation.registry import METRICS

    bad = [m.label for m in METRICS if "|" in m.label or "$" in m.label]
    assert not bad, f"labels with '|' or '$': {bad}"
