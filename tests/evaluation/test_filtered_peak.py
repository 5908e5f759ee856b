"""The filtered peak axial force, the force the docking gate judges, pinned part by part.

``filtered_peak_axial_force_N`` is max over the run of |mean of the axial force over
``task.force_window``|. Over a series sampled every dt, that is the mean of
n = round(window / dt) consecutive rows (n ≥ 1 and at most the whole series), taken at
every full window from the one that starts on the first row to the one that ends on the
last row. Each test below builds a series whose answer follows from that sentence by hand.
benchmarks/mutation_score.py (mutations F1–F18) checks that each part is pinned.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from compliant_docking.evaluation.docking import SeatState, compute_metrics, docking_gate, filtered_peak
from compliant_docking.sim.telemetry import FORCE, MOMENT, ORI_ERROR, POSITION, POSITION_REF
from tests.helpers import make_cfg

DT = 0.001
T = np.arange(200) * DT  # 0.2 s at 1 ms


def spikes(rows: dict[int, float], n: int = 200) -> np.ndarray:
    force = np.zeros(n)
    for row, value in rows.items():
        force[row] = value
    return force


def test_the_window_is_round_window_over_dt_rows_and_at_least_one():
    """A 10 N one-row spike reads 10 / n: 4.6 ms at dt = 1 ms is n = 5 rows (2 N; flooring
    gives 4 rows, 2.5 N), 4.4 ms is 4 rows (2.5 N; ceiling gives 5 rows, 2 N), and 0.4 ms
    rounds to no row, clamped to one: the raw 10 N."""
    force = spikes({100: 10.0})
    assert filtered_peak(force, T, 0.0046) == pytest.approx(2.0, rel=1e-12)
    assert filtered_peak(force, T, 0.0044) == pytest.approx(2.5, rel=1e-12)
    assert filtered_peak(force, T, 0.0004) == pytest.approx(10.0, rel=1e-12)


def test_the_window_is_in_seconds_whatever_the_time_step():
    """dt is read from the time column: 50 ms is 25 rows at dt = 2 ms and 100 rows at
    dt = 0.5 ms, so a 10 N one-row spike reads 10 / 25 = 0.4 N and 10 / 100 = 0.1 N."""
    coarse = np.arange(200) * 0.002
    fine = np.arange(400) * 0.0005
    assert filtered_peak(spikes({50: 10.0}), coarse, 0.05) == pytest.approx(0.4, rel=1e-12)
    assert filtered_peak(spikes({50: 10.0}, 400), fine, 0.05) == pytest.approx(0.1, rel=1e-12)


def test_a_window_holds_exactly_n_consecutive_rows():
    """With n = 5 rows: two 10 N spikes 5 rows apart never share a window (10 / 5 = 2 N; a
    6-row window would read 20 / 6 N), two spikes 4 rows apart do (20 / 5 = 4 N), and a
    10 N block of exactly 5 rows reads 10 N (a 6-row window: 50 / 6 N)."""
    assert filtered_peak(spikes({100: 10.0, 105: 10.0}), T, 0.005) == pytest.approx(2.0, rel=1e-12)
    assert filtered_peak(spikes({100: 10.0, 104: 10.0}), T, 0.005) == pytest.approx(4.0, rel=1e-12)
    block = spikes(dict.fromkeys(range(100, 105), 10.0))
    assert filtered_peak(block, T, 0.005) == pytest.approx(10.0, rel=1e-12)


def test_the_first_and_the_last_full_windows_count():
    """A 10-row 6 N block on rows 0–9 or on the last 10 rows: the window of rows 0–9 (the
    first) or of the last 10 rows (the last) reads 6 N; every other window reads less."""
    first = spikes(dict.fromkeys(range(0, 10), 6.0))
    last = spikes(dict.fromkeys(range(190, 200), 6.0))
    assert filtered_peak(first, T, 0.01) == pytest.approx(6.0, rel=1e-12)
    assert filtered_peak(last, T, 0.01) == pytest.approx(6.0, rel=1e-12)


def test_a_series_shorter_than_the_window_is_averaged_whole():
    """Rows 1, 2, 3, 4 N over a 50 ms window at dt = 1 ms (4 rows < 50): their mean, 2.5 N,
    not their sum (10 N) and not the mean of a 50-row window padded with zeros (0.2 N)."""
    assert filtered_peak(np.array([1.0, 2.0, 3.0, 4.0]), T[:4], 0.05) == pytest.approx(2.5, rel=1e-12)


def test_the_peak_is_of_the_absolute_mean_not_the_mean_of_absolutes():
    """A pull reads as much as a push (−3 N held: 3 N), and a force that flips sign every
    row (±8 N) averages out over an even window (0 N), where the mean of |f| would be 8 N;
    over an odd window of 5 rows it reads 8 / 5 N."""
    pull = np.full(200, -3.0)
    assert filtered_peak(pull, T, 0.05) == pytest.approx(3.0, rel=1e-12)
    flipping = 8.0 * (-1.0) ** np.arange(200)
    assert filtered_peak(flipping, T, 0.004) == pytest.approx(0.0, abs=1e-12)
    assert filtered_peak(flipping, T, 0.005) == pytest.approx(1.6, rel=1e-12)


def test_a_mean_not_a_sum():
    """A 0.2 N·s impulse in one row at dt = 1 ms (200 N) over 50 ms: 0.2 / 0.05 = 4 N (the
    sum over the window would be 200 N)."""
    assert filtered_peak(spikes({100: 200.0}), T, 0.05) == pytest.approx(4.0, rel=1e-12)


def test_an_empty_series_has_no_filtered_peak():
    assert math.isnan(filtered_peak(np.zeros(0), np.zeros(0), 0.05))


def _series(force: np.ndarray, dt: float = DT) -> pd.DataFrame:
    """A one-joint run at rest on its reference, with the given force ON the tool (rows)."""
    n = len(force)
    frame = {"t": np.arange(n) * dt, "q1": np.zeros(n), "v1": np.zeros(n), "pos_error": np.zeros(n)}
    for columns in (POSITION, POSITION_REF, ORI_ERROR, MOMENT):
        frame |= dict.fromkeys(columns, np.zeros(n))
    frame |= {c: force[:, i] for i, c in enumerate(FORCE)}
    return pd.DataFrame(frame)


def _metrics(ts: pd.DataFrame, axis=(0.0, 0.0, -1.0), force_window=0.05) -> dict:
    return compute_metrics(
        ts,
        axis=np.asarray(axis),
        q_lower=np.array([-1.0]),
        q_upper=np.array([1.0]),
        velocity_limits=np.array([1.0]),
        manipulability=None,
        steady_window=0.01,
        force_window=force_window,
    )


def test_the_metric_filters_the_axial_force_over_the_whole_run():
    """Insertion along world −z; the force ON the tool is +z when the plug presses in.
    A 20 N side force (x) held for 0.1 s is not axial; a 200 N push for one row at
    t = 0.05 s (0.2 N·s) reads 4 N over 50 ms; 1 N held to the end. The filtered peak is
    4 N (the side force's magnitude would give 20 N, the steady window alone 1 N, a 10 ms
    window 20 N); the raw peak is 200 N."""
    force = np.zeros((400, 3))
    force[200:300, 0] = 20.0
    force[50, 2] = 200.0
    force[300:, 2] = 1.0
    m = _metrics(_series(force))
    assert m["filtered_peak_axial_force_N"] == pytest.approx(4.0, rel=1e-12)
    assert m["peak_axial_force_N"] == pytest.approx(200.0, rel=1e-12)
    assert _metrics(_series(force), force_window=0.01)["filtered_peak_axial_force_N"] == pytest.approx(20.0)


def test_the_gate_judges_the_filtered_peak_of_a_series():
    """The one-row 200 N strike above (filtered 4 N) passes a 50 N budget although its raw
    peak is 200 N; a 60 N push held for 50 ms (filtered 60 N) fails it."""
    gate = SimpleNamespace(
        depth_tolerance_m=1e-3, lateral_tolerance_m=1e-3, tilt_tolerance_deg=2.0, peak_force_budget_N=50.0
    )
    seat = SeatState(0.0, 0.0, 0.0, 1.0)
    force = np.zeros((400, 3))
    force[50, 2] = 200.0
    assert docking_gate(seat, _metrics(_series(force)), gate) == []
    force[100:150, 2] = 60.0
    assert docking_gate(seat, _metrics(_series(force)), gate) == [
        "peak force 60 N (filtered) over the 50 N budget"
    ]


def test_the_default_window_is_50_ms():
    """docs/run_directory.md states the filtered peak over task.force_window (50 ms)."""
    assert make_cfg().task.force_window == 0.05
