"""load_runs and the summaries: single runs, sweeps, nested trees, unfinished directories."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from omegaconf import OmegaConf

from compliant_docking import report
from compliant_docking.results import (
    BASE_COLUMNS,
    RunSkippedWarning,
    comparison_markdown,
    comparison_table,
    configuration_keys,
    configuration_labels,
    counts,
    load_runs,
    scan,
    write_summary,
)
from compliant_docking.run.rundir import find_job_dirs, parse_override
from compliant_docking.run.runner import execute
from tests.helpers import make_cfg

# short runs (2 s simulated); settle_time ≥ 1 s leaves room for the end-of-motion press
SHORT = ("task.progress=false", "trajectory.duration=1", "task.settle_time=1")


def fake_job(path: Path, overrides: list[str], **metrics) -> Path:
    """A job directory as Hydra + runner leave it: .hydra/overrides.yaml and metrics.json."""
    (path / ".hydra").mkdir(parents=True)
    (path / ".hydra" / "overrides.yaml").write_text("".join(f"- {o}\n" for o in overrides))
    record = {
        "status": "ok",
        "error": None,
        "success": True,
        "robot": "iiwa14",
        "controller": "impedance",
        "trajectory": "quintic",
        "peak_axial_force_N": 10.0,
        "pos_tracking_rms_m": 0.001,
        **metrics,
    }
    (path / "metrics.json").write_text(json.dumps(record))
    return path


@pytest.fixture(scope="module")
def real_run(tmp_path_factory) -> Path:
    """One real (short) run written by runner.execute, without Hydra's .hydra folder."""
    run_dir = tmp_path_factory.mktemp("single") / "run"
    execute(make_cfg(*SHORT), run_dir, figures=False, echo=False)
    return run_dir


def test_single_run_directory(real_run):
    df = load_runs(real_run)
    assert len(df) == 1
    assert list(df.columns[: len(BASE_COLUMNS)]) == list(BASE_COLUMNS)
    row = df.iloc[0]
    assert row["run_dir"] == str(real_run.resolve()) and row["job"] == "run"
    assert row["status"] == "ok" and row["controller"] == "impedance"
    saved = json.loads((real_run / "metrics.json").read_text())
    assert set(saved) <= set(df.columns)  # every metric is a column
    assert row["peak_axial_force_N"] == pytest.approx(saved["peak_axial_force_N"])
    assert pd.api.types.is_float_dtype(df["misalignment_x_m"])


def test_a_file_path_reads_its_directory(real_run):
    assert len(load_runs(real_run / "metrics.json")) == 1


