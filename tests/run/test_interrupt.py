"""A run leaves a true record whatever happens: interrupted by a signal, warned by MuJoCo,
too long for memory, written next to another writer."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import mujoco
import pandas as pd
import pytest

from compliant_docking.run import files, rundir
from compliant_docking.run.runner import execute
from compliant_docking.run.summary import format_summary
from compliant_docking.sim import mjlog
from tests.helpers import REPO_ROOT, make_cfg


# --------------------------------------------------------------------------- signals
@pytest.mark.parametrize(
    ("signum", "code", "how"), [(signal.SIGINT, 130, "SIGINT (Ctrl-C)"), (signal.SIGTERM, 143, "SIGTERM")]
)
def test_a_signalled_single_run_records_itself_as_interrupted(tmp_path, signum, code, how):
    """Ctrl-C or SIGTERM in the middle of a run: status "interrupted" with the time series
    so far (one row per simulated step), exit 128 + signal number, no traceback."""
    run_dir = tmp_path / "run"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "compliant_docking",
            "trajectory.duration=200",  # far longer than the test waits
            "task.progress=false",
            f"hydra.run.dir={run_dir}",
        ],
        cwd=REPO_ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    deadline = time.monotonic() + 120
    while not (run_dir / ".hydra").is_dir():
        assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()
        time.sleep(0.1)
    time.sleep(4.0)  # the scene is built within about 1 s; then it simulates
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err[-3000:]
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    record = json.loads((run_dir / "metrics.json").read_text())
    assert record["status"] == "interrupted" and record["success"] is False
    assert record["error"].startswith(f"interrupted by {how} at t = ")
    assert record["gate_verdict"] is None  # no gate is judged on a partial run
    assert 0 < record["steps"] < 200_000
    series = pd.read_parquet(run_dir / "timeseries.parquet")
    assert len(series) == record["steps"]  # the partial time series, every row complete
    assert series.notna().all().all()
    assert record["sim_time_s"] == pytest.approx(record["steps"] * 0.001)
    assert "status interrupted" in out and "INTERRUPTED" in (run_dir / "summary.txt").read_text()


def test_an_interrupted_run_in_python_is_recorded_then_raised(tmp_path):
    """execute() records the interruption, then raises it again: a loop of runs stops."""
    cfg = make_cfg("trajectory.duration=200", "task.progress=false")
    timer = threading.Timer(3.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            execute(cfg, tmp_path, figures=False, echo=False)
    finally:
        timer.cancel()
    record = json.loads((tmp_path / "metrics.json").read_text())
    assert record["status"] == "interrupted" and record["steps"] > 0
    assert len(pd.read_parquet(tmp_path / "timeseries.parquet")) == record["steps"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # handlers restored


# --------------------------------------------------------------------------- MuJoCo's log
def _unstable_step() -> None:
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body><freejoint/><geom size=".1"/></body></worldbody></mujoco>'
    )
    data = mujoco.MjData(model)
    data.qvel[:] = float("nan")
    mujoco.mj_step(model, data)


def test_mujoco_warnings_go_to_the_run_not_to_mujoco_log_txt(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with mjlog.captured() as messages:
        _unstable_step()
    assert messages and "Nan, Inf or huge value in QVEL" in messages[0]
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
    assert mujoco.get_mju_user_warning() is None  # MuJoCo's own handler is back
    rundir.write_mujoco_log(tmp_path, messages)
    assert (tmp_path / rundir.MUJOCO_LOG_FILE).read_text().startswith("Nan, Inf or huge value")
    record = {"status": "failed", "error": "simulation diverged", "success": False, "mujoco_warnings": 1}
    assert "MuJoCo warnings: 1 (mujoco.log in the run directory)" in format_summary(record)


def test_mujoco_log_txt_is_git_ignored():
    ignored = (REPO_ROOT / ".gitignore").read_text().splitlines()
    assert "MUJOCO_LOG.TXT" in ignored


# --------------------------------------------------------------------------- failures
def test_a_failed_run_prints_its_reason_not_a_table_of_n_a():
    record = {"status": "failed", "error": "physics.timestep must be …", "success": False}
    text = format_summary(record)
    assert "n/a" not in text and "error: physics.timestep must be …" in text
    assert len(text.splitlines()) <= 6


def test_a_run_too_long_for_memory_fails_before_allocating(tmp_path):
    """A planner whose duration follows from the scene (twophase at 1 nm/s: 1.9e8 s) is
    checked by the simulation with its exact step count, before the logs exist."""
    cfg = make_cfg("trajectory=twophase", "trajectory.v_max_docking=1e-9", "task.progress=false")
    started = time.perf_counter()
    record = execute(cfg, tmp_path, figures=False, echo=False)
    assert record["status"] == "failed" and "its logs would need about" in record["error"]
    assert "the planned trajectory + task.settle_time" in record["error"]
    assert time.perf_counter() - started < 60  # nothing of 1.9e11 steps was allocated


# --------------------------------------------------------------------------- concurrent writers
def test_every_writer_has_its_own_temporary_name(tmp_path):
    target = tmp_path / "metrics.json"
    names = {files.temporary_name(target) for _ in range(100)}
    assert len(names) == 100 and all(n.name.startswith(".metrics.json.") for n in names)
    assert all(n.name.endswith(".tmp") and f".{os.getpid()}-" in n.name for n in names)


def test_concurrent_writers_of_one_file_never_collide(tmp_path):
    target = tmp_path / "figures"
    errors: list[BaseException] = []

    def write(k: int) -> None:
        def draw(folder: Path) -> None:
            folder.mkdir()
            (folder / "a.png").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes([k]) * 1000)

        try:
            for _ in range(20):
                rundir.write_figures(tmp_path, draw)
                files.atomic_write_text(tmp_path / "summary.txt", f"writer {k}\n")
        except BaseException as exc:  # pragma: no cover - the failure the test looks for
            errors.append(exc)

    threads = [threading.Thread(target=write, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figures", "summary.txt"]  # no leftovers
    assert (target / "a.png").stat().st_size == 1008
