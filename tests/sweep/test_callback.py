"""Sweeps end to end (joblib, 2 workers): failure isolation, summary, exit status, crashes."""

from __future__ import annotations

import json
import multiprocessing
import re
from pathlib import Path

import pandas as pd
import pytest
from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from hydra.core.override_parser.overrides_parser import OverridesParser
from omegaconf import OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.config import register_schemas
from compliant_docking.sweep.callback import expected_jobs
from compliant_docking.sweep.outcome import ORPHAN_ERROR, SweepOutcome
from compliant_docking.sweep.progress import COUNT_FILE, job_line, next_count, remove_count, reset_count
from compliant_docking.sweep.session import SweepSession
from tests.helpers import SHORT_SWEEP as SHORT
from tests.helpers import TESTS, sweep_cli


def test_a_failing_job_is_recorded_and_the_sweep_goes_on(failing_sweeps):
    """The shared three-job sweep (tests/sweep/conftest.py) on the default launcher: the
    third job fails (its start is out of reach: a failure only the run finds; a value the
    config check refuses would refuse the whole sweep up front), the other two finish, and
    the summary and console say so."""
    run = failing_sweeps.result("pool")
    sweep, out = run.sweep_dir, run.stdout
    assert run.returncode == 1, run.stderr[-3000:]  # a job failed

    jobs = sorted(p for p in sweep.iterdir() if p.is_dir() and p.name[0].isdigit())
    assert [p.name.split("_", 1)[0] for p in jobs] == ["0", "1", "2"]
    assert all("task.init_pos=" in p.name for p in jobs)  # a person can tell them apart
    records = {p.name[0]: json.loads((p / "metrics.json").read_text()) for p in jobs}
    assert records["2"]["status"] == "failed" and "inverse kinematics" in records["2"]["error"]
    assert records["0"]["status"] == records["1"]["status"] == "ok"
    assert (jobs[0] / "timeseries.parquet").is_file() and not (jobs[2] / "timeseries.parquet").exists()
    assert not any((job / "figures").exists() for job in jobs)  # no per-job figures in a sweep

    summary = pd.read_parquet(sweep / "summary.parquet")
    assert len(summary) == 3 and len(pd.read_csv(sweep / "summary.csv")) == 3
    assert list(summary["status"]) == ["ok", "ok", "failed"]
    # the resolved config's value (a list as its JSON text), also where it was overridden
    assert summary["task.init_pos"].map(json.loads).tolist() == [
        [0.55, 0, 0.35],
        [0.55, 0, 0.4],
        [3, 0, 0.35],
    ]
    md = (sweep / "summary.md").read_text()
    assert (
        "3 jobs: 2 finished (0 docked, 0 not docked, 2 without a gate), 1 failed" in md
        and "peak axial force [N]" in md
    )
    assert (sweep / "comparison" / "table10_bars.png").is_file()
    # free space, no contact: no force overlay (it would be an empty panel)
    assert not (sweep / "comparison" / "force_overlay.png").exists()
    assert not (sweep / COUNT_FILE).exists()  # the progress count is gone with the sweep

    # console: a line per finished job with a running count, then the counts
    lines = [line for line in out.splitlines() if re.match(r"\[\d/3\] ", line)]
    assert sorted(line[:5] for line in lines) == ["[1/3]", "[2/3]", "[3/3]"]
    assert any(
        line.split()[1].startswith("2_") and "task.init_pos=[3,0,0.35]" in line and "FAILED" in line
        for line in lines
    )
    assert any(" · finished · " in line and (" N · " in line or " N) · " in line) for line in lines)
    assert "sweep: 3 jobs on 2 worker processes" in out
    assert re.search(
        r"sweep finished in [\d.]+ s: 3 jobs: 2 finished \(0 docked, 0 not docked, 2 without a gate\), 1 failed",
        out,
    )
    assert re.search(r"FAILED 2_\S*task.init_pos=\[3,0,0.35\]\S*: inverse kinematics", out)