def test_sweep_directory_with_overrides_as_columns(tmp_path):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    (sweep / "multirun.yaml").write_text("hydra: {}\n")
    fake_job(
        sweep / "0_controller=impedance,robot=fr3",
        [
            "controller=impedance",
            "robot=fr3",
            "target.geometry.radial_clearance=0.0004",
            "+experiment=clearance",
        ],
        robot="fr3",
    )
    fake_job(
        sweep / "1_controller=hqp,robot=fr3",
        [
            "controller=hqp",
            "robot=fr3",
            "target.geometry.radial_clearance=0.0008",
            "+experiment=clearance",
            "task.stroke=[0,0,-0.1]",
        ],
        robot="fr3",
        controller="hqp",
    )
    fake_job(
        sweep / "10_x",
        ["controller=hqp", "robot=fr3", "target.geometry.radial_clearance=0.0016", "+experiment=clearance"],
        robot="fr3",
        controller="hqp",
        status="failed",
        error="boom",
        success=False,
        peak_axial_force_N=None,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to warn about here
        df = load_runs(sweep)
    assert list(df["job"]) == ["0_controller=impedance,robot=fr3", "1_controller=hqp,robot=fr3", "10_x"]
    assert list(df["controller"]) == ["impedance", "hqp", "hqp"]
    assert list(df["target.geometry.radial_clearance"]) == [0.0004, 0.0008, 0.0016]
    assert pd.api.types.is_float_dtype(df["target.geometry.radial_clearance"])
    assert list(df["experiment"]) == ["clearance"] * 3  # "+" prefix dropped
    assert df["task.stroke"].iloc[1] == "[0,0,-0.1]" and pd.isna(df["task.stroke"].iloc[0])
    assert pd.isna(df["peak_axial_force_N"].iloc[2])  # JSON null → NaN
    assert df["error"].iloc[2] == "boom"
    assert configuration_keys(df) == ["controller", "target.geometry.radial_clearance", "task.stroke"]
    labels = configuration_labels(df)
    assert labels.iloc[0] == "impedance · clearance 0.4 mm · stroke=default"  # short, in its unit


def test_nested_trees_and_unfinished_directories_are_skipped_with_a_warning(tmp_path):
    root = tmp_path / "runs"
    fake_job(root / "2025-01-01" / "10-00-00_iiwa14_impedance_quintic", [])
    fake_job(root / "multirun" / "2025-01-01" / "11-00-00" / "0_robot=fr3", ["robot=fr3"], robot="fr3")
    running = root / "multirun" / "2025-01-01" / "11-00-00" / "1_robot=iiwa14"
    (running / ".hydra").mkdir(parents=True)  # started, no metrics.json yet (or crashed)
    half = fake_job(root / "multirun" / "2025-01-01" / "11-00-00" / "2_robot=iiwa14", ["robot=iiwa14"])
    (half / "metrics.json").write_text('{"status": "ok", "succ')  # half-written
    listy = fake_job(root / "odd", [])
    (listy / "metrics.json").write_text("[1, 2]")  # valid JSON, not an object
    (root / "multirun" / "2025-01-01" / "11-00-00" / "multirun.yaml").write_text("x: 1\n")
    (root / "notes").mkdir()  # not a job

    assert len(find_job_dirs(root)) == 5
    with pytest.warns(RunSkippedWarning) as caught:
        df = load_runs(root)
    assert len(df) == 2
    assert set(df["robot"]) == {"iiwa14", "fr3"}
    messages = " ".join(str(w.message) for w in caught)
    assert "1_robot=iiwa14" in messages and "no metrics.json" in messages
    assert "2_robot=iiwa14" in messages and "not valid JSON" in messages
    assert "odd" in messages and "not a JSON object" in messages
    frame, skipped = scan(root)
    assert len(frame) == 2 and len(skipped) == 3


def test_empty_and_missing_paths(tmp_path):
    df = load_runs(tmp_path)
    assert df.empty and list(df.columns) == list(BASE_COLUMNS)
    with pytest.raises(FileNotFoundError):
        load_runs(tmp_path / "nope")


def test_parse_override_forms():
    assert parse_override("controller=hqp") == ("controller", "hqp")
    assert parse_override("+experiment=misalignment") == ("experiment", "misalignment")
    assert parse_override("++task.settle_time=1") == ("task.settle_time", 1)
    assert parse_override("controller.k=1e2") == ("controller.k", 100.0)
    assert parse_override("task.misalignment.x_range=[-0.001,0.001]") == (
        "task.misalignment.x_range",
        "[-0.001,0.001]",
    )
    assert parse_override("~task.duration") == ("task.duration", None)


def test_comparison_pools_repeats_and_counts_outcomes(tmp_path):
    """Four seeds of one configuration (the last failed) and one failed job of another:
    metrics are the mean over the jobs that have them (10, 40, 90 N → 46.67 N, where the
    median would be 40 N); the success rate is docked / all jobs (3/4, not 3/3)."""
    for seed in range(4):
        failed = seed == 3
        fake_job(
            tmp_path / f"{seed}_a",
            ["controller=impedance", f"task.misalignment.seed={seed}"],
            status="failed" if failed else "ok",
            error="diverged" if failed else None,
            success=not failed,
            peak_axial_force_N=None if failed else 10.0 * (seed + 1) ** 2,
        )
    fake_job(
        tmp_path / "4_b",
        ["controller=hqp", "task.misalignment.seed=0"],
        controller="hqp",
        status="failed",
        error="diverged",
        success=False,
        peak_axial_force_N=None,
    )
    df = load_runs(tmp_path)
    assert configuration_keys(df) == ["controller"]  # the seed repeats a configuration
    table = comparison_table(df)
    assert list(table.columns) == ["impedance", "hqp"]
    assert table.loc[
        ("contact safety", "peak axial force (raw, per step) [N]"), "impedance"
    ] == pytest.approx(140.0 / 3)
    assert table.loc[("tracking accuracy", "position RMS, whole run [mm]"), "impedance"] == pytest.approx(1.0)
    assert (
        table.loc[("success", "jobs"), "impedance"] == 4
        and table.loc[("success", "failed"), "impedance"] == 1
    )
    assert table.loc[("success", "success rate"), "impedance"] == pytest.approx(0.75)
    assert table.loc[("success", "failed"), "hqp"] == 1
    assert table.loc[("success", "success rate"), "hqp"] == 0.0
    assert np.isnan(
        table.loc[("contact safety", "peak axial force (raw, per step) [N]"), "hqp"]
    )  # no value: n/a
    text = comparison_markdown(table)
    assert "**contact safety**" in text and "75 %" in text and "n/a" in text
    assert counts(df).line() == "5 jobs: 3 finished (3 docked, 0 not docked), 2 failed"


def test_write_summary_and_report_command(tmp_path, capsys):
    fake_job(tmp_path / "0_a", ["controller=impedance", "task.stroke=[0,0,-0.1]"])
    fake_job(
        tmp_path / "1_b",
        ["controller=hqp", "controller.K0=[1,2,3,4,5,6]"],
        controller="hqp",
        status="failed",
        error="bad | value",
        success=False,
    )
    paths = write_summary(load_runs(tmp_path), tmp_path, title="t")
    back = pd.read_parquet(paths["summary.parquet"])
    assert len(back) == 2 and len(pd.read_csv(paths["summary.csv"])) == 2
    md = paths["summary.md"].read_text()
    assert (
        "## Comparison: the docking metrics (Ren & Shan 2026, Table 10)" in md
        and "| 1_b " in md
        and "bad / value" in md
    )

    assert report.main([str(tmp_path), "--no-figures"]) == 0
    out = capsys.readouterr().out
    assert "2 jobs: 1 finished (1 docked, 0 not docked), 1 failed" in out and "peak axial force" in out
    assert report.main([str(tmp_path / "nothing")]) == 2


def test_report_draws_the_comparison_figures(real_run, tmp_path):
    out = tmp_path / "out"
    assert report.main([str(real_run), "--out", str(out)]) == 0
    assert (out / "comparison" / "force_overlay.png").stat().st_size > 1000
    assert not (out / "comparison" / "force_overlay.pdf").exists()  # PNG unless asked
    # one configuration: no bars to compare; nothing misaligned: no success curve
    assert sorted(p.name for p in (out / "comparison").iterdir()) == ["force_overlay.png"]
    assert report.main([str(real_run), "--out", str(out), "--formats", "png", "pdf"]) == 0
    assert (out / "comparison" / "force_overlay.pdf").stat().st_size > 1000
    assert report.main([str(real_run), "--formats", "gif"]) == 2  # refused, naming the formats

    two = tmp_path / "two"  # two controllers: the bars compare them
    fake_job(two / "0_a", ["controller=impedance"])
    fake_job(two / "1_b", ["controller=hqp"], controller="hqp")
    assert report.main([str(two), "--formats", "png", "pdf"]) == 0
    for fmt in ("png", "pdf"):
        assert (two / "comparison" / f"table10_bars.{fmt}").stat().st_size > 1000


def test_report_draws_the_runs_own_figures_on_demand(tmp_path, capsys):
    """A sweep job leaves out its figures; ``report --runs`` draws them from its files."""
    from compliant_docking.run.figures import redraw

    run_dir = tmp_path / "job"
    cfg = make_cfg(*SHORT)
    execute(cfg, run_dir, figures=False, echo=False)
    assert not (run_dir / "figures").exists()
    (run_dir / ".hydra").mkdir()  # as Hydra leaves it: the composed config
    (run_dir / ".hydra" / "config.yaml").write_text(OmegaConf.to_yaml(cfg))
    fake_job(tmp_path / "failed", ["controller=hqp"], status="failed", error="x", success=False)
    assert report.main([str(tmp_path), "--runs", "--no-figures", "--formats", "png", "pdf"]) == 0
    out = capsys.readouterr()
    assert "drew the figures of 1 of 2 runs" in out.out
    assert "failed: no timeseries.parquet" in out.err  # named, not fatal
    stems = ("tcp_tracking", "tracking_error", "contact_force", "joint_torques")
    for stem in stems:
        for fmt in ("png", "pdf"):
            assert (run_dir / "figures" / f"{stem}.{fmt}").stat().st_size > 1000
    with pytest.raises(ValueError, match="config.yaml"):  # the limits and axis come from it
        (run_dir / ".hydra" / "config.yaml").unlink()
        redraw(run_dir)


def _sweep(root: Path, *parts: str, mtime: float | None = None) -> Path:
    """An empty sweep directory (multirun.yaml only), optionally with a modification time."""
    import os

    path = root.joinpath(*parts)
    path.mkdir(parents=True)
    (path / "multirun.yaml").write_text("hydra: {}\n")
    if mtime is not None:
        os.utime(path / "multirun.yaml", (mtime, mtime))
        os.utime(path, (mtime, mtime))
    return path


def test_newest_sweep_is_the_latest_start_in_the_names_not_the_last_touched(tmp_path):
    import os
    import time

    from compliant_docking.results import newest_sweep, sweep_started

    old = _sweep(tmp_path, "2025-06-01", "09-00-00_misalignment")
    new = _sweep(tmp_path, "2025-06-01", "14-03-12")
    _sweep(tmp_path, "2025-05-31", "23-59-59")
    # a report written into the old sweep now: its folder and files are the newest on disk
    (old / "summary.md").write_text("# report\n")
    later = time.time() + 3600
    os.utime(old, (later, later))
    os.utime(old / "multirun.yaml", (later, later))
    assert newest_sweep(tmp_path) == new
    assert sweep_started(old).strftime("%Y-%m-%d %H:%M:%S") == "2025-06-01 09:00:00"
    assert newest_sweep(tmp_path / "nothing-here") is None


def test_sweeps_named_otherwise_are_dated_by_their_multirun_yaml(tmp_path):
    from datetime import datetime

    from compliant_docking.results import newest_sweep

    named = _sweep(tmp_path, "2025-06-01", "14-03-12")
    named_time = datetime(2025, 6, 1, 14, 3, 12).timestamp()
    _sweep(tmp_path, "custom", mtime=named_time - 60)  # started a minute before
    assert newest_sweep(tmp_path) == named
    later = _sweep(tmp_path, "custom2", mtime=named_time + 60)  # a minute after
    assert newest_sweep(tmp_path) == later


def test_locate_runs_reads_relative_paths_from_the_working_directory_then_the_base(tmp_path, monkeypatch):
    from compliant_docking.results import locate_runs
    from tests.helpers import REPO_ROOT

    monkeypatch.chdir(tmp_path)  # like a notebook running in analysis/
    assert locate_runs("conf", base=REPO_ROOT) == (REPO_ROOT / "conf").resolve()
    (tmp_path / "conf").mkdir()
    assert locate_runs("conf", base=REPO_ROOT) == (tmp_path / "conf").resolve()  # the working directory first
    assert locate_runs(tmp_path) == tmp_path.resolve()
    with pytest.raises(FileNotFoundError, match="no directory 'runs/multirun/nope'"):
        locate_runs("runs/multirun/nope", base=REPO_ROOT)
    with pytest.raises(FileNotFoundError, match="no directory 'assets'"):
        locate_runs("assets")  # without a base: the working directory only


def test_a_failed_or_interrupted_job_never_counts_as_docked(tmp_path, capsys):
    """A record whose status is failed or interrupted but whose ``success`` says true (a
    hand-edited file, another writer) is read as not docked by every reader: load_runs,
    the counts and tables, report, the progress line."""
    from compliant_docking.run.rundir import read_metrics
    from compliant_docking.sweep.progress import job_line

    fake_job(tmp_path / "0_a", ["controller.k=1"], status="failed", error="diverged", success=True)
    fake_job(tmp_path / "1_b", ["controller.k=2"], status="interrupted", error="SIGINT", success=True)
    fake_job(tmp_path / "2_c", ["controller.k=3"])  # finished and docked
    assert [read_metrics(tmp_path / d)[0]["success"] for d in ("0_a", "1_b", "2_c")] == [False, False, True]
    df = load_runs(tmp_path)
    assert df.set_index("job")["success"].to_dict() == {"0_a": False, "1_b": False, "2_c": True}
    assert counts(df).line() == "3 jobs: 1 finished (1 docked, 0 not docked), 2 failed"
    assert report.main([str(tmp_path), "--no-figures"]) == 0
    assert "3 jobs: 1 finished (1 docked, 0 not docked), 2 failed" in capsys.readouterr().out
    assert "docked" not in job_line(tmp_path / "0_a", tmp_path, 3, done=1).split(" · ")[1:3]
