"""Docking metrics, seat state and the docking gate on synthetic time series whose answers
are known in closed form (docs/control_laws.md §5).

Every expected value below is written from the construction of the series, not recomputed
with the formula under test. The series are piecewise constant, so each statistic has an
exact value; tolerances are round-off (``rel=1e-12``) unless a line says otherwise. Each
case is built so that the likely wrong formula gives a different number (the maximum
instead of the minimum, the mean instead of the RMS, the whole run instead of the steady
window, the unprojected error, …): benchmarks/mutation_score.py checks that they do.
"""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest
from omegaconf import OmegaConf

from compliant_docking.evaluation.docking import (
    SeatState,
    compute_metrics,
    docking_gate,
    filtered_peak,
    manipulability_series,
    seat_state,
)
from compliant_docking.evaluation.registry import CONTACT_KEYS, DOCKING_KEYS
from compliant_docking.sim.telemetry import FORCE, MOMENT, ORI_ERROR, POSITION, POSITION_REF, QUATERNION
from tests.helpers import make_cfg

DT = 0.01
N = 1000  # t = 0 … 9.99 s; every series is constant from t = 5 s on
STEADY = 2.0  # the steady window: t ≥ 7.99 s, inside the constant part
FORCE_WINDOW = 0.05  # the filtered peak's window: 5 rows
#: the docking axis, deliberately oblique and not normalised (compute_metrics normalises it)
AXIS_RAW = np.array([2.0, -1.0, 2.0]) * 5.0
AXIS = AXIS_RAW / np.linalg.norm(AXIS_RAW)
#: a unit vector perpendicular to AXIS
PERP = np.array([1.0, 2.0, 0.0]) / math.sqrt(5.0)
#: joint ranges and speed limits of a 3-joint arm; joint 3 has no position limit, joint 2 no speed limit
Q_LOWER, Q_UPPER = np.array([-2.0, -1.0, -np.inf]), np.array([2.0, 3.0, np.inf])
V_LIMITS = np.array([2.0, np.inf, 0.5])


def synthetic_run() -> pd.DataFrame:
    """A 10 s docking series (module doc) with these closed-form statistics:

    - axial force: 0, a 40 N push at t = 3 s, a 45 N pull at t = 3.5 s, 2.5 N from t = 5 s;
    - a 30 N side force with a 40 N·m moment at t = 4 s (wrench norm 50, axial force 0);
      from t = 5 s a 1.2 N side force and a 0.9 N·m moment (wrench norm √8.5 N);
    - joints: joint 1 reaches 1.5 rad (75 % of its half range), joint 2 −0.6 rad (|−1.6|/2:
      80 %), joint 3 100 rad (no limit: skipped); joint 1 speed −0.75 rad/s (37.5 % of 2),
      joint 3 0.1 rad/s (20 % of 0.5), joint 2 50 rad/s (no limit: skipped);
    - position error: up to t = 5 s alternately 1 mm and 7 mm along PERP (RMS² 25 mm², mean
      4 mm), then 4 mm along the axis plus 3 mm along PERP (5 mm, lateral 3 mm): over the
      run RMS 5 mm, mean 4.5 mm;
    - orientation error: 0, then from t = 2 s to 5 s alternately 0.1 and 0.7 rad, then 0:
      RMS √0.075 rad, mean 0.12 rad, 0 in the steady window;
    - contacts from row 301 on: the first contact's state is row 300 (t = 3 s), so the
      motion before contact is rows 0–299 (position RMS 5 mm, orientation RMS √(1/12) rad:
      100 of its 300 rows alternate 0.1 and 0.7 rad).
    """
    t = np.arange(N) * DT
    k = np.arange(N)
    late = k >= 500
    axial = np.zeros(N)
    axial[300], axial[350], axial[late] = 40.0, -45.0, 2.5
    side = np.zeros(N)
    side[400], side[late] = 30.0, 1.2
    moment = np.zeros((N, 3))
    moment[400], moment[late] = [0.0, 0.0, 40.0], [0.0, 0.9, 0.0]
    force = -np.outer(axial, AXIS) + np.outer(side, PERP)  # axial force = −f·axis

    q = np.zeros((N, 3))
    q[600, 0], q[700, 1], q[100, 2] = 1.5, -0.6, 100.0
    v = np.zeros((N, 3))
    v[200, 0], v[250, 2], v[300, 1] = -0.75, 0.1, 50.0

    err_norm = np.where(k % 2 == 0, 1e-3, 7e-3)
    err = np.outer(err_norm, PERP)
    err[late] = 4e-3 * AXIS + 3e-3 * PERP
    err_norm[late] = 5e-3
    ref = np.array([0.5, 0.1, 0.3]) + np.outer(t, [0.01, 0.0, -0.02])

    ori_norm = np.zeros(N)
    mid = (k >= 200) & (k < 500)
    ori_norm[mid] = np.where(k[mid] % 2 == 0, 0.1, 0.7)
    ori = np.outer(ori_norm, np.array([3.0, 0.0, 4.0]) / 5.0)

    cols: dict = {"t": t}
    for i in range(3):
        cols[f"q{i + 1}"], cols[f"v{i + 1}"] = q[:, i], v[:, i]
    for block, names in ((ref + err, POSITION), (ref, POSITION_REF), (force, FORCE), (moment, MOMENT)):
        cols.update({name: block[:, i] for i, name in enumerate(names)})
    cols["pos_error"] = err_norm
    cols["contacts"] = np.where(k >= 301, 2, 0)
    cols.update({name: ori[:, i] for i, name in enumerate(ORI_ERROR)})
    return pd.DataFrame(cols)


