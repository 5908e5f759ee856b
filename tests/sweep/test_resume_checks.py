"""A resume keeps only what it verified, says why every other job runs again, and counts
this run's jobs 1, 2, 3… (the count: compliant_docking/sweep/progress.py)"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pandas as pd
import pytest

from compliant_docking.run.runner import execute
from compliant_docking.sweep import progress, resume
from tests.helpers import SWEEP_LAUNCHERS, make_cfg, sweep_with

SHORT = ("trajectory.duration=1", "task.settle_time=1", "task.progress=false")


@pytest.fixture(scope="module")
def finished_job(tmp_path_factory):
    cfg = make_cfg(*SHORT)
    job = tmp_path_factory.mktemp("job") / "0_x"
    execute(cfg, job, figures=True, echo=False)
    return cfg, job


def _copy(source: Path, tmp_path: Path) -> Path:
    job = tmp_path / source.name
    shutil.copytree(source, job)
    return job


def _truncate(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def test_assess_keeps_a_sound_job_and_says_why_it_reruns_another(finished_job, tmp_path):
    cfg, source = finished_job
    job = _copy(source, tmp_path)
    kept, why = resume.assess(cfg, job)
    assert kept is not None and why == ""
    cases = [
        (lambda j: _truncate(j / "timeseries.parquet"), "timeseries.parquet cannot be read"),
        (lambda j: (j / "timeseries.parquet").unlink(), "timeseries.parquet is missing"),
        (lambda j: (j / "summary.txt").unlink(), "summary.txt is missing"),
        (
            lambda j: (j / "figures" / "contact_force.png").write_bytes(b""),
            "figures/contact_force.png is empty",
        ),
        (lambda j: _truncate(j / "metrics.json"), "metrics.json is not valid JSON"),
    ]
    for case, (sabotage, reason) in enumerate(cases):
        job = _copy(source, tmp_path / f"case{case}")
        sabotage(job)
        kept, why = resume.assess(cfg, job)
        assert kept is None and reason in why, (reason, why)
    job = _copy(source, tmp_path / "rows")
    record = json.loads((job / "metrics.json").read_text())
    (job / "metrics.json").write_text(
        json.dumps({**record, "steps": record["steps"] + 1, "timeseries_rows": record["steps"] + 1})
    )
    assert resume.assess(cfg, job)[1] == "timeseries.parquet has 2000 rows, metrics.json says 2001 steps"
    changed = make_cfg("trajectory.duration=1", "task.settle_time=1.5", "task.progress=false")
    kept, why = resume.assess(changed, _copy(source, tmp_path / "changed"))
    assert kept is None and why.startswith("its config changed since it ran (config hash ")
    assert resume.assess(cfg, tmp_path / "never")[1] == "it never started"


@pytest.mark.parametrize("launcher", SWEEP_LAUNCHERS)
def test_resume_reruns_a_job_whose_artefact_is_corrupt_and_says_why(tmp_path, capsys, launcher):
    sweep = tmp_path / "sweep"
    args = ("trajectory=hold", "target=none", "task.init_pos=[0.55,0,0.35]", *SHORT)
    args = (*args, "trajectory.duration=1,1.5,2", "hydra.callbacks.sweep.figures=false")
    first = sweep_with(launcher, capsys, sweep, *args)
    assert first.returncode == 0, first.stderr[-3000:]
    jobs = sorted(p for p in sweep.iterdir() if p.is_dir())
    corrupt, edited, kept = jobs
    _truncate(corrupt / "timeseries.parquet")  # a kill while a disk was full, a bad copy
    record = json.loads((edited / "metrics.json").read_text())
    (edited / "metrics.json").write_text(json.dumps({**record, "config_hash": "0" * 16}))  # conf/ edited
    kept_bytes = (kept / "metrics.json").read_bytes()

    result = sweep_with(launcher, capsys, sweep, *args, f"resume={sweep}")
    assert result.returncode == 0, result.stderr[-3000:]
    lines = [line for line in result.stdout.splitlines() if re.match(r"\[\d/3\] ", line)]
    assert sorted(line[:5] for line in lines) == ["[1/3]", "[2/3]", "[3/3]"]  # this run's count
    by_job = {line.split()[1]: line for line in lines}
    assert "· rerun: timeseries.parquet cannot be read (" in by_job[corrupt.name]
    assert "· rerun: its config changed since it ran (config hash 0000000000000000 → " in by_job[edited.name]
    assert by_job[kept.name].endswith(resume.SKIPPED)
    assert "3 jobs: 3 finished" in result.stdout
    assert (
        len(pd.read_parquet(corrupt / "timeseries.parquet"))
        == json.loads((corrupt / "metrics.json").read_text())["steps"]
    )
    assert (kept / "metrics.json").read_bytes() == kept_bytes
    assert not (sweep / progress.COUNT_FILE).exists()
