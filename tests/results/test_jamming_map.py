"""The jamming map's cells and figure from a hand-made table of jobs (no simulation)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from compliant_docking.config.store import default_interface
from compliant_docking.evaluation.map_boundaries import MapBoundaries
from compliant_docking.results.jamming_map import cell_table, jamming_map_figure
from compliant_docking.results.stats import wilson


@pytest.fixture(scope="module")
def bounds() -> MapBoundaries:
    plug, socket, contact = default_interface()
    return MapBoundaries.for_interface(plug, socket, contact.friction[0])


def jobs() -> pd.DataFrame:
    """fr3 · impedance: cell x ∈ [0, 2] mm, tilt ∈ [0, 1]°: 3 of 4 docked (one failed run);
    cell x ∈ [0, 2] mm, tilt ∈ [2, 3]°: 0 of 2; hqp: one job, docked."""
    rows = []
    for success, status in ((True, "ok"), (True, "ok"), (True, "ok"), (False, "failed")):
        rows.append(("impedance", "[0.0,0.002]", "[0.0,1.0]", 0.0005, 0.3, success, status))
    for _ in range(2):
        rows.append(("impedance", "[0.0,0.002]", "[2.0,3.0]", 0.0015, 2.5, False, "ok"))
    rows.append(("hqp", "[0.0,0.002]", "[0.0,1.0]", 0.001, 0.7, True, "ok"))
    columns = ["controller", "task.misalignment.x_range", "task.misalignment.tilt_deg_range",
               "misalignment_x_m", "misalignment_tilt_deg", "success", "status"]  # fmt: skip
    df = pd.DataFrame(rows, columns=columns)
    df["robot"] = "fr3"
    return df


def test_cells_are_the_drawn_ranges_with_wilson_intervals(bounds):
    cells = cell_table(jobs(), bounds).set_index(["controller", "tilt_low_deg"])
    cell = cells.loc[("impedance", 0.0)]
    assert (cell["x_low_mm"], cell["x_high_mm"], cell["tilt_high_deg"]) == pytest.approx((0.0, 2.0, 1.0))
    assert (cell["jobs"], cell["docked"]) == (4, 3)  # the failed run counts as not docked
    assert cell["success_rate"] == 0.75
    assert (cell["wilson_low"], cell["wilson_high"]) == pytest.approx(wilson(3, 4), rel=1e-12)
    # the centre (1 mm, 0.5°) lands on the chamfer; the corner (2 mm, 1°) past its 1.61 mm: the funnel
    assert cell["theory"] == "mixed: chamfer, funnel"
    assert cells.loc[("impedance", 2.0), "theory"] == "two-point"  # 2–3°, all over 1.72°
    assert (cells.loc[("hqp", 0.0), "jobs"], cells.loc[("hqp", 0.0), "docked"]) == (1, 1)


def test_without_drawn_ranges_jobs_are_binned_1_mm_by_1_degree(bounds):
    df = jobs().drop(columns=["task.misalignment.x_range", "task.misalignment.tilt_deg_range"])
    cells = cell_table(df, bounds)
    bins = set(zip(cells["x_low_mm"], cells["x_high_mm"], cells["tilt_low_deg"]))
    assert bins == {(0.0, 1.0, 0.0), (1.0, 2.0, 2.0), (1.0, 2.0, 0.0)}


def test_the_figure_draws_the_theory_where_it_says(bounds, monkeypatch):
    """The chamfer's lines pass through ±2.13 mm upright; the two-point line at 1.72°; the
    funnel mouth (±10.8 mm) and wedging (11.7°) lie outside these axes and are not drawn,
    until the map reaches the mouth (+10.79 mm upright)."""
    monkeypatch.setattr("compliant_docking.results.figures.common.save_figure", lambda *a, **k: [])
    df = jobs()
    df.loc[len(df)] = df.loc[0].copy()
    df.loc[len(df) - 1, ["task.misalignment.x_range", "task.misalignment.tilt_deg_range"]] = [
        "[-0.006,-0.004]",
        "[4.0,5.0]",
    ]
    fig = jamming_map_figure(cell_table(df, bounds), bounds)
    ax = fig.axes[0]
    lines = {line.get_label(): line for line in ax.get_lines()}
    chamfer = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
    upright = sorted(float(line.get_xdata()[0]) for line in chamfer)
    assert upright == pytest.approx([-2.132, 2.132], abs=1e-3)
    two_point = lines["two-point contact before the seat (rigid)"]
    assert float(np.asarray(two_point.get_ydata())[0]) == pytest.approx(bounds.two_point_tilt_deg)
    assert "wedging (l < μd)" not in lines and "funnel mouth (capture)" not in lines
    assert ax.get_xlim() == pytest.approx((-6.0, 2.0)) and ax.get_ylim() == pytest.approx((0.0, 5.0))
    wide = df.copy()
    wide.loc[0, "task.misalignment.x_range"] = "[0.008,0.012]"  # the mouth, 7.63 mm at 4°, in view
    funnel = {
        line.get_label(): line
        for line in jamming_map_figure(cell_table(wide, bounds), bounds).axes[0].get_lines()
    }
    ends = funnel["funnel mouth (capture)"]
    assert float(ends.get_xdata()[0]) == pytest.approx(bounds.funnel_capture_m * 1e3, rel=1e-9)
