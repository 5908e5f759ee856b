"""A run's own figures: the contact-force panel zoomed on the contact with the budget and the
docking time, the tracking test's paths, segments and thresholds without a contact-force
figure, and axes without offset notation (the figures are caught as they are saved)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from compliant_docking.planning.tracking import segment_times
from compliant_docking.run import figures as run_figures
from compliant_docking.run.figures import RunMarks, plot_run


def series(contact_at: float | None = 10.0, peak: float = 30.0, duration: float = 12.0) -> pd.DataFrame:
    """A run's time series on a 1 ms grid: x held at 0.55 m ± 1e-7, the orientation error
    at 0.5° ± 6e-8 (the offset-notation cases), a circle in y-z and a figure-8 in x-y as reference and actual, and from
    ``contact_at`` a strike of ``peak`` N decaying to 2 N along −z."""
    t = np.arange(0.0, duration, 0.001)
    ts = pd.DataFrame({"t": t})
    ts["x_ref"] = 0.55 + 1e-7 * np.sin(t)
    ts["y_ref"] = 0.1 * np.sin(t)
    ts["z_ref"] = 0.4 + 0.1 * np.cos(t)
    for c in "xyz":
        ts[c] = ts[f"{c}_ref"] + 1e-5
    ts["pos_error"] = 1e-5 + 0 * t
    ts["ori_error_x"] = 0.0087 + 1e-9 * np.sin(t)  # a steady 0.5° error: the offset-notation case
    ts["ori_error_y"], ts["ori_error_z"] = 0.0, 0.0
    force = np.zeros_like(t)
    contacts = np.zeros_like(t, dtype=int)
    if contact_at is not None:
        on = t >= contact_at
        force[on] = 2.0 + (peak - 2.0) * np.exp(-(t[on] - contact_at) * 40)
        contacts[on] = 1
    ts["fx"], ts["fy"], ts["fz"] = 0.0, 0.0, force  # the socket pushes back up: +z on the tool
    ts["mx"], ts["my"], ts["mz"] = 0.0, 0.0, 0.0
    ts["contacts"] = contacts
    for i in range(1, 8):
        ts[f"tau{i}"] = 0.0
    return ts


@pytest.fixture
def drawn(monkeypatch):
    """{stem: figure} of everything plot_run saves (the figures stay open to inspect)."""
    figures = {}

    def save(fig, out_dir, stem, formats=run_figures.FORMATS):
        fig.canvas.draw()  # tick labels and offset texts exist only once drawn
        figures[stem] = fig
        return []

    monkeypatch.setattr(run_figures, "save", save)
    import matplotlib.pyplot as plt

    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: None)
    yield figures
    for fig in figures.values():
        close(fig)


def run(tmp_path, ts, marks: RunMarks) -> None:
    plot_run(ts, tmp_path, axis=np.array([0.0, 0.0, -1.0]), torque_limits=np.full(7, 10.0), marks=marks)


def test_contact_panel_zooms_on_the_contact_with_budget_and_docked_marker(tmp_path, drawn):
    run(tmp_path, series(contact_at=10.0, peak=30.0), RunMarks(budget=40.0, docking_time=10.4))
    ax = drawn["contact_force"].axes[0]
    assert ax.get_xlim() == pytest.approx((10.0 - 0.3 - 0.001, 12.0 - 0.001), abs=2e-3)  # 0.3 s before
    budget = [line for line in ax.lines if list(line.get_ydata()) == [40.0, 40.0]]
    assert len(budget) == 1 and "budget 40 N" in budget[0].get_label()
    markers = [line.get_xdata()[0] for line in ax.lines if line.get_linestyle() == "-."]
    assert markers == [pytest.approx(10.4)]  # docked
    assert {t.get_text() for t in drawn["contact_force"].axes[1].texts} == {"first contact", "docked"}


def test_a_budget_far_above_the_forces_is_named_not_drawn(tmp_path, drawn):
    run(tmp_path, series(peak=3.0), RunMarks(budget=50.0))
    ax = drawn["contact_force"].axes[0]
    assert not [line for line in ax.lines if list(line.get_ydata()) == [50.0, 50.0]]
    assert any("budget 50 N: above the scale" in t.get_text() for t in ax.texts)
    assert ax.get_ylim()[1] < 10  # the 3 N strike fills the panel


def test_tracking_test_draws_paths_segments_and_thresholds_but_no_contact_force(tmp_path, drawn):
    segments = tuple(segment_times(1.5, 5.0, 5.0))
    limits = {"circle_position_rms_m": 0.005, "figure8_position_rms_m": 0.005, "position_peak_m": 0.015,
              "orientation_rms_rad": 0.0087}  # fmt: skip
    run(
        tmp_path,
        series(contact_at=None, duration=15.0),
        RunMarks(free_space=True, segments=segments, thresholds=limits),
    )
    assert set(drawn) == {"tcp_tracking", "tracking_error", "joint_torques", "tracking_path"}
    paths = drawn["tracking_path"].axes
    assert [ax.get_xlabel() + " " + ax.get_ylabel() for ax in paths] == ["y [m] z [m]", "x [m] y [m]"]
    assert all(len(ax.lines) == 2 for ax in paths)  # reference and actual
    error = drawn["tracking_error"].axes[0]
    starts = sorted(line.get_xdata()[0] for line in error.lines if line.get_linestyle() == ":")
    assert starts == pytest.approx([0.0, 1.5, 6.5, 8.0, 13.0])  # every boundary, the end too
    names = {t.get_text() for t in error.texts}
    assert names == {"tr. 1", "circle", "tr. 2", "figure-8"}
    limit_values = sorted({round(float(s[0][1]), 6) for c in error.collections for s in c.get_segments()})
    assert limit_values == [5.0, 15.0]  # RMS limits and the peak limit, in mm


def test_no_offset_notation_on_the_axes(tmp_path, drawn):
    run(tmp_path, series(), RunMarks(budget=50.0))
    for fig in drawn.values():
        fig.canvas.draw()
        for ax in fig.axes:
            assert ax.yaxis.get_offset_text().get_text() == "", ax.get_ylabel()
    x_axis = drawn["tcp_tracking"].axes[0]
    low, high = x_axis.get_ylim()
    assert high - low >= 2e-3 - 1e-12  # a held coordinate gets a 2 mm span, not µm ticks


@pytest.mark.parametrize("first_row", [0, 1, 1234, None])
def test_the_first_contact_mark_is_the_metrics_first_contact_time(first_row):
    """The figure marks first contact where the metrics put ``first_contact_time_s``: the
    state before the first row with contacts (row 0 when that is the first), none without."""
    import pinocchio as pin

    from compliant_docking.evaluation.contact import contact_metrics

    ts = series(contact_at=None)
    ts["vx"], ts["vy"], ts["vz"] = 0.0, 0.0, 0.0
    if first_row is not None:
        ts.loc[first_row:, "contacts"] = 1
    metric = contact_metrics(ts, pin.SE3.Identity(), steady_window=1.0, strike_window=0.1)[
        "first_contact_time_s"
    ]
    expected = None if first_row is None else ts["t"].iloc[max(first_row - 1, 0)]
    assert run_figures.first_contact_time(ts) == metric == expected
