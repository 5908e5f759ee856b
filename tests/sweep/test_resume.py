"""Interrupted sweeps and resume=<sweep dir>: nothing half-done counts as a result, and a
resumed sweep runs exactly the jobs without one."""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
import warnings
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import pandas as pd
import pytest
from omegaconf import OmegaConf

from compliant_docking.results import RunSkippedWarning, load_runs
from compliant_docking.run.provenance import config_hash
from compliant_docking.run.runner import execute
from compliant_docking.sweep import outcome as sweep_outcome
from compliant_docking.sweep import resume
from compliant_docking.sweep.session import SweepSession
from tests.helpers import REPO_ROOT, cli_in_process, make_cfg

#: 6 short free-space jobs (0.7-1.7 s simulated each): what is judged is which jobs finished
#: before the kill and what the resume runs again, not what a job simulates; the last two
#: still take over a second each, so the kill lands while one of them runs
SWEEP_ARGS = (
    "trajectory=hold",
    "trajectory.duration=0.5",
    "target=none",
    "task.init_pos=[0.55,0,0.35]",
    "task.settle_time=0.2,0.4,0.6,0.8,1,1.2",
    "task.progress=false",
    "hydra.callbacks.sweep.figures=false",
    "hydra.launcher.n_jobs=2",
)
FINISHED_BEFORE_KILL = 4


def sweep_command(sweep_dir: Path, *extra: str) -> list[str]:
    return [
        sys.executable,
        "-m",
        "compliant_docking",
        "-m",
        *SWEEP_ARGS,
        f"hydra.sweep.dir={sweep_dir}",
        *extra,
    ]


def _env() -> dict:
    return {**os.environ, "PYTHONUNBUFFERED": "1"}


def _ok_jobs(sweep_dir: Path) -> list[Path]:
    found = []
    for path in sweep_dir.glob("*/metrics.json"):
        try:
            if json.loads(path.read_text()).get("status") == "ok":
                found.append(path.parent)
        except (OSError, ValueError):
            pass
    return sorted(found)


def _running(sweep_dir: Path) -> list[Path]:
    """Jobs inside their run: Hydra has written a file of ``.hydra/``, and no metrics.json
    exists yet. An empty ``.hydra/`` is not enough: a job killed there never started (an
    aborted sweep removes its directory, and it counts as missing, not as unfinished)."""
    return [
        p.parent
        for p in sweep_dir.glob("*/.hydra")
        if any(f.is_file() for f in p.iterdir()) and not (p.parent / "metrics.json").exists()
    ]


def _mtimes(job_dir: Path) -> dict[str, int]:
    return {str(p.relative_to(job_dir)): p.stat().st_mtime_ns for p in job_dir.rglob("*")}


@dataclass
class Killed:
    """A 6-job sweep killed after some jobs finished, sabotaged, then resumed."""

    sweep_dir: Path
    signum: int
    killed_at: float  # time.time() of the kill
    kill_returncode: int
    after_kill: dict[str, dict | None]  # job name → its metrics.json right after the kill
    aborted_summary: str | None  # summary.md right after the kill
    kept: dict[str, dict[str, int]]  # untouched finished jobs → mtimes of all their files
    kept_metrics: dict[str, bytes]
    truncated: str  # job names of the sabotaged ones
    missing: str
    changed: str
    before_resume: pd.DataFrame  # load_runs before the resume
    skipped_warnings: list[str]
    resumed: subprocess.CompletedProcess


