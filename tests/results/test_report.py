"""python -m compliant_docking.report: a broken file is skipped with a message, a
directory it cannot write is refused with a pointer to --out, never a traceback."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from compliant_docking.report import main as report
from compliant_docking.run.runner import execute
from tests.helpers import REPO_ROOT, make_cfg


def _truncate(path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    for name, settle in (("0_a", "1"), ("1_b", "1.5")):
        execute(
            make_cfg("trajectory.duration=1", f"task.settle_time={settle}", "task.progress=false"),
            root / name,
            figures=False,
            echo=False,
        )
    return root


def test_report_skips_a_broken_time_series_with_a_message(two_runs, tmp_path, capsys):
    root = tmp_path / "runs"
    shutil.copytree(two_runs, root)
    _truncate(root / "0_a" / "timeseries.parquet")  # the run the force overlay picks
    (root / "2_c").mkdir()
    (root / "2_c" / "metrics.json").write_text('{"status": "ok", "succ')  # half-written
    assert report([str(root)]) == 0
    err = capsys.readouterr().err
    assert f"report: skipping the time series of {root / '0_a'}: ArrowInvalid" in err
    assert f"report: skipped {root / '2_c'}: metrics.json is not valid JSON (half-written?)" in err
    assert "Traceback" not in err
    assert (root / "summary.md").is_file() and (root / "summary.csv").is_file()


def test_report_on_a_directory_it_cannot_write_suggests_out(two_runs, tmp_path, capsys, monkeypatch):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    assert report([str(two_runs), "--out", str(blocker / "out"), "--no-figures"]) == 2
    err = capsys.readouterr().err
    assert f"report: cannot write into {blocker / 'out'}: {blocker} is not a directory;" in err
    assert "elsewhere with --out DIR" in err and "Traceback" not in err
    assert report([str(two_runs), "--out", "/proc/report", "--no-figures"]) == 2
    assert "report: cannot write into /proc/report: cannot write in /proc (" in capsys.readouterr().err
    # a directory that refuses writes (what a read-only sweep gives a non-root user)
    from compliant_docking import report as module

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(module, "write_summary", refuse)
    assert report([str(two_runs), "--no-figures"]) == 2
    err = capsys.readouterr().err
    assert f"report: cannot write into {two_runs} (Permission denied)" in err and "--out DIR" in err


def test_report_runs_as_a_command(two_runs, tmp_path):
    out = tmp_path / "tables"
    result = subprocess.run(
        [sys.executable, "-m", "compliant_docking.report", str(two_runs), "--out", str(out), "--no-figures"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert (out / "summary.md").is_file() and not (two_runs / "summary.md").exists()