def test_a_worker_crash_aborts_the_sweep_but_leaves_a_record(tmp_path):
    """A segfault kills its worker: joblib stops the pool (the sibling job dies too), Hydra
    aborts without on_multirun_end; main() still writes the summary and exits 1."""
    sweep = tmp_path / "sweep"
    result = sweep_cli(
        sweep,
        *SHORT,
        "task.stroke=[0,0,-0.1],[0,0,-0.09],[0,0,-0.08]",
        "+hydra.callbacks.crash._target_=sweep_crash_helper.SegfaultJob",
        pythonpath=TESTS,
    )
    assert result.returncode == 1
    # one line about the worker, not joblib's TerminatedWorkerError traceback (the dying
    # worker's own faulthandler report of the segmentation fault stays)
    assert "sweep: a worker process died (exit codes SIGSEGV(-11))" in result.stderr
    assert "TerminatedWorkerError" not in result.stderr and "Traceback" not in result.stderr
    assert re.search(r"sweep ABORTED in [\d.]+ s", result.stdout)
    jobs = [p for p in sweep.iterdir() if p.is_dir() and p.name[0].isdigit()]
    assert any(p.name.startswith("1_") for p in jobs)
    for job in jobs:  # every job directory ends with a metrics.json
        record = json.loads((job / "metrics.json").read_text())
        if job.name.startswith("1_"):
            assert record["status"] == "failed" and record["error"] == ORPHAN_ERROR
            assert record["controller"] == "impedance"
    summary = pd.read_csv(sweep / "summary.csv")
    assert len(summary) == len(jobs) and (summary["status"] == "failed").any()
    assert "(aborted)" in (sweep / "summary.md").read_text()


def _compose_multirun(*overrides: str):
    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose("config", overrides=list(overrides), return_hydra_config=True)


def test_sweeps_run_on_the_worker_pool_with_one_worker_per_core_and_the_summary_callback():
    cfg = _compose_multirun()
    assert cfg.hydra.launcher._target_ == "hydra_plugins.compliant_docking_launcher.PoolLauncher"
    assert cfg.hydra.launcher.n_jobs == -1
    assert cfg.hydra.callbacks.sweep._target_ == "compliant_docking.sweep.callback.SweepCallback"
    assert cfg.hydra.sweep.dir.startswith("runs/multirun/")
    assert "experiment" in cfg.hydra.job.config.override_dirname.exclude_keys


@pytest.mark.parametrize(
    "preset, jobs", [("controller_comparison", 180), ("misalignment", 90), ("clearance", 150)]
)
def test_presets_name_existing_options_and_compose(preset, jobs):
    cfg = _compose_multirun(f"+experiment={preset}")
    params = dict(cfg.hydra.sweeper.params)
    assert expected_jobs(cfg) == jobs
    assert f"_{preset}" in cfg.hydra.sweep.dir
    parser = OverridesParser.create()
    sweeps = {}
    for key, value in params.items():
        override = parser.parse_override(f"{key}={value}")
        sweeps[key] = list(override.sweep_string_iterator())
        if (CONF_DIR / key).is_dir():  # a config group: every option must exist
            for option in sweeps[key]:
                assert (CONF_DIR / key / f"{option}.yaml").is_file(), f"{key}={option}"
    # the first and the last job compose (keys and values valid for the schemas)
    for pick in (0, -1):
        combo = [f"{k}={v[pick]}" for k, v in sweeps.items()]
        job = _compose_multirun(f"+experiment={preset}", *combo)
        OmegaConf.to_container(job, resolve=False)