def _kill_and_resume(tmp_path: Path, signum: int) -> Killed:
    sweep_dir = tmp_path / "sweep"
    proc = subprocess.Popen(
        sweep_command(sweep_dir),
        cwd=REPO_ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(),
        start_new_session=True,
    )  # its own process group, workers included
    deadline = time.monotonic() + 180
    # kill once some jobs have finished and another is running (its directory has .hydra/)
    while (
        len(_ok_jobs(sweep_dir)) < FINISHED_BEFORE_KILL or not _running(sweep_dir)
    ) and proc.poll() is None:
        assert time.monotonic() < deadline, "the sweep did not get going"
        time.sleep(0.02)
    killed_at = time.time()
    os.killpg(proc.pid, signum)
    proc.communicate(timeout=120)
    jobs = sorted(p for p in sweep_dir.iterdir() if p.is_dir() and not p.name.startswith("."))
    after_kill = {}
    for job in jobs:
        path = job / "metrics.json"
        after_kill[job.name] = json.loads(path.read_text()) if path.is_file() else None

    summary_md = sweep_dir / "summary.md"
    aborted_summary = summary_md.read_text() if summary_md.is_file() else None
    ok = _ok_jobs(sweep_dir)
    assert FINISHED_BEFORE_KILL <= len(ok) < 6, "the kill came too late to leave work undone"
    # sabotage three finished jobs: what a kill in the middle of writing would leave
    truncated, missing, changed, *kept = ok
    text = (truncated / "metrics.json").read_text()
    (truncated / "metrics.json").write_text(text[: len(text) // 2])  # half-written JSON
    (missing / "metrics.json").unlink()  # killed after its time series, before metrics.json
    (missing / ".timeseries.parquet.tmp").write_text("partial")
    record = json.loads((changed / "metrics.json").read_text())
    record["config_hash"] = "0" * 16  # a result of another config (conf/ edited since)
    (changed / "metrics.json").write_text(json.dumps(record))
    kept_mtimes = {job.name: _mtimes(job) for job in kept}
    kept_metrics = {job.name: (job / "metrics.json").read_bytes() for job in kept}

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        before = load_runs(sweep_dir)
    skipped = [str(w.message) for w in caught if issubclass(w.category, RunSkippedWarning)]

    time.sleep(0.05)  # mtimes of the resume are strictly later
    resumed = _resume_in_this_process(sweep_dir)
    return Killed(
        sweep_dir,
        signum,
        killed_at,
        proc.returncode,
        after_kill,
        aborted_summary,
        kept_mtimes,
        kept_metrics,
        truncated.name,
        missing.name,
        changed.name,
        before,
        skipped,
        resumed,
    )


def _resume_in_this_process(sweep_dir: Path) -> subprocess.CompletedProcess:
    """The killed sweep's command with ``resume=``, through the command's main in this
    process on Hydra's basic launcher (its jobs run here too, one after the other): which
    jobs a resume keeps and reruns is decided by the sweep's callback before any launcher
    runs them (sweep/resume.py), and the launcher is not one of the overrides a resume
    compares with the sweep's (``hydra.overrides.task``)."""
    from compliant_docking.cli import main

    args = [
        a for a in sweep_command(sweep_dir, f"resume={sweep_dir}")[3:] if not a.startswith("hydra.launcher.")
    ]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([*args, "hydra/launcher=basic"])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


@pytest.fixture(
    scope="module",
    params=[
        pytest.param(signal.SIGTERM, id="SIGTERM"),
        pytest.param(signal.SIGKILL, id="SIGKILL", marks=pytest.mark.slow),
    ],
)
def killed(request, tmp_path_factory) -> Killed:
    return _kill_and_resume(tmp_path_factory.mktemp(f"killed_{request.param}"), request.param)


def _started(record: dict) -> float:
    return datetime.fromisoformat(record["started_at"]).timestamp()


def test_an_interrupted_sweep_leaves_nothing_that_reads_as_a_result(killed):
    unfinished = [name for name, r in killed.after_kill.items() if r is None or r["status"] != "ok"]
    assert unfinished  # killed while a job ran
    for name, record in killed.after_kill.items():
        if record is None:  # half-done, skipped by load_runs
            continue
        if record["status"] == "ok":
            assert (killed.sweep_dir / name / "timeseries.parquet").is_file()
            assert _started(record) < killed.killed_at
        else:  # the launching process's record of a job it lost
            assert record["status"] == "failed" and record["interrupted"] is True
            assert record["error"] == sweep_outcome.ORPHAN_ERROR and record["error"].startswith("interrupted")
    if killed.signum == signal.SIGTERM:  # unwound like Ctrl-C: records, summary, exit 143
        assert killed.kill_returncode in (143, 1)  # 1: a worker's death was seen first
        assert all(killed.after_kill[name] is not None for name in unfinished)
        assert "(aborted)" in killed.aborted_summary
    else:  # SIGKILL: nothing could clean up; the running jobs' directories stay unfinished
        assert killed.aborted_summary is None
        assert all(killed.after_kill[name] is None for name in unfinished)


def test_resume_reruns_exactly_the_jobs_without_a_result(killed):
    result = killed.resumed
    assert result.returncode == 0, result.stderr[-3000:]
    assert "resume: " in result.stdout and "kept if their config is unchanged" in result.stdout
    skipped_lines = [line for line in result.stdout.splitlines() if resume.SKIPPED in line]
    assert sorted(line.split()[1] for line in skipped_lines) == sorted(killed.kept)
    # kept jobs: not a single file rewritten (metrics.json, time series, figures, .hydra/)
    for name, mtimes in killed.kept.items():
        job = killed.sweep_dir / name
        assert _mtimes(job) == mtimes, name
        assert (job / "metrics.json").read_bytes() == killed.kept_metrics[name]
    # every other job ran again, after the kill
    jobs = sorted(p for p in killed.sweep_dir.iterdir() if p.is_dir() and not p.name.startswith("."))
    assert len(jobs) == 6
    for job in jobs:
        record = json.loads((job / "metrics.json").read_text())
        assert record["status"] == "ok", (job.name, record["error"])
        assert "interrupted" not in record
        if job.name not in killed.kept:
            assert _started(record) > killed.killed_at, job.name
            assert (job / "metrics.json").stat().st_mtime > killed.killed_at
            assert (job / ".hydra" / "overrides.yaml").is_file()
    # the complete summary: all six rows
    summary = pd.read_csv(killed.sweep_dir / "summary.csv")
    assert len(summary) == 6 and set(summary["status"]) == {"ok"}
    assert "6 jobs: 6 finished" in (killed.sweep_dir / "summary.md").read_text()
    assert "sweep finished" in result.stdout


def test_half_written_job_directories_are_rerun_not_reported(killed):
    # before the resume: load_runs skips them with a warning, never as rows
    for name in (killed.truncated, killed.missing):
        assert name not in set(killed.before_resume["job"])
        assert any(name in message for message in killed.skipped_warnings)
    assert any("not valid JSON" in m for m in killed.skipped_warnings)
    # after: rerun, complete, and the leftovers of the broken attempt are gone
    for name in (killed.truncated, killed.missing, killed.changed):
        job = killed.sweep_dir / name
        record = json.loads((job / "metrics.json").read_text())
        assert record["status"] == "ok" and _started(record) > killed.killed_at
        assert record["config_hash"] != "0" * 16
        assert (job / "timeseries.parquet").is_file() and (job / "summary.txt").is_file()
    assert not (killed.sweep_dir / killed.missing / ".timeseries.parquet.tmp").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RunSkippedWarning)
        assert len(load_runs(killed.sweep_dir)) == 6


def test_a_resume_with_other_overrides_is_refused_and_touches_nothing(killed, capsys):
    saved = killed.sweep_dir / "multirun.yaml"
    before = saved.stat().st_mtime_ns, saved.read_bytes()
    other = [
        a.replace("task.settle_time=0.2,0.4,", "task.settle_time=0.3,0.4,")
        for a in sweep_command(killed.sweep_dir, f"resume={killed.sweep_dir}")
    ]
    assert other != sweep_command(killed.sweep_dir, f"resume={killed.sweep_dir}")
    # refused before anything runs: the command's main in this process (no process start)
    code, err = cli_in_process(capsys, *other[3:])  # without ``python -m compliant_docking``
    assert code == 2  # refused, like every refusal of the command line
    assert "was started with the overrides" in err
    assert (saved.stat().st_mtime_ns, saved.read_bytes()) == before


# --------------------------------------------------------------------------- units
def test_resume_argument_becomes_hydra_overrides(tmp_path, monkeypatch):
    sweep_dir = tmp_path / "runs" / "multirun" / "2025-06-01" / "14-03-12"
    sweep_dir.mkdir(parents=True)
    (sweep_dir / "multirun.yaml").write_text("hydra: {}\n")
    tail = ["hydra.callbacks.sweep.resume=true", "hydra.output_subdir=null"]
    assert resume.translate_argv(["-m", "a=1,2", f"resume={sweep_dir}"]) == [
        "-m",
        "a=1,2",
        f"hydra.sweep.dir={sweep_dir}",
        *tail,
    ]
    assert resume.translate_argv(["-m", f"hydra.sweep.dir={sweep_dir}", "resume=true"]) == [
        "-m",
        f"hydra.sweep.dir={sweep_dir}",
        *tail,
    ]
    assert resume.translate_argv(["-m", "a=1", "resume=false"]) == ["-m", "a=1"]
    assert resume.translate_argv(["-m", "a=1"]) == ["-m", "a=1"]
    monkeypatch.chdir(tmp_path)  # resume=last: the newest sweep under runs/multirun
    assert (
        resume.translate_argv(["--multirun", "resume=last"])[1]
        == f"hydra.sweep.dir={Path('runs/multirun/2025-06-01/14-03-12')}"
    )
    odd = tmp_path / "a b,c=d"
    odd.mkdir()
    (odd / "multirun.yaml").write_text("hydra: {}\n")
    assert f"hydra.sweep.dir='{odd}'" in resume.translate_argv(["-m", f"resume={odd}"])
    for args, message in (
        (["a=1", f"resume={sweep_dir}"], "with -m"),
        (["-m", f"resume={tmp_path / 'nothing'}"], "no multirun.yaml"),
        (["-m", "resume=true"], "needs hydra.sweep.dir"),
        (["-m", f"resume={sweep_dir}", f"hydra.sweep.dir={odd}"], "different"),
    ):
        with pytest.raises(resume.ResumeError, match=message):
            resume.translate_argv(args)


def test_check_sweep_compares_the_overrides_with_multirun_yaml(tmp_path):
    saved = {
        "hydra": {
            "sweep": {"dir": str(tmp_path)},
            "sweeper": {"params": None},
            "overrides": {"task": ["robot=iiwa14,fr3", "controller=hqp"]},
        }
    }
    OmegaConf.save(OmegaConf.create(saved), tmp_path / "multirun.yaml")
    resume.check_sweep(OmegaConf.create(saved))  # the same command: no refusal
    assert resume.status_lines(tmp_path)[0].startswith("resume: 0 finished jobs")
    swapped = {
        **saved,
        "hydra": {**saved["hydra"], "overrides": {"task": ["controller=hqp", "robot=iiwa14,fr3"]}},
    }
    with pytest.raises(resume.ResumeError, match="same order"):
        resume.check_sweep(OmegaConf.create(swapped))
    preset = {**saved, "hydra": {**saved["hydra"], "sweeper": {"params": {"robot": "fr3"}}}}
    with pytest.raises(resume.ResumeError, match="hydra.sweeper.params"):
        resume.check_sweep(OmegaConf.create(preset))


@pytest.fixture(scope="module")
def finished_job(tmp_path_factory):
    cfg = make_cfg("task.progress=false", "trajectory.duration=1", "task.settle_time=1")
    job = tmp_path_factory.mktemp("job") / "0_x"
    execute(cfg, job, figures=False, echo=False)
    return cfg, job


def test_finished_record_keeps_only_a_complete_result_of_the_same_config(finished_job, tmp_path):
    import shutil

    cfg, source = finished_job
    job = tmp_path / "0_x"
    shutil.copytree(source, job)
    record = resume.finished_record(cfg, job)
    assert record is not None and record["config_hash"] == config_hash(cfg)
    other = make_cfg("task.progress=false", "trajectory.duration=1", "task.settle_time=1.5")
    assert resume.finished_record(other, job) is None  # another config
    metrics = job / "metrics.json"
    for status, kept in (("incomplete", True), ("failed", False)):
        metrics.write_text(json.dumps({**record, "status": status}))
        assert (resume.finished_record(cfg, job) is not None) is kept, status
    metrics.write_text(json.dumps({k: v for k, v in record.items() if k != "config_hash"}))
    assert resume.finished_record(cfg, job) is None  # from before config hashes: rerun
    metrics.write_text(json.dumps(record))
    (job / "timeseries.parquet").unlink()
    assert resume.finished_record(cfg, job) is None  # its time series is gone


def test_prepare_rerun_clears_the_previous_attempt_but_keeps_hydra(tmp_path):
    job = tmp_path / "sweep" / "3_x"
    (job / ".hydra").mkdir(parents=True)
    (job / ".hydra" / "config.yaml").write_text("a: 1\n")
    (job / "figures").mkdir()
    for name in ("metrics.json", "timeseries.parquet", "summary.txt", ".metrics.json.tmp", "figures/x.png"):
        (job / name).write_text("old")
    resume.prepare_rerun(make_cfg(), job, tmp_path / "sweep")  # not under Hydra: .hydra/ as it is
    assert sorted(p.name for p in job.iterdir()) == [".hydra"]
    assert (job / ".hydra" / "config.yaml").read_text() == "a: 1\n"
    (tmp_path / "sweep" / "multirun.yaml").write_text("hydra: {}\n")
    with pytest.raises(RuntimeError, match="sweep directory"):
        resume.prepare_rerun(make_cfg(), tmp_path / "sweep", tmp_path / "sweep")


@pytest.mark.parametrize("where", ["outside", "parent", "itself"])
def test_prepare_rerun_never_clears_a_directory_outside_its_sweep(tmp_path, where):
    """The last line of defence (the guard refuses such job directories up front): a job
    directory that is not strictly inside the sweep directory is never emptied."""
    sweep = tmp_path / "runs" / "sweep"
    sweep.mkdir(parents=True)
    victim = {"outside": tmp_path / "precious", "parent": tmp_path / "runs", "itself": sweep}[where]
    victim.mkdir(exist_ok=True)
    (victim / "data.txt").write_text("keep me")
    with pytest.raises(RuntimeError, match="not inside the sweep directory"):
        resume.prepare_rerun(make_cfg(), victim, sweep)
    assert (victim / "data.txt").read_text() == "keep me"


def test_orphan_records_are_marked_and_never_replace_a_result(tmp_path):
    lost, done = tmp_path / "1_lost", tmp_path / "2_done"
    for job in (lost, done):
        (job / ".hydra").mkdir(parents=True)
    (done / "metrics.json").write_text('{"status": "ok"}')
    sweep_outcome.record_orphan(lost)
    sweep_outcome.record_orphan(done)  # its result arrived meanwhile: kept
    record = json.loads((lost / "metrics.json").read_text())
    assert record["status"] == "failed" and record["interrupted"] is True
    assert record["error"].startswith("interrupted")
    assert json.loads((done / "metrics.json").read_text()) == {"status": "ok"}
    assert sorted(p.name for p in lost.iterdir()) == [".hydra", "metrics.json"]  # no temp file


def test_an_aborted_submitit_sweep_writes_no_orphan_records(tmp_path):
    """Submitit jobs outlive the launching process: their directories stay unfinished
    (a resume reruns or keeps them), never marked interrupted while they may still run."""
    job = tmp_path / "0_running"
    (job / ".hydra").mkdir(parents=True)
    session = SweepSession()
    session.begin(tmp_path, None, independent_jobs=True)
    outcome = session.finish_aborted()
    assert outcome.aborted and outcome.exit_status == 1 and outcome.unfinished == 1
    assert not (job / "metrics.json").exists()


def test_an_aborted_sweep_removes_the_empty_directory_of_a_job_that_never_started(tmp_path):
    """A worker killed between creating its job's directory and writing ``.hydra/`` leaves
    an empty directory: removed (a job that never started), so every job directory that
    stays ends with a metrics.json; anything with a file in it is kept and recorded."""
    done, lost = tmp_path / "0_done", tmp_path / "1_lost"
    never, nested = tmp_path / "2_never", tmp_path / "3_a" / "b"
    (done / ".hydra").mkdir(parents=True)
    (done / "metrics.json").write_text('{"status": "ok", "success": true}')
    (lost / ".hydra").mkdir(parents=True)
    (lost / ".hydra" / "overrides.yaml").write_text("- task.stroke=[0,0,-0.1]\n")
    (never / ".hydra").mkdir(parents=True)  # Hydra made .hydra/ and was killed before its files
    nested.mkdir(parents=True)
    (tmp_path / "comparison").mkdir()  # not a job's folder: left alone
    assert sweep_outcome.remove_unstarted_job_dirs(tmp_path) == [
        never / ".hydra",
        never,
        nested,
        nested.parent,
    ]
    sweep_outcome.summarise(tmp_path, aborted=True, figures=False, total=4)
    jobs = sorted(p.name for p in tmp_path.iterdir() if p.is_dir() and p.name[0].isdigit())
    assert jobs == ["0_done", "1_lost"] and (tmp_path / "comparison").is_dir()
    assert all((tmp_path / job / "metrics.json").is_file() for job in jobs)
    assert json.loads((lost / "metrics.json").read_text())["interrupted"] is True
