"""The comparison figures draw every configuration: one panel or line per configuration,
counted on the artists, and a note on the figure for what they pool or leave out."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import QuadMesh
from matplotlib.container import BarContainer, ErrorbarContainer

from compliant_docking.results.figures import (
    force_overlay,
    metric_bars,
    success_map,
    success_vs_error,
    success_vs_misalignment,
)
from compliant_docking.run import rundir


def runs(tmp_path, repeats: int, *, robots=("iiwa14", "fr3"), controllers=("impedance", "hqp"),
         trajectories=("quintic", "se3topp"), touching=True) -> pd.DataFrame:  # fmt: skip
    """Jobs as load_runs returns them, each with a time series: a strike of (2 + job) N at
    t = 1 s on a 1 ms grid (contacts from then on), the last run never touching."""
    rows = []
    rng = np.random.default_rng(0)
    for robot in robots:
        for controller in controllers:
            for trajectory in trajectories:
                for seed in range(repeats):
                    n = len(rows)
                    run_dir = tmp_path / f"{n}"
                    run_dir.mkdir()
                    t = np.arange(0.0, 2.0, 0.001)
                    contacts = (t >= 1.0).astype(int) if touching or n else np.zeros_like(t, dtype=int)
                    fz = np.where(t >= 1.0, 2.0 + n + np.exp(-(t - 1.0) * 50), 0.0) * contacts
                    rundir.write_timeseries(
                        run_dir,
                        pd.DataFrame({"t": t, "contacts": contacts, "fx": 0.0 * t, "fy": 0.0 * t, "fz": fz}),
                    )
                    tilt, lateral = rng.uniform(0, 3), rng.uniform(0, 0.012)
                    rows.append(
                        {
                            "run_dir": str(run_dir), "job": f"{n}_job", "status": "ok", "error": None,
                            "success": bool(tilt < 1.8 and lateral < 0.011),
                            "gate_failures": None if tilt < 1.8 else "seat depth error 0.003 m > 0.001 m",
                            "robot": robot, "controller": controller, "trajectory": trajectory,
                            "overridden": "robot,controller,trajectory,task.misalignment.seed",
                            "task.misalignment.seed": seed, "task.stroke": "[0.0, 0.0, 1.0]",
                            "task.gate.peak_force_budget_N": 50.0,
                            "misalignment_lateral_m": lateral, "misalignment_tilt_deg": tilt,
                            "misalignment_yaw_deg": rng.uniform(-180, 180),
                            "peak_axial_force_N": 2.0 + n,
                        }
                    )  # fmt: skip
    return pd.DataFrame(rows)


def _traces(ax, kind: str) -> set[str]:
    return {str(a.get_gid()).split(":", 1)[1] for a in [*ax.lines, *ax.collections]
            if str(a.get_gid()).startswith(kind + ":")}  # fmt: skip


def test_force_overlay_draws_every_run_in_a_panel_per_robot_and_controller(tmp_path):
    df = runs(tmp_path, repeats=1, touching=False)
    fig = force_overlay(df)
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in axes] == [
        "iiwa14 · impedance",
        "iiwa14 · hqp",
        "fr3 · impedance",
        "fr3 · hqp",
    ]
    for ax in axes:  # one line per planner: both configurations of the panel
        assert len([line for line in ax.lines if str(line.get_gid()).startswith("run:")]) in (1, 2)
    # the first run never touched: named on the figure, the other 7 drawn
    assert sum(len(_traces(ax, "run")) for ax in axes) == 7  # 8 configurations, one never touched
    notes = " ".join(t.get_text() for t in fig.texts)
    assert "not shown, no readable time series or no contact: 1 runs (0_job)" in notes
    assert "budget 50 N: above" in " ".join(t.get_text() for ax in axes for t in ax.texts)  # 2-9 N drawn


def test_force_overlay_draws_median_and_band_with_many_runs(tmp_path):
    df = runs(tmp_path, repeats=5, robots=("fr3",), controllers=("hqp",))
    fig = force_overlay(df)
    [ax] = fig.axes
    assert _traces(ax, "median") == _traces(ax, "band") == {"quintic", "se3topp"}
    assert not _traces(ax, "run")
    assert "median and 10–90 % band" in " ".join(t.get_text() for t in fig.texts)
    # the window: 50 ms before the first contact to 0.6 s after
    assert ax.get_xlim()[0] < -0.04 and ax.get_xlim()[1] > 0.59


def test_success_figures_show_every_controller_with_intervals(tmp_path):
    df = runs(tmp_path, repeats=6, trajectories=("quintic",), controllers=("impedance", "hqp", "se3_lie"))
    fig = success_vs_misalignment(df)
    top = fig.axes[:2]  # lateral and tilt (the yaw only turns the tilt of a round socket)
    assert [ax.get_xlabel() for ax in fig.axes[2:4]] == ["lateral error [mm]", "tilt error [deg]"]
    for ax in top:
        assert len([c for c in ax.containers if isinstance(c, ErrorbarContainer)]) == 3  # one per controller
    assert "pooled over: robot" in " ".join(t.get_text() for t in fig.texts)

    fig = success_map(df)
    panels = [ax for ax in fig.axes if any(isinstance(c, QuadMesh) for c in ax.collections)]
    assert len(panels) == 2 * 3  # robot × controller
    assert {ax.get_title() for ax in panels} == {f"{r} · {c}" for r in ("iiwa14", "fr3")
                                                for c in ("impedance", "hqp", "se3_lie")}  # fmt: skip
    labels = {t.get_text() for t in fig.legends[0].texts}
    assert "docked" in labels and "stuck short of the seat (jammed/wedged)" in labels


def test_success_against_the_drawn_errors_bins_their_size_per_controller(tmp_path):
    """success_vs_error: one panel per drawn error that varies (the link mass error measured
    from 1, in %), one line per controller; the rate in each bin is the share of its jobs
    that docked (here: docked exactly when the link mass error is under 1 %)."""
    df = runs(tmp_path, repeats=8, trajectories=("quintic",), controllers=("impedance", "hqp"))
    rng = np.random.default_rng(1)
    df["model_error_link_mass_scale"] = rng.uniform(0.98, 1.02, len(df))
    df["model_error_tool_mass_kg"] = 0.0  # not varied: no panel
    df["success"] = (df["model_error_link_mass_scale"] - 1.0).abs() < 0.01
    fig = success_vs_error(df)
    assert [ax.get_xlabel() for ax in fig.axes[1:2]] == ["link mass error [%]"]
    bars = [c for c in fig.axes[0].containers if isinstance(c, ErrorbarContainer)]
    assert len(bars) == 2
    for line in bars:
        rate = np.asarray(line.lines[0].get_data()[1])
        assert rate[0] == 100.0 and rate[-1] == 0.0  # the smallest errors docked, the largest did not
    df = df.drop(columns=["model_error_link_mass_scale"])
    assert success_vs_error(df) is None


def test_success_map_needs_both_errors():
    df = pd.DataFrame({"misalignment_lateral_m": [0.0, 0.001], "misalignment_tilt_deg": [0.0, 0.0],
                       "status": "ok", "success": True})  # fmt: skip
    assert success_map(df) is None


@pytest.mark.parametrize("controllers", [("impedance",), ("impedance", "hqp", "se3_lie")])
def test_metric_bars_draw_one_bar_per_configuration(tmp_path, controllers):
    df = runs(tmp_path, repeats=2, controllers=controllers)
    fig = metric_bars(df)
    configurations = len(controllers) * 2 * 2
    panel = next(ax for ax in fig.axes if ax.get_title() == "peak axial force (raw, per step) [N]")
    bars = [b for c in panel.containers if isinstance(c, BarContainer) for b in c]
    assert len(bars) == configurations
    heights = sorted(b.get_height() for b in bars)
    means = sorted(df.groupby(["robot", "controller", "trajectory"])["peak_axial_force_N"].mean())
    assert heights == pytest.approx(means)