def manipulability_of(t: np.ndarray) -> np.ndarray:
    """0.1 − 0.07 sin(π t / 10): 0.1 at the ends, its minimum 0.03 at t = 5 s."""
    return 0.1 - 0.07 * np.sin(np.pi * t / 10.0)


def metrics_of(ts: pd.DataFrame, **overrides) -> dict:
    kwargs = dict(
        axis=AXIS_RAW,
        q_lower=Q_LOWER,
        q_upper=Q_UPPER,
        velocity_limits=V_LIMITS,
        manipulability=manipulability_of(ts["t"].to_numpy()),
        steady_window=STEADY,
        force_window=FORCE_WINDOW,
    )
    kwargs.update(overrides)
    return compute_metrics(ts, **kwargs)


EXPECTED = {
    "peak_axial_force_N": 45.0,  # the 45 N pull: a peak of |F| (push 40 N, side force 0 N)
    "filtered_peak_axial_force_N": 9.0,  # the one-row 45 N pull over a 5-row window (push: 8 N)
    "peak_wrench_norm_N": 50.0,  # ‖[30 N side; 40 N·m]‖ at t = 4 s
    "steady_axial_force_N": 2.5,  # the 1.2 N side force is not axial
    "steady_wrench_norm_N": math.sqrt(2.5**2 + 1.2**2 + 0.9**2),
    "max_joint_pos_pct": 80.0,
    "max_joint_pos_joint": 1,
    "max_joint_vel_pct": 37.5,
    "max_joint_vel_joint": 0,
    "min_manipulability": 0.03,
    "pos_tracking_rms_m": 5e-3,  # the mean would be 4.5 mm
    "ori_tracking_rms_rad": math.sqrt(0.075),  # the mean would be 0.12 rad
    "approach_pos_rms_m": 5e-3,  # rows 0–299 (the mean would be 4 mm)
    "approach_ori_rms_rad": math.sqrt(1.0 / 12.0),  # rows 0–299; through row 300: √(25.01/301)
    "press_depth_m": -4e-3,  # the tip 4 mm PAST the reference along the axis (the 3 mm across: not counted)
    "final_lateral_error_m": 3e-3,  # unprojected: 5 mm; over the run: more
    "final_orientation_error_rad": 0.0,  # over the run: 0.12 rad
}


def test_expected_covers_every_docking_metric():
    assert set(EXPECTED) == set(DOCKING_KEYS)


@pytest.mark.parametrize("key", sorted(EXPECTED))
def test_each_metric_has_its_closed_form_value(key):
    value = metrics_of(synthetic_run())[key]
    expected = EXPECTED[key]
    if isinstance(expected, int):
        assert value == expected and isinstance(value, int)
    else:  # round-off only: sums of ≤ 1000 exactly known terms
        assert value == pytest.approx(expected, rel=1e-12, abs=1e-15), (key, value)


def test_the_steady_window_is_the_last_seconds():
    """Shorten the window to 0.5 s and put a different constant in its last 1 s: the steady
    values follow the window, not the run."""
    ts = synthetic_run()
    last = ts["t"] >= 9.0
    ts.loc[last, FORCE] = -6.0 * AXIS  # 6 N axial, no side force
    ts.loc[last, MOMENT] = 0.0
    m = metrics_of(ts, steady_window=0.5)
    assert m["steady_axial_force_N"] == pytest.approx(6.0, rel=1e-12)
    assert m["steady_wrench_norm_N"] == pytest.approx(6.0, rel=1e-12)


