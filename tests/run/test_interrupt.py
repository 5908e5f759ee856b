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
#: One signal per process test in the fast suite, the others in the nightly suite (`slow`):
#: the run installs one handler for SIGINT, SIGTERM and SIGHUP alike (run/interrupt.py's
#: raise_stop) and holds all three alike while its directory is claimed, so each test's
#: fast cell proves the path for every signal. Fast proofs: the signalled loop's SIGTERM
#: cell (143 through a process) and the claimed directory's SIGINT cell (130 through a
#: process), below; 129 for SIGHUP: tests/test_exit_codes.py; SIGHUP delivered to a
#: command: test_the_other_commands_stop_on_a_signal_in_one_line[interface]
_NIGHTLY = pytest.mark.slow(reason="the same handler as the fast cell; see _signals")


def _signals(fast: signal.Signals) -> list:
    """(signum, exit status, name) of each stop signal; only ``fast``'s cell in the fast suite."""
    cells = [
        (signal.SIGINT, 130, "SIGINT (Ctrl-C)"),
        (signal.SIGTERM, 143, "SIGTERM"),
        (signal.SIGHUP, 129, "SIGHUP"),
    ]
    return [cell if cell[0] == fast else pytest.param(*cell, marks=_NIGHTLY) for cell in cells]


def _start_run(run_dir: Path, *args: str) -> tuple[subprocess.Popen, list[str]]:
    """A long single run in a subprocess, its stderr on a pseudo-terminal (where the loop
    prints its progress: the marker that it runs); the pieces of stderr as they come."""
    import pty

    main_fd, child_fd = pty.openpty()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "compliant_docking",
            "trajectory.duration=200",
            *args,
            f"hydra.run.dir={run_dir}",
        ],
        cwd=REPO_ROOT,
        stdout=subprocess.PIPE,
        stderr=child_fd,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    os.close(child_fd)
    err: list[str] = []

    def read() -> None:
        while True:
            try:
                chunk = os.read(main_fd, 4096)
            except OSError:  # the run ended: the terminal is closed
                break
            if not chunk:
                break
            err.append(chunk.decode(errors="replace"))
        os.close(main_fd)

    threading.Thread(target=read, daemon=True).start()
    return proc, err


def _wait(proc: subprocess.Popen, ready, what: str) -> None:
    deadline = time.monotonic() + 180
    while not ready():
        assert proc.poll() is None, f"the run ended before {what}"
        assert time.monotonic() < deadline, f"no {what} within 180 s"
        time.sleep(0.01)


@pytest.mark.parametrize(("signum", "code", "how"), _signals(signal.SIGTERM))
def test_a_signalled_single_run_records_itself_as_interrupted(tmp_path, signum, code, how):
    """A signal in the middle of a run (once it prints its progress: the loop runs): status
    "interrupted" with the time series so far (one row per simulated step), exit 128 +
    signal number, no traceback."""
    run_dir = tmp_path / "run"
    proc, err = _start_run(run_dir, "task.progress=true")
    _wait(proc, lambda: "simulating" in "".join(err), "the loop's progress")
    proc.send_signal(signum)
    out, _ = proc.communicate(timeout=120)
    text = "".join(err)
    assert proc.returncode == code, text[-3000:]
    assert "Traceback" not in text and "KeyboardInterrupt" not in text
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


@pytest.mark.parametrize(("signum", "code", "how"), _signals(signal.SIGINT))
def test_a_signal_as_the_run_directory_appears_is_recorded(tmp_path, signum, code, how):
    """The moment the run's directory is claimed, before the loop (Hydra writes .hydra/, the
    libraries load): before, SIGINT left the directory without a record and SIGTERM ended
    with an ImportError traceback ("partially initialized module")."""
    run_dir = tmp_path / "run"
    proc, err = _start_run(run_dir, "task.progress=false")
    _wait(proc, run_dir.exists, "a run directory")
    proc.send_signal(signum)
    proc.communicate(timeout=120)
    text = "".join(err)
    assert proc.returncode == code, text[-3000:]
    assert "Traceback" not in text and "Error" not in text
    record = json.loads((run_dir / "metrics.json").read_text())
    assert record["status"] == "interrupted" and record["error"].startswith(f"interrupted by {how}")
    assert (run_dir / "summary.txt").is_file()


