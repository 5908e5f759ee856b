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