def test_joints_without_a_finite_positive_limit_are_skipped():
    ts = synthetic_run()
    m = metrics_of(
        ts, q_lower=np.full(3, -np.inf), q_upper=np.full(3, np.inf), velocity_limits=[0.0, np.inf, -1.0]
    )
    assert m["max_joint_pos_pct"] is None and m["max_joint_pos_joint"] is None
    assert m["max_joint_vel_pct"] is None and m["max_joint_vel_joint"] is None


def test_missing_or_non_finite_values_are_null_never_made_up():
    assert metrics_of(synthetic_run(), manipulability=None)["min_manipulability"] is None
    empty = metrics_of(synthetic_run().iloc[:0], manipulability=np.zeros(0))
    assert set(empty) == set(DOCKING_KEYS) and all(v is None for v in empty.values())
    ts = synthetic_run()
    ts.loc[100, "fx"] = np.nan  # before the steady window
    ts.loc[150, "pos_error"] = np.inf
    m = metrics_of(ts)
    assert m["peak_axial_force_N"] is None and m["peak_wrench_norm_N"] is None
    assert m["pos_tracking_rms_m"] is None
    assert m["steady_axial_force_N"] == pytest.approx(2.5, rel=1e-12)  # the window is clean


def test_filtered_peak_is_the_peak_of_the_window_mean():
    """A rectangular impulse of 0.2 N·s lasting 1, 2 or 5 ms (peaks 200, 100, 40 N) reads
    0.2 / 0.05 = 4 N through a 50 ms window whatever its length (the property the gate
    needs: an impact's per-step peak scales with the contact time constant, its impulse does
    not); a held force reads itself; the sign does not matter; a series shorter than the
    window is averaged whole."""
    dt = 0.001
    t = np.arange(400) * dt
    for rows in (1, 2, 5):
        force = np.zeros(400)
        force[100 : 100 + rows] = 0.2 / (rows * dt)
        assert filtered_peak(force, t, 0.05) == pytest.approx(4.0, rel=1e-12)
        assert filtered_peak(-force, t, 0.05) == pytest.approx(4.0, rel=1e-12)
    held = np.where(t >= 0.2, 3.0, 0.0)
    assert filtered_peak(held, t, 0.05) == pytest.approx(3.0, rel=1e-12)
    ramp = np.arange(10.0)  # 10 rows < 50: the mean of all, 4.5
    assert filtered_peak(ramp, t[:10], 0.05) == pytest.approx(4.5, rel=1e-12)
    assert filtered_peak(ramp, t[:10], 0.0021) == pytest.approx(8.5, rel=1e-12)  # 2 rows: (8 + 9) / 2


def test_the_gate_judges_the_filtered_peak_not_the_raw_one():
    """A raw per-step peak of 120 N whose filtered peak is 40 N passes a 50 N budget; a
    filtered 60 N fails it, and the message says it is the filtered force."""
    seat = SeatState(0.0, 0.0, 0.0, 1.0)
    gate = SimpleNamespace(
        depth_tolerance_m=1e-3, lateral_tolerance_m=1e-3, tilt_tolerance_deg=2.0, peak_force_budget_N=50.0
    )
    metrics = {"peak_axial_force_N": 120.0, "filtered_peak_axial_force_N": 40.0}
    assert docking_gate(seat, metrics, gate) == []
    metrics = {"peak_axial_force_N": 45.0, "filtered_peak_axial_force_N": 60.0}
    assert docking_gate(seat, metrics, gate) == ["peak force 60 N (filtered) over the 50 N budget"]


# --------------------------------------------------------------------------- manipulability
class _DiagonalArm:
    """A stand-in arm whose 6×7 Jacobian is diag(q₁, 1, 1, 1, 1, 2): √det(J Jᵀ) = 2|q₁|."""

    nv = 7

    class model:  # noqa: N801 - mimics ArmModel.model
        @staticmethod
        def createData():  # noqa: N802 - Pinocchio's name
            return None

    @staticmethod
    def world_jacobian(q, data):
        J = np.zeros((6, 7))
        J[np.arange(6), np.arange(6)] = [q[0], 1.0, 1.0, 1.0, 1.0, 2.0]
        return J


def test_manipulability_series_is_the_product_of_the_singular_values():
    q = np.zeros((4, 7))
    q[:, 0] = [0.5, -0.25, 0.0, 3.0]
    np.testing.assert_allclose(manipulability_series(_DiagonalArm, q), [1.0, 0.5, 0.0, 6.0], rtol=1e-12)


