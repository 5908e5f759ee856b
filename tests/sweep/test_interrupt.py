"""A signal stops a whole sweep: its workers are gone when the command ends, no job starts
after it, every job directory has a record, the summary says what finished, and the exit
status is 128 + the signal's number — at every moment: before the first job, while jobs
run, while the summary is written. Real signals to a real sweep, each sent when the
sweep's own output shows the moment (no fixed sleeps: the machine may be loaded)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pytest

from tests.helpers import REPO_ROOT

#: four short docking jobs on two workers (about half a second of simulation each)
JOBS = (
    "controller.k=50,60,70,80",
    "trajectory.duration=0.5",
    "task.settle_time=0.3",
    "task.press_duration=0.1",
    "task.progress=false",
    "hydra.launcher.n_jobs=2",
    "hydra.callbacks.sweep.figures=false",
)
#: the moments, by the line of the sweep's output that shows them
MOMENTS = {
    "before the jobs": lambda line: line.startswith("sweep: 4 jobs"),
    "while jobs run": lambda line: line.startswith("[1/4]"),
    "while the summary is written": lambda line: line.startswith("[4/4]"),
}
#: (signal, sent to): SIGTERM to the launching process (kill, a scheduler), SIGINT and
#: SIGHUP to the whole process group (Ctrl-C, the terminal closing)
SIGNALS = {
    "SIGTERM": (signal.SIGTERM, "process"),
    "SIGINT": (signal.SIGINT, "group"),
    "SIGHUP": (signal.SIGHUP, "group"),
}
#: the cases of the fast suite (the others are marked slow)
FAST = {("while jobs run", "SIGTERM")}


def _job_dirs(sweep_dir: Path) -> set[str]:
    return (
        {p.name for p in sweep_dir.iterdir() if p.is_dir() and p.name[0].isdigit()}
        if sweep_dir.is_dir()
        else set()
    )


@pytest.mark.parametrize(
    ("moment", "name"),
    [
        pytest.param(m, n, marks=() if (m, n) in FAST else pytest.mark.slow, id=f"{n} {m}")
        for m in MOMENTS
        for n in SIGNALS
    ],
)
def test_a_signal_stops_the_whole_sweep(tmp_path, moment, name):
    signum, target = SIGNALS[name]
    sweep_dir = tmp_path / "sweep"
    proc = subprocess.Popen(
        [sys.executable, "-m", "compliant_docking", "-m", *JOBS, f"hydra.sweep.dir={sweep_dir}"],
        cwd=REPO_ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        start_new_session=True,  # a process group of its own, workers included
    )
    out: list[str] = []
    err: list[str] = []
    readers = [
        threading.Thread(target=lambda: out.extend(proc.stdout), daemon=True),
        threading.Thread(target=lambda: err.extend(proc.stderr), daemon=True),
    ]
    for reader in readers:
        reader.start()
    deadline = time.monotonic() + 180
    while not any(MOMENTS[moment](line) for line in list(out)):
        assert proc.poll() is None, "".join(out)[-2000:] + "".join(err)[-2000:]
        assert time.monotonic() < deadline, f"the sweep showed no sign of {moment!r} within 180 s"
        time.sleep(0.01)
    workers = psutil.Process(proc.pid).children(recursive=True)
    if target == "group":
        os.killpg(proc.pid, signum)
    else:
        os.kill(proc.pid, signum)
    proc.wait(timeout=120)
    at_exit = _job_dirs(sweep_dir)
    gone, alive = psutil.wait_procs(workers, timeout=5)
    for reader, pipe in zip(readers, (proc.stdout, proc.stderr)):
        reader.join(timeout=10)  # the pipes end with the processes that held them
        pipe.close()
    text_out, text_err = "".join(out), "".join(err)

    assert proc.returncode == 128 + signum, text_out[-2000:] + text_err[-2000:]
    assert "Traceback" not in text_err
    assert not alive, f"workers still running after the command ended: {[p.pid for p in alive]}"
    time.sleep(1.0)  # a worker that lived on would start a job now
    assert _job_dirs(sweep_dir) == at_exit, "a job started after the sweep was stopped"
    for job in at_exit:  # every job that started has a record: its own, or the aborted sweep's
        assert (sweep_dir / job / "metrics.json").is_file(), job
    summary = (sweep_dir / "summary.md").read_text()
    assert f"{len(at_exit)} jobs:" in summary
    finished = [line for line in text_out.splitlines() if line.startswith("[") and "/4]" in line]
    assert len(finished) <= 4 and "never started" in text_out if len(at_exit) < 4 else True
