"""The command line refuses bad input before anything is written, gives every command a
directory of its own, and leaves no worker behind (compliant_docking/sweep/guard.py)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from datetime import datetime, timedelta
from pathlib import Path

import psutil
import pytest
from omegaconf import OmegaConf

from compliant_docking.run import directories
from tests.helpers import REPO_ROOT, SHORT_SWEEP, cli_in_process

#: short single runs: 1 s of motion, 1 s of settling
SHORT_RUN = ("trajectory.duration=1", "task.settle_time=1", "task.progress=false")


# --------------------------------------------------------------------------- refused up front
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("physics.timestep=0",), "physics.timestep must be a finite number in (0, 0.01] s; got 0.0."),
        (
            ("physics.timestep=-0.001",),
            "physics.timestep must be a finite number in (0, 0.01] s; got -0.001.",
        ),
        (("physics.timestep=nan",), "physics.timestep must be a finite number in (0, 0.01] s; got nan."),
        (("physics.timestep=inf",), "physics.timestep must be a finite number in (0, 0.01] s; got inf."),
        (("physics.timestep=100",), "physics.timestep must be a finite number in (0, 0.01] s; got 100.0."),
        (("task.duration=inf",), "task.duration must be a finite number > 0 s; got inf."),
        (("task.duration=1e9",), "its logs would need about"),
        (("robot.max_torque=[nan,10,10,10,10,10,10]",), "robot.max_torque[0] must be a finite number > 0"),
        (("robot.ik_guess=[0,nan,0,-1.6,0,1,0]",), "robot.ik_guess[1] must be a finite number"),
        (("controller.k=nan",), "controller.k must be a finite number >= 0 N/m; got nan."),
        (("controller.k=inf",), "controller.k must be a finite number >= 0 N/m; got inf."),
        (("task.stroke=[0,0,inf]",), "task.stroke[2] must be a finite number in [-10, 10] m; got inf."),
        (("controller=se3_lie", "controller.K_diag=[inf,50,50,25,25,25]"), "controller.K_diag[0] must be"),
        (("target.geometry.radial_clearance=-0.001",), "target.geometry.radial_clearance must be"),
        (
            ("+physcs.timestep=0.002",),
            "physcs.timestep is not a setting (added with + or ++?); did you mean physics.timestep?",
        ),
        (
            ("++physics.timstep=0.002",),
            "physics.timstep is not a setting of physics=space (added with + or ++?); did you mean physics.timestep?",
        ),
        (
            ("+controller.kk=1",),
            "controller.kk is not a setting of controller=impedance (added with + or ++?); did you mean controller.k?",
        ),
        (("controller.kk=1",), "controller.kk is not a setting; did you mean controller.k?"),
        (("viewer=true",), "viewer=true needs a desktop display"),
    ],
)
def test_a_bad_input_is_refused_before_a_run_directory_is_written(
    tmp_path, monkeypatch, capsys, args, message
):
    monkeypatch.chdir(tmp_path)  # the default run directory: runs/<date>/<time>_…
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    code, err = cli_in_process(capsys, *args, *SHORT_RUN)
    assert code == 2
    assert message in err
    assert err.startswith("compliant-docking: the configuration is refused; nothing was run or written.")
    assert "Traceback" not in err and "n/a" not in err
    assert "Config" not in err.replace("configuration", "")  # config keys, never schema classes
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ("trajectory=twophase", "trajectory.v_max_docking=1e-9"),  # a planner's duration: 1.9e8 s
            "its logs would need about",
        ),
        (
            tuple(f"robot.{k}=[1,1,1,1,1,1]" for k in ("velocity_limits", "torque_limits", "max_torque"))
            + ("robot.ik_guess=[0,0.5,0,-1.6,0,1]",),
            "robot.velocity_limits has 6 values; robot iiwa14 has 7 joints: give one value per joint.",
        ),
        (("trajectory=tracking",), "trajectory=tracking is a free-space test and must not touch the docking"),
        (
            ("target=none", "trajectory=twophase", "task.init_pos=[0.55,0,0.35]"),
            "trajectory=twophase needs a goal (a target)",
        ),
        (("tool.mjcf=no/such/tool.xml",), "tool.mjcf must name an MJCF file; there is no such file "),
        (("tool.mjcf=assets/iiwa14/iiwa14.xml",), "iiwa14.xml: no body named 'dock'. A tool fragment must"),
        (("target.mjcf=no/such/target.xml",), "target.mjcf must name an MJCF file; there is no such file "),
        (("robot.mjcf=no/such/robot.xml",), "robot.mjcf must name an MJCF file; there is no such file "),
        (
            ("robot.ee_site=flange",),
            "robot.ee_site must be a site of robot.mjcf (attachment_site); got 'flange'.",
        ),
        (
            ("controller=hqp", "controller.eps_abs=5"),
            "robot.max_torque must exceed 4·controller.eps_abs = 20 N·m for every joint",
        ),
    ],
)
def test_what_only_the_robot_the_planner_or_the_files_tell_is_refused_up_front(
    tmp_path, monkeypatch, capsys, args, message
):
    """A job the run would refuse once its scene and planner exist is refused before its
    directory does: the planner's own checks and its duration (the memory of the run),
    per-joint lists against the robot's joints, the files the run loads."""
    monkeypatch.chdir(tmp_path)
    code, err = cli_in_process(capsys, *args, "task.progress=false")
    assert code == 2
    assert message in err
    assert err.startswith("compliant-docking: the configuration is refused; nothing was run or written.")
    assert "Traceback" not in err
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ("robot=iiwa14,ur5",),
            "Could not find 'robot/ur5'; Available options in 'robot': fr3, iiwa14 [job 1: robot=ur5",
        ),
        (
            ("controller.k=50,nan",),
            "controller.k must be a finite number >= 0 N/m; got nan. [job 1: controller.k=nan",
        ),
        (("viewer=true",), "viewer=true is refused in a sweep (-m)"),
        (
            ("controller.k=40,50", "+controller.kk=1"),
            "controller.kk is not a setting of controller=impedance (added with + or ++?); "
            "did you mean controller.k? [jobs 0, 1;",
        ),
    ],
)
def test_a_bad_sweep_is_refused_before_anything_is_created(tmp_path, monkeypatch, capsys, args, message):
    monkeypatch.chdir(tmp_path)
    code, err = cli_in_process(capsys, "-m", *args, *SHORT_SWEEP)
    assert code == 2
    assert message in err
    assert err.startswith("compliant-docking: the sweep is refused; nothing was run or written.")
    assert "resume" not in err and "Traceback" not in err
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("trajectory=hold,tracking",), "trajectory=tracking is a free-space test"),
        (
            ("trajectory=twophase", "trajectory.v_max_docking=0.02,1e-9"),
            "its logs would need about",
        ),
    ],
)
def test_a_sweep_whose_planner_refuses_a_job_is_refused_up_front(
    tmp_path, monkeypatch, capsys, args, message
):
    monkeypatch.chdir(tmp_path)
    code, err = cli_in_process(capsys, "-m", *args, "task.progress=false")
    assert code == 2 and message in err and "[job 1: " in err
    assert err.startswith("compliant-docking: the sweep is refused; nothing was run or written.")
    assert not (tmp_path / "runs").exists()