def test_manipulability_of_the_iiwa14_is_zero_stretched_out():
    """At q = 0 the iiwa14 stands straight up: joints 1, 3, 5 and 7 are coaxial and J loses
    rank, so w = 0 (to round-off: the smallest singular value is ~1e-17). Elsewhere w is the
    product of J's singular values (an independent formula)."""
    from compliant_docking.sim.simulate import prepare

    arm = prepare(make_cfg("task.progress=false")).scene.arm
    q = np.zeros((2, arm.nv))
    q[1] = [0.3, 0.6, -0.2, -1.4, 0.4, 0.9, 0.1]
    w = manipulability_series(arm, q)
    assert w[0] < 1e-9
    assert w[1] == pytest.approx(np.prod(np.linalg.svd(arm.world_jacobian(q[1]), compute_uv=False)), rel=1e-9)


# --------------------------------------------------------------------------- seat state
#: the true seat: an oblique pose, so that a tip position not rotated into the seat frame,
#: or a tilt measured against the wrong axis, gives other numbers
SEAT = pin.SE3(pin.exp3(np.array([0.4, -0.3, 0.2])), np.array([0.6, -0.1, 0.25]))
DEPTH_TOL = 1.5e-3


def seat_series() -> pd.DataFrame:
    """The tip, in the seat frame: down the axis from 0.1 m at 0.02 m/s (depth ≤ 1.5 mm from
    t = 4.93 s), 2 mm then 20 mm off the axis and tilted 20° before t = 5 s; then (0.3, −0.4,
    −0.2) mm with a 1.5° tilt, except one sample at (0.6, 0.8, 0.7) mm tilted 1.8°.
    Steady maxima: depth 0.7 mm, lateral 1.0 mm, tilt 1.8°."""
    t = np.arange(N) * DT
    rel = np.zeros((N, 3))
    rel[:, 2] = np.maximum(0.1 - 0.02 * t, 0.0)
    rel[:250, 0], rel[250:500, 1] = 2e-3, 20e-3
    tilt = np.full(N, math.radians(20.0))
    rel[500:] = [0.3e-3, -0.4e-3, -0.2e-3]
    tilt[500:] = math.radians(1.5)
    rel[900], tilt[900] = [0.6e-3, 0.8e-3, 0.7e-3], math.radians(1.8)
    pos = SEAT.translation + rel @ SEAT.rotation.T
    # inserted: the plug's +z along the socket's −z (Rx(π)), then tilted about y
    flip = pin.exp3(np.array([math.pi, 0.0, 0.0]))
    quat = np.array(
        [
            np.roll(pin.Quaternion(SEAT.rotation @ flip @ pin.exp3(np.array([0.0, a, 0.0]))).coeffs(), 1)
            for a in tilt
        ]
    )
    cols = {"t": t, **{n: pos[:, i] for i, n in enumerate(POSITION)}}
    cols.update({n: quat[:, i] for i, n in enumerate(QUATERNION)})
    return pd.DataFrame(cols)


def test_seat_state_is_measured_in_the_true_seat_frame():
    state = seat_state(seat_series(), SEAT, STEADY, DEPTH_TOL)
    assert state.depth_error_m == pytest.approx(0.7e-3, rel=1e-9)  # 1e-9: poses round-trip through SE3
    assert state.lateral_error_m == pytest.approx(1.0e-3, rel=1e-9)
    assert state.tilt_deg == pytest.approx(1.8, rel=1e-7)  # arccos near 1 loses half the digits
    assert state.seated_time_s == pytest.approx(4.93, abs=1e-12)


def test_seat_state_without_data_or_never_seated():
    assert seat_state(seat_series().iloc[:0], SEAT, STEADY, DEPTH_TOL) == SeatState(None, None, None, None)
    far = seat_series()
    far[POSITION] += SEAT.rotation[:, 2] * 0.05  # 5 cm out of the socket all along
    assert seat_state(far, SEAT, STEADY, DEPTH_TOL).seated_time_s is None


