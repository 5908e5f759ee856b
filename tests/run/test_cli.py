"""The command line, through a real process: the default docking with its run directory and
the exit statuses (0 docked, 1 failed, 3 gate not passed); --help: tests/test_cli.py."""

import json

import numpy as np
import pandas as pd
import pytest

from tests.helpers import run_cli

#: a short docking (1 s stroke, 1 s settling): enough to finish with status ok
SHORT = ("trajectory.duration=1", "task.settle_time=1", "task.progress=false", "figures=false")


def test_the_default_docking_succeeds_and_writes_the_run_directory(tmp_path):
    """`python -m compliant_docking`: the default scene docks (exit 0) and the run directory
    is complete. Expected: seated (depth < 1 mm), inside the bore's 0.4 mm radial
    clearance (+0.1 mm: the 30° chamfer's centring play), pressed home by the reference's
    5 mm press past the seat with k·5 mm = 0.25 N (measured 0.24999 N; 0.1 %: the tip
    rests 7 µm off the axis, nothing else loads the spring), and a peak force of 1.37 N
    (±10 %: a one-step contact impulse, the value most sensitive to round-off across
    MuJoCo builds; the earth twin in tests/run/test_runner.py has its own)."""
    run_dir = tmp_path / "run"
    result = run_cli(f"hydra.run.dir={run_dir}", "task.progress=false")
    assert result.returncode == 0, result.stderr[-2000:]
    assert "success true" in result.stdout
    for name in ("metrics.json", "timeseries.parquet", "summary.txt", ".hydra/config.yaml"):
        assert (run_dir / name).is_file(), name
    for stem in ("tcp_tracking", "tracking_error", "contact_force", "joint_torques"):
        assert (run_dir / "figures" / f"{stem}.png").stat().st_size > 1000
    assert not list((run_dir / "figures").glob("*.pdf"))  # PDF on request (report --formats)
    record = json.loads((run_dir / "metrics.json").read_text())
    assert record["status"] == "ok" and record["error"] is None and record["controller"] == "impedance"
    assert record["success"] is True, record["gate_failures"]
    assert record["seat_depth_error_m"] < 1e-3
    assert record["seat_lateral_error_m"] < 0.4e-3 + 1e-4
    assert record["steady_axial_force_N"] == pytest.approx(50.0 * 0.005, rel=1e-3)
    assert record["peak_axial_force_N"] == pytest.approx(1.37, rel=0.1)
    assert record["sim_time_s"] == pytest.approx(18.0)
    ts = pd.read_parquet(run_dir / "timeseries.parquet")
    assert len(ts) == 18000 and np.isfinite(ts.drop(columns=["torque_saturated"]).to_numpy(float)).all()
    assert not list(run_dir.glob(".*.tmp")) and not list(run_dir.glob("*.tmp"))


def test_a_docking_gate_failure_exits_3(tmp_path):
    """A run that finishes (status ok) but is never within 1 nm of the seat."""
    run_dir = tmp_path / "run"
    result = run_cli(f"hydra.run.dir={run_dir}", *SHORT, "task.gate.depth_tolerance_m=1e-9")
    assert result.returncode == 3, result.stdout[-2000:] + result.stderr[-2000:]
    record = json.loads((run_dir / "metrics.json").read_text())
    assert record["status"] == "ok" and record["success"] is False
    assert record["gate_failures"].startswith("not seated: ")


def test_a_runtime_failure_exits_1(tmp_path):
    """A config that passes every check but cannot run (a socket out of the arm's reach):
    status failed, exit 1. A value the checks refuse (a zero stroke) exits 2 before any
    run directory exists (tests/sweep/test_guard.py)."""
    run_dir = tmp_path / "run"
    result = run_cli(f"hydra.run.dir={run_dir}", *SHORT, "target.pos=[3.0,0.0,0.2]")
    assert result.returncode == 1, result.stdout[-2000:] + result.stderr[-2000:]
    record = json.loads((run_dir / "metrics.json").read_text())
    assert record["status"] == "failed" and "inverse kinematics" in record["error"]
    refused = run_cli(f"hydra.run.dir={tmp_path / 'refused'}", *SHORT, "task.stroke=[0,0,0]")
    assert refused.returncode == 2 and "task.stroke must be a non-zero vector" in refused.stderr
    assert not (tmp_path / "refused").exists()
