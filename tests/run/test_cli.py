"""The command line: the default docking with its run directory and the exit statuses (0
docked, 1 failed, 3 gate not passed), its main in this process (a process's exit status is
main's, `sys.exit(main())`: 130 and 143 through a real process in tests/run/test_interrupt.py,
the console script against main in tests/test_cli.py); --help: tests/test_cli.py."""

import json
import os

import numpy as np
import pandas as pd
import pytest

from tests.helpers import cli_in_process_output, run_cli

#: a short docking (1 s stroke, 1 s settling): enough to finish with status ok
SHORT = ("trajectory.duration=1", "task.settle_time=1", "task.progress=false", "figures=false")


def test_the_default_docking_succeeds_and_writes_the_run_directory(tmp_path, capsys):
    """`python -m compliant_docking`: the default scene docks (exit 0) and the run directory
    is complete. Expected: seated (depth < 1 mm), inside the bore's 0.4 mm radial
    clearance (+0.1 mm: the 30° chamfer's centring play), pressed home by the reference's
    5 mm press past the seat with k·5 mm = 0.25 N (measured 0.24999 N; 0.1 %: the tip
    rests 7 µm off the axis, nothing else loads the spring), and a peak force of 1.37 N
    (±10 %: a one-step contact impulse, the value most sensitive to round-off across
    MuJoCo builds; the earth twin in tests/run/test_runner.py has its own)."""
    run_dir = tmp_path / "run"
    code, out, err = cli_in_process_output(capsys, f"hydra.run.dir={run_dir}", "task.progress=false")
    assert code == 0, err[-2000:]
    assert "success true" in out
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


@pytest.mark.slow(
    reason="in-process proof: tests/test_exit_codes.py::test_a_failed_run_exits_1_and_an_undocked_one_3; "
    "a process's exit status is main's: tests/run/test_interrupt.py's signalled runs (130, 143)"
)
def test_a_docking_gate_failure_exits_3(tmp_path):
    """A run that finishes (status ok) but is never within 1 nm of the seat."""
    run_dir = tmp_path / "run"
    result = run_cli(f"hydra.run.dir={run_dir}", *SHORT, "task.gate.depth_tolerance_m=1e-9")
    assert result.returncode == 3, result.stdout[-2000:] + result.stderr[-2000:]
    record = json.loads((run_dir / "metrics.json").read_text())
    assert record["status"] == "ok" and record["success"] is False
    assert record["gate_failures"].startswith("not seated: ")


@pytest.mark.slow(
    reason="in-process proof: tests/test_exit_codes.py::test_a_failed_run_exits_1_and_an_undocked_one_3; "
    "a process's exit status is main's: tests/run/test_interrupt.py's signalled runs (130, 143)"
)
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


# --------------------------------------------------------------------------- in this process
def _trap_the_sweep_package(monkeypatch) -> None:
    """Every function of the sweep's guard, directories and resume, and the sweep guard's
    check, raise."""
    import inspect

    from compliant_docking.sweep import directories, guard, resume

    def trap(*args, **kwargs):
        raise AssertionError("a single run went through the sweep package")

    for module in (guard, directories, resume):
        for name, obj in list(vars(module).items()):
            if inspect.isfunction(obj) and obj.__module__ == module.__name__:
                monkeypatch.setattr(module, name, trap)
    # Hydra instantiates every configured callback in both modes and calls its hooks: the
    # sweep guard's own work is on_multirun_start (its on_job_start does nothing in a run)
    monkeypatch.setattr(guard.SweepGuard, "on_multirun_start", trap)


def test_a_single_run_goes_through_the_run_layer_only(tmp_path, monkeypatch, capsys):
    """The checks, the refusals and the directory claim of one run are the run layer's
    (run/guard.py, run/directories.py): with the sweep's guard, directories and resume
    made to raise, a run still refuses a bad value and a used directory."""
    from tests.helpers import cli_in_process

    _trap_the_sweep_package(monkeypatch)
    held = tmp_path / "held"
    held.mkdir()
    (held / "x").write_text("")
    code, err = cli_in_process(capsys, f"hydra.run.dir={held}")
    assert code == 2 and "is not empty (x)" in err, err
    code, err = cli_in_process(capsys, "controller.k=-1", f"hydra.run.dir={tmp_path / 'bad'}")
    assert code == 2 and "controller.k" in err and not (tmp_path / "bad").exists(), err


@pytest.mark.slow
def test_a_single_run_runs_without_the_sweep_package(tmp_path, monkeypatch, capsys):
    """The task of one run (its execution, summary and record) with the sweep's guard,
    directories and resume made to raise (a few seconds: the fast twin above checks the
    guard's path)."""
    from tests.helpers import cli_in_process_output

    _trap_the_sweep_package(monkeypatch)
    run_dir = tmp_path / "run"
    short = ("task.duration=0.05", "task.progress=false", "figures=false", "output.timeseries=false")
    code, out, err = cli_in_process_output(capsys, f"hydra.run.dir={run_dir}", *short)
    assert code in (0, 3) and (run_dir / "metrics.json").is_file(), out + err


def test_a_command_leaves_the_process_as_it_found_it(tmp_path, monkeypatch, capsys):
    """Hydra's process-wide HydraConfig and its error switch (HYDRA_FULL_ERROR, which the
    command sets to report Hydra's errors itself) are put back after a command run in this
    process: a later run through the Python API does not take this one's overrides."""
    from hydra.core.hydra_config import HydraConfig

    from compliant_docking.cli import main

    monkeypatch.delenv("HYDRA_FULL_ERROR", raising=False)
    held = tmp_path / "held"
    held.mkdir()
    (held / "x").write_text("")
    assert not HydraConfig.initialized()
    with pytest.raises(SystemExit) as refused:  # refused after the run's config was set
        main([f"hydra.run.dir={held}", "controller.k=60"])
    assert refused.value.code == 2 and "is not empty" in capsys.readouterr().err
    assert not HydraConfig.initialized() and "HYDRA_FULL_ERROR" not in os.environ


def test_an_unexpected_error_exits_1_with_its_traceback(tmp_path, monkeypatch, capsys):
    """An error nobody reports (a bug) ends the command with status 1 and its traceback,
    as Hydra's own reporter did; with HYDRA_FULL_ERROR=1 set by the user it propagates."""
    from compliant_docking.cli import main
    from compliant_docking.run import runner

    def broken(*args, **kwargs):
        raise RuntimeError("a bug in the runner")

    monkeypatch.setattr(runner, "execute", broken)
    monkeypatch.delenv("HYDRA_FULL_ERROR", raising=False)
    with pytest.raises(SystemExit) as failed:
        main([f"hydra.run.dir={tmp_path / 'a'}"])
    err = capsys.readouterr().err
    assert failed.value.code == 1 and "Traceback" in err and "RuntimeError: a bug in the runner" in err
    monkeypatch.setenv("HYDRA_FULL_ERROR", "1")
    with pytest.raises(RuntimeError, match="a bug in the runner"):
        main([f"hydra.run.dir={tmp_path / 'b'}"])
    assert os.environ["HYDRA_FULL_ERROR"] == "1"