# --------------------------------------------------------------------------- the docking gate
#: the gate's items: label (in a "not available" failure), tolerance field, where the value
#: lives (a SeatState field, a metrics key or a contact-metrics key), and how a failure over
#: the tolerance starts (it says what failed). A new item is one more row. The force spread's
#: limit is max(max_force_std_N, max_force_std_ratio × mean): with the mean at 1 N (below) it
#: is max_force_std_N; the ratio's side is tested in tests/evaluation/test_contact.py.
GATE_ITEMS = {
    "seat depth error": ("depth_tolerance_m", "seat", "depth_error_m", "not seated: "),
    "seat lateral error": ("lateral_tolerance_m", "seat", "lateral_error_m", "off the axis: "),
    "plug tilt": ("tilt_tolerance_deg", "seat", "tilt_deg", "tilted: "),
    "peak axial force": ("peak_force_budget_N", "metrics", "filtered_peak_axial_force_N", "peak force "),
    "key yaw": ("key_yaw_tolerance_deg", "seat", "key_yaw_deg", "key yaw "),
    "steady contact events": (
        "max_contact_events_per_s",
        "contact",
        "steady_contact_events_per_s",
        "contact chatter: ",
    ),
    "steady force spread": ("max_force_std_N", "contact", "steady_force_std_N", "unsteady hold: "),
}
HOLD_MEAN_N = 1.0  # the held force's mean in these cases: 20 % of it is below max_force_std_N
#: the shipped tolerances (conf/task/docking.yaml); the key-yaw one is null there (a keyed
#: interface's default is its yaw play + 0.1°, tests/sim/test_keyed.py): 2.44° as for a
#: square key with 2.34° of play
GATE = OmegaConf.merge(make_cfg().task.gate, {"key_yaw_tolerance_deg": 2.44})


def _judge(item: str | None = None, value=None, gate=GATE) -> list[str]:
    """The gate of a keyed interface with every item at half its tolerance, except ``item``
    at ``value``."""
    half = {field: 0.5 * gate[tolerance] for tolerance, where, field, _ in GATE_ITEMS.values()}
    seat = SeatState(
        half["depth_error_m"], half["lateral_error_m"], half["tilt_deg"], 3.0, key_yaw_deg=half["key_yaw_deg"]
    )
    metrics = dict.fromkeys(DOCKING_KEYS, 1.0) | {
        "filtered_peak_axial_force_N": half["filtered_peak_axial_force_N"]
    }
    contact = dict.fromkeys(CONTACT_KEYS, 1.0) | {
        "steady_force_mean_N": HOLD_MEAN_N,
        "steady_force_std_N": half["steady_force_std_N"],
        "steady_contact_events_per_s": half["steady_contact_events_per_s"],
    }
    if item is not None:
        _, where, field, _ = GATE_ITEMS[item]
        if where == "seat":
            seat = replace(seat, **{field: value})
        else:
            (metrics if where == "metrics" else contact)[field] = value
    return docking_gate(seat, metrics, gate, key_yaw_limit_deg=gate.key_yaw_tolerance_deg, contact=contact)


def test_gate_items_are_the_configured_tolerances():
    assert set(GATE) == {spec[0] for spec in GATE_ITEMS.values()} | {"max_force_std_ratio"}
    assert float(GATE.max_force_std_ratio) * HOLD_MEAN_N < float(GATE.max_force_std_N)
    assert _judge() == []


@pytest.mark.parametrize("item", GATE_ITEMS)
def test_each_gate_item_passes_just_inside_and_fails_just_outside(item):
    """At the tolerance itself the item passes (≤); 1 ppm above it fails alone. A gate with
    its tolerances widened (or an item dropped) passes that value and fails this test."""
    limit = float(GATE[GATE_ITEMS[item][0]])
    assert _judge(item, limit * (1.0 - 1e-6)) == []
    assert _judge(item, limit) == []
    failures = _judge(item, limit * (1.0 + 1e-6))
    assert len(failures) == 1 and failures[0].startswith(GATE_ITEMS[item][3]), failures


@pytest.mark.parametrize("item", GATE_ITEMS)
@pytest.mark.parametrize("value", [None, math.nan, math.inf])
def test_a_missing_or_non_finite_gate_value_fails(item, value):
    failures = _judge(item, value)
    assert len(failures) == 1 and failures[0].startswith(item), failures


def test_every_failing_item_is_listed_with_its_value_and_limit():
    seat = SeatState(2e-3, 3e-3, 4.0, None, key_yaw_deg=5.0)
    metrics = dict.fromkeys(DOCKING_KEYS) | {"filtered_peak_axial_force_N": 80.0}
    failures = docking_gate(seat, metrics, SimpleNamespace(**GATE), key_yaw_limit_deg=2.44)
    assert failures[:4] == [
        "not seated: tip up to 2 mm from the seat over the steady window (tolerance 1 mm)",
        "off the axis: tip up to 3 mm from the socket axis over the steady window (tolerance 1 mm)",
        "tilted: plug up to 4° off the socket axis (tolerance 2°)",
        "peak force 80 N (filtered) over the 50 N budget",
    ]
    assert len(failures) == 5 and failures[4].startswith("key yaw 5 deg > 2.44 deg")
    # a round interface has no key: its yaw is not judged
    assert docking_gate(replace(seat, key_yaw_deg=None), metrics, SimpleNamespace(**GATE))[4:] == []