def test_expected_jobs_and_command_line_lists_replace_preset_lists():
    def with_task_overrides(cfg, *overrides):  # as `-m overrides…` leaves them in the config
        OmegaConf.update(cfg, "hydra.overrides.task", list(overrides), force_add=True)
        return cfg

    cfg = with_task_overrides(_compose_multirun(), "robot=iiwa14,fr3", "controller=impedance")
    assert expected_jobs(cfg) == 2
    cfg = _compose_multirun("+experiment=controller_comparison")
    cfg = with_task_overrides(cfg, "+experiment=controller_comparison", "robot=fr3")
    assert expected_jobs(cfg) == 90  # 3 controllers × 3 planners × 10 draws
    cfg = with_task_overrides(cfg, "+experiment=controller_comparison", "robot=fr3", "controller=glob(*)")
    assert expected_jobs(cfg) is None  # glob needs Hydra's config loader: count unknown


@pytest.mark.parametrize(
    "overrides",
    [
        ("robot=iiwa14,fr3", "controller=impedance"),
        ("+experiment=controller_comparison", "robot=fr3"),
        ("+experiment=misalignment",),
        ("controller.k=range(10,50,10)", "controller.d=choice(1,2)", "controller.k=5,6"),
        ("task.settle_time=1,1.5,2", "task.settle_time=3"),
        ("controller.k=interval(1,2)",),
    ],
)
def test_expected_jobs_counts_what_hydras_basic_sweeper_launches(overrides):
    """Pinned against Hydra's own (private) BasicSweeper.split_arguments: if a Hydra release
    changes how the basic sweeper combines sweeper params and command-line overrides, this
    fails. None where Hydra refuses the sweep (interval) and the count is unknown."""
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

    cfg = _compose_multirun(*(o for o in overrides if o.startswith("+experiment")))  # the presets
    OmegaConf.update(cfg, "hydra.overrides.task", list(overrides), force_add=True)  # as -m leaves them
    params = [f"{k}={v}" for k, v in (cfg.hydra.sweeper.get("params") or {}).items()] + list(overrides)
    try:
        batches = BasicSweeper.split_arguments(OverridesParser.create().parse_overrides(params), None)
        hydra_count = sum(len(batch) for batch in batches)
    except Exception:
        hydra_count = None
    assert expected_jobs(cfg) == hydra_count


def test_job_line_and_exit_status(tmp_path):
    job = tmp_path / "sweep" / "3_controller=hqp"
    job.mkdir(parents=True)
    reset_count(tmp_path / "sweep")  # the sweep has started: its count file exists
    (job / "metrics.json").write_text(
        json.dumps(
            {
                "status": "ok",
                "success": True,
                "peak_axial_force_N": 42.34,
                "filtered_peak_axial_force_N": 12.34,
                "wall_time_s": 4.2,
            }
        )
    )
    line = job_line(job, tmp_path / "sweep", total=6)
    # the force the gate judges, then the raw per-step peak
    assert line == "[1/6] 3_controller=hqp · finished · docked · peak 12.3 N (raw 42.3 N) · 4.2 s"
    (job / "metrics.json").write_text(
        json.dumps({"status": "failed", "success": False, "error": "diverged", "wall_time_s": 1.0})
    )
    # the second line of this sweep: numbered 2 (each call is a job finishing)
    assert job_line(job, tmp_path / "sweep", None) == "[2 done] 3_controller=hqp · FAILED · 1.0 s · diverged"
    bouncing = {"status": "ok", "success": False, "filtered_peak_axial_force_N": 24.1, "wall_time_s": 4.2}
    bouncing.update(
        steady_contact_events_per_s=203.0, gate_verdict="seated; contact chatter: 203 make/break events/s"
    )
    (job / "metrics.json").write_text(json.dumps(bouncing))
    assert job_line(job, tmp_path / "sweep", 6) == (
        "[3/6] 3_controller=hqp · finished · not docked · peak 24.1 N · 203 contact events/s · 4.2 s · "
        "seated; contact chatter: 203 make/break events/s"
    )
    outcome = dict(sweep_dir=tmp_path, jobs=4, ok=4, docked=0, unfinished=0, summary={})
    assert SweepOutcome(failed=0, aborted=False, **outcome).exit_status == 0  # not docked ≠ failed
    assert SweepOutcome(failed=1, aborted=False, **outcome).exit_status == 1
    assert SweepOutcome(failed=0, aborted=True, **outcome).exit_status == 1