def test_a_signal_while_the_record_is_written_waits_for_it(tmp_path, monkeypatch):
    """A signal while the run's record is written: the record is finished first, whole, then
    the run stops with that signal."""
    from compliant_docking.run.interrupt import Stopped

    write = rundir.write_summary_text

    def signalled_write(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)  # delivered now, in the middle of the writing
        return write(*args, **kwargs)

    monkeypatch.setattr(rundir, "write_summary_text", signalled_write)
    cfg = make_cfg(
        "trajectory.duration=0.3", "task.settle_time=0.2", "task.press_duration=0.1", "task.progress=false"
    )
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: (_ for _ in ()).throw(Stopped(signum)))
    try:
        with pytest.raises(Stopped) as stopped:
            execute(cfg, tmp_path, figures=False, echo=False)
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert stopped.value.signum == signal.SIGTERM
    record = json.loads((tmp_path / "metrics.json").read_text())
    assert record["status"] == "ok" and (tmp_path / "summary.txt").is_file()  # the finished run's record


def test_an_interrupted_run_in_python_is_recorded_then_raised(tmp_path, monkeypatch):
    """execute() records the interruption, then raises it again: a loop of runs stops."""
    from compliant_docking.sim.simulate import Simulation

    cfg = make_cfg("trajectory.duration=200", "task.progress=false")
    done, looping = threading.Event(), threading.Event()
    start = Simulation.start

    def started(self, *args, **kwargs):  # the loop's bindings are made: its steps come next
        start(self, *args, **kwargs)
        looping.set()

    monkeypatch.setattr(Simulation, "start", started)

    def press_ctrl_c() -> None:  # 0.3 s into the loop, then twice a second until it has stopped
        while not looping.wait(0.05):
            if done.is_set():
                return
        while not done.wait(0.3 if not sent else 0.5):
            os.kill(os.getpid(), signal.SIGINT)
            sent.append(time.monotonic())

    sent: list[float] = []
    # Python's own Ctrl-C handler, whatever an earlier test in this process left behind
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    presser = threading.Thread(target=press_ctrl_c, daemon=True)
    presser.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            execute(cfg, tmp_path, figures=False, echo=False)
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # handlers restored
    finally:
        done.set()
        presser.join()
        signal.signal(signal.SIGINT, previous)
    record = json.loads((tmp_path / "metrics.json").read_text())
    assert record["status"] == "interrupted" and record["steps"] > 0
    assert len(pd.read_parquet(tmp_path / "timeseries.parquet")) == record["steps"]


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


@pytest.mark.parametrize(
    ("command", "patched", "signum"),
    [
        ("report", "compliant_docking.report.scan", signal.SIGTERM),
        ("findings", "compliant_docking.results.findings.load_runs", signal.SIGINT),
        ("interface", "compliant_docking.interface.convert", signal.SIGHUP),
    ],
)
def test_the_other_commands_stop_on_a_signal_in_one_line(
    tmp_path, monkeypatch, capsys, command, patched, signum
):
    """report, findings and interface: a signal ends them like the simulation's command (one
    line, 128 + signal number), not with a KeyboardInterrupt traceback."""
    import importlib

    def signalled(*args, **kwargs):
        os.kill(os.getpid(), signum)
        time.sleep(5)  # the handler raises before this ends
        raise AssertionError("the signal was not acted on")

    monkeypatch.setattr(patched, signalled)
    main = importlib.import_module(
        {"report": "compliant_docking.report", "findings": "compliant_docking.results.findings",
         "interface": "compliant_docking.interface"}[command]
    ).main  # fmt: skip
    cad = REPO_ROOT / "assets" / "interfaces" / "keyed_cad" / "cad"
    argv = {
        "report": [str(tmp_path)],
        "findings": [str(tmp_path)],
        "interface": [str(cad / "plug.stl"), str(cad / "socket.stl"), "--out", str(tmp_path / "out")],
    }[command]
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    assert main(argv) == 128 + signum
    err = capsys.readouterr().err
    assert err.strip().endswith(
        f"{command}: stopped by {'SIGINT (Ctrl-C)' if signum == signal.SIGINT else signum.name}"
    )
    assert "Traceback" not in err
    assert {s: signal.getsignal(s) for s in handlers} == handlers  # put back