def test_a_slurm_sweep_without_slurm_is_refused_before_anything_is_created(tmp_path, monkeypatch, capsys):
    """hydra/launcher=submitit_slurm on a machine without sbatch: before, the sweep directory
    and an empty "aborted" summary were written and the command exited 0."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PATH", str(tmp_path / "no_slurm_here"))  # no sbatch (nor srun) to find
    code, err = cli_in_process(
        capsys, "-m", "controller.k=50,60", "hydra/launcher=submitit_slurm", *SHORT_SWEEP
    )
    assert code == 2
    assert err.startswith("compliant-docking: the sweep is refused; nothing was run or written.")
    assert "hydra/launcher=submitit_slurm needs Slurm, and this machine has no sbatch on its PATH" in err
    assert not (tmp_path / "runs").exists()


def test_an_unwritable_directory_is_refused_before_anything_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    code, err = cli_in_process(
        capsys, "-m", "controller.k=40,50", f"hydra.sweep.dir={blocker}/sweep", *SHORT_SWEEP
    )
    assert code == 2 and f"hydra.sweep.dir={blocker}/sweep: {blocker} is not a directory" in err
    assert "resume" not in err
    code, err = cli_in_process(
        capsys, "-m", "controller.k=40,50", "hydra.sweep.dir=/proc/sweep", *SHORT_SWEEP
    )
    assert code == 2 and "hydra.sweep.dir=/proc/sweep: cannot write in /proc" in err
    code, err = cli_in_process(capsys, "hydra.run.dir=/proc/run", *SHORT_RUN)
    assert code == 2 and "hydra.run.dir=/proc/run: cannot write in /proc" in err
    if os.geteuid() != 0:  # permission bits bind everyone but root
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o555)
        code, err = cli_in_process(
            capsys, "-m", "controller.k=40,50", f"hydra.sweep.dir={locked}/sweep", *SHORT_SWEEP
        )
        assert code == 2 and "cannot write in" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"] + (["locked"] if os.geteuid() else [])


# --------------------------------------------------------------------------- own directories
def test_a_taken_default_name_gets_the_next_free_one(tmp_path):
    run_dir = tmp_path / "runs" / "14-03-12_iiwa14_impedance_quintic"
    cfg = OmegaConf.create({"hydra": {"run": {"dir": str(run_dir)}, "overrides": {"hydra": []}}})
    assert directories.claim(cfg, "run") is None and run_dir.is_dir()
    assert directories.claim(cfg, "run") is None and cfg.hydra.run.dir == f"{run_dir}_2"
    sweep = OmegaConf.create({"hydra": {"sweep": {"dir": str(run_dir)}, "overrides": {"hydra": []}}})
    assert directories.claim(sweep, "sweep") is None and sweep.hydra.sweep.dir == f"{run_dir}_3"
    assert list(sweep.hydra.overrides.hydra) == [f"hydra.sweep.dir={run_dir}_3"]  # for the jobs
    explicit = OmegaConf.create(
        {"hydra": {"run": {"dir": str(run_dir)}, "overrides": {"hydra": [f"hydra.run.dir={run_dir}"]}}}
    )
    assert directories.claim(explicit, "run") is None and explicit.hydra.run.dir == str(run_dir)  # as given


def test_a_claimed_directory_that_stayed_empty_is_released(tmp_path):
    """A sweeper that refuses its set-up after the claim (the tuning sweeper) leaves nothing."""
    empty, used = tmp_path / "empty", tmp_path / "used"
    for path in (empty, used):
        cfg = OmegaConf.create({"hydra": {"sweep": {"dir": str(path)}, "overrides": {"hydra": []}}})
        assert directories.claim(cfg, "sweep") is None
    (used / "multirun.yaml").write_text("hydra: {}\n")
    directories.release_empty()
    assert not empty.exists() and (used / "multirun.yaml").is_file() and not directories.CLAIMED


def _block_the_next_minute(root: Path, pattern: str) -> set[Path]:
    """Create the default directories of the next 90 seconds, so that two commands started
    now both find their name taken and race for the next free one."""
    now = datetime.now()
    made = set()
    for s in range(-2, 90):
        moment = now + timedelta(seconds=s)
        path = root / moment.strftime("%Y-%m-%d") / (moment.strftime("%H-%M-%S") + pattern)
        path.mkdir(parents=True, exist_ok=True)
        made.add(path)
    return made


def _together(cwd: Path, *commands: list[str]) -> list[subprocess.CompletedProcess]:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "compliant_docking", *args],
            cwd=cwd,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        for args in commands
    ]
    outputs = [p.communicate(timeout=600) for p in procs]
    return [subprocess.CompletedProcess(p.args, p.returncode, *o) for p, o in zip(procs, outputs)]


#: the racing runs: 0.3 s simulated each (the race is for the directory, claimed before the
#: simulation starts; what they simulate is not judged)
RACING_RUN = (
    "trajectory.duration=0.2",
    "task.settle_time=0.1",
    "task.press_duration=0.1",
    "task.progress=false",
)


def test_two_runs_started_together_each_get_their_own_directory(tmp_path):
    blocked = _block_the_next_minute(tmp_path / "runs", "_iiwa14_impedance_quintic")
    results = _together(tmp_path, ["controller.k=40", *RACING_RUN], ["controller.k=300", *RACING_RUN])
    for result in results:
        assert result.returncode in (0, 3), result.stderr[-3000:]
    records = {p.parent: json.loads(p.read_text()) for p in (tmp_path / "runs").glob("*/*/metrics.json")}
    assert len(records) == 2  # both finished, each in its own directory
    assert {r["overrides"].split()[0] for r in records.values()} == {"controller.k=40", "controller.k=300"}
    for run_dir, record in records.items():
        assert run_dir not in blocked and run_dir.name.endswith(("_2", "_3"))
        assert record["status"] == "ok" and (run_dir / "timeseries.parquet").is_file()
        assert (run_dir / "figures" / "contact_force.png").is_file()
        assert str(run_dir.relative_to(tmp_path)) in " ".join(r.stdout for r in results)


@pytest.mark.slow(reason="the same claim as test_two_runs_started_together, for a sweep; see the comment")
def test_two_sweeps_started_together_each_get_their_own_directory(tmp_path):
    # nightly (two sweep processes and their workers): a sweep takes its directory by the
    # claim a run does (sweep/directories.py), which test_two_runs_started_together races
    # between two real processes in the fast suite; the next free sweep name and the
    # override that sends the jobs there: test_a_taken_default_name_gets_the_next_free_one
    blocked = _block_the_next_minute(tmp_path / "runs" / "multirun", "")
    sweep = ["-m", *SHORT_SWEEP, "hydra.launcher.n_jobs=1", "hydra.callbacks.sweep.figures=false"]
    results = _together(tmp_path, [*sweep, "controller.k=40,41"], [*sweep, "controller.k=300,301"])
    for result in results:
        assert result.returncode == 0, result.stderr[-3000:]
        counts = sorted(
            line[:5] for line in result.stdout.splitlines() if line.startswith("[") and "/2]" in line
        )
        assert counts == ["[1/2]", "[2/2]"]  # no [4/2]: the other sweep's jobs are elsewhere
        assert "2 jobs: 2 finished" in result.stdout
    sweeps = {p.parent for p in (tmp_path / "runs" / "multirun").glob("*/*/multirun.yaml")}
    assert len(sweeps) == 2 and not sweeps & blocked
    for sweep_dir in sweeps:
        jobs = sorted(p.name for p in sweep_dir.iterdir() if p.is_dir())
        assert len(jobs) == 2 and len({j.split("controller.k=")[1][0] for j in jobs}) == 1  # one sweep's
        assert not (sweep_dir / ".finished_jobs").exists()


# --------------------------------------------------------------------------- orphans
def _loky_workers(pid: int) -> list[psutil.Process]:
    """The loky workers among the descendants of ``pid``; a process that ends while it is
    looked at (a zombie, gone: e.g. a job's short-lived ``git``) is not one of them."""
    found = []
    for p in psutil.Process(pid).children(recursive=True):
        try:
            if "popen_loky_posix" in " ".join(p.cmdline()):
                found.append(p)
        except (psutil.ZombieProcess, psutil.NoSuchProcess, psutil.AccessDenied):
            continue
    return found


# nightly (a real sweep killed with SIGKILL); fast proof:
# tests/sweep/test_watchdog.py::test_a_pool_worker_exits_when_its_launching_process_dies
# (the pool's worker start-up starts the watchdog, and a worker whose launcher dies exits)
@pytest.mark.slow
def test_the_workers_of_a_killed_sweep_exit_within_a_minute(tmp_path):
    """SIGKILL of the launching process leaves its joblib worker without a parent: its
    watchdog ends it (measured: about 1 s) instead of loky's 300 s idle timeout or, as
    seen, a pipe write blocked for good. One worker: every worker runs its own watchdog."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "compliant_docking",
            "-m",
            "task.settle_time=1,2",
            "trajectory.duration=60",
            "task.progress=false",
            f"hydra.sweep.dir={tmp_path / 'sweep'}",
            "hydra.launcher.n_jobs=1",
            "hydra.callbacks.sweep.figures=false",
        ],
        cwd=REPO_ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    workers: list[psutil.Process] = []
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:  # the worker started and running a job
            workers = _loky_workers(proc.pid)
            if len(workers) == 1 and list((tmp_path / "sweep").glob("*/.hydra/*")):
                break
            time.sleep(0.1)
        assert len(workers) == 1, "the sweep did not start its worker"
        time.sleep(0.5)  # inside its job
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        killed_at = time.monotonic()
        gone, alive = psutil.wait_procs(workers, timeout=60)
        assert not alive, f"workers alive 60 s after their parent died: {[p.pid for p in alive]}"
        assert time.monotonic() - killed_at < 60
    finally:
        for worker in workers:  # only the processes this test started, by pid
            if worker.is_running():
                worker.kill()