def test_a_lenient_sweep_in_which_every_job_failed_exits_1(tmp_path):
    """strict=false (the tuning presets): a failed job is a penalised result, but a study
    in which every job failed measured nothing (before: exit 0)."""
    outcome = dict(sweep_dir=tmp_path, docked=0, summary={}, aborted=False, strict=False)
    assert SweepOutcome(jobs=4, ok=3, failed=1, unfinished=0, **outcome).exit_status == 0
    assert SweepOutcome(jobs=4, ok=0, failed=4, unfinished=0, **outcome).exit_status == 1
    assert SweepOutcome(jobs=2, ok=0, failed=4, unfinished=2, **outcome).exit_status == 1  # 2 left no record
    assert SweepOutcome(jobs=0, ok=0, failed=0, unfinished=0, **outcome).exit_status == 0  # nothing to run


def _count(sweep_dir: str, times: int) -> list[int | None]:
    return [next_count(Path(sweep_dir)) for _ in range(times)]


def test_jobs_finishing_together_get_distinct_progress_counts(tmp_path):
    """8 processes take 50 numbers each as fast as they can: every number from 1 to 400 is
    given exactly once (a plain count of metrics.json files would repeat some), and a
    job's line shows its number."""
    reset_count(tmp_path)
    with multiprocessing.get_context("fork").Pool(4) as pool:
        taken = pool.starmap(_count, [(str(tmp_path), 50)] * 8)
    assert sorted(n for numbers in taken for n in numbers) == list(range(1, 401))
    reset_count(tmp_path)  # a new (or resumed) sweep starts again at 1
    for name in ("0_a", "1_b"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "metrics.json").write_text(json.dumps({"status": "ok", "success": True}))
    lines = [job_line(tmp_path / name, tmp_path, 3) for name in ("1_b", "0_a")]
    assert [line[:6] for line in lines] == ["[1/3] ", "[2/3] "]
    remove_count(tmp_path)
    assert not (tmp_path / COUNT_FILE).exists()


def test_strict_false_makes_failed_jobs_results_but_not_an_aborted_sweep(tmp_path):
    outcome = SweepOutcome(sweep_dir=tmp_path, jobs=4, ok=3, failed=1, docked=2, unfinished=0, aborted=False)
    assert outcome.exit_status == 1  # the default: a failed job fails the sweep
    outcome.strict = False  # the tuning presets: a diverging trial is a penalised result
    assert outcome.exit_status == 0
    outcome.aborted = True
    assert outcome.exit_status == 1


def test_the_expected_jobs_of_a_tuning_study_are_trials_times_draws():
    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose(
            config_name="config",
            overrides=["+experiment=tune", "hydra.sweeper.n_trials=5", "+hydra.sweeper.draws.task.x='1,2,3'"],
            return_hydra_config=True,
        )
    assert expected_jobs(cfg) == 5 * 4 * 3  # seeds 0-3 of the preset × the 3 values added


def test_the_count_file_is_never_left_behind(tmp_path):
    """A sweep refused after it began (a tuning set-up refused by the sweeper itself), and a
    job that finishes after its sweep was summarised (an aborted one's), leave no
    .finished_jobs in the sweep directory."""
    session = SweepSession()
    session.begin(tmp_path, 4, independent_jobs=False)
    assert (tmp_path / COUNT_FILE).is_file()
    session.discard()
    assert not (tmp_path / COUNT_FILE).exists()
    reset_count(tmp_path)
    remove_count(tmp_path)  # the sweep was summarised
    assert next_count(tmp_path) is None and not (tmp_path / COUNT_FILE).exists()
