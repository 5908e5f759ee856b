"""No command can destroy or mix results: an explicit run or sweep directory must be new or
empty (or continued: resume=, a tuning study), every job writes a directory of its own
inside its sweep, and a resume touches nothing outside its sweep nor moves its jobs
(compliant_docking/sweep/directories.py, sweep/resume.py)."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest
from omegaconf import OmegaConf

from tests.helpers import cli_in_process, cli_in_process_output

#: a two-job sweep in free space, 0.2 s simulated per job, jobs run in the launching process
TINY = (
    "controller.k=50,60",
    "trajectory=hold",
    "trajectory.duration=0.2",
    "target=none",
    "task.init_pos=[0.55,0,0.35]",
    "task.settle_time=0",
    "task.progress=false",
    "hydra/launcher=basic",
    "hydra.callbacks.sweep.figures=false",
)


def _tree(path: Path) -> dict[str, bytes]:
    """Every file under ``path`` with its bytes: what a refused command must leave as it was."""
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


# --------------------------------------------------------------------------- job directories
@pytest.mark.parametrize(
    ("subdirs", "message"),
    [
        ({0: "same", 1: "same"}, "job 1 would write the same directory as job 0 ('same')"),
        ({0: "a", 1: "a/b"}, "job 1 would write a directory inside that of job 0 ('a/b')"),
        ({0: "0_x", 1: ".."}, "job 1's is '..'"),
        ({0: "0_x", 1: "x/../../victim"}, "job 1's is 'x/../../victim'"),
        ({0: "/tmp/victim", 1: "1_x"}, "job 0's is '/tmp/victim'"),
        ({0: "", 1: "1_x"}, "job 0's is ''"),
        ({0: ".", 1: "1_x"}, "job 0's is '.'"),
    ],
)
def test_every_job_needs_a_directory_of_its_own_inside_the_sweep(subdirs, message):
    from compliant_docking.sweep.directories import job_dir_problems

    found = job_dir_problems(subdirs)
    assert len(found) == 1 and message in found[0]
    assert found[0].startswith("hydra.sweep.subdir must")


def test_distinct_job_directories_inside_the_sweep_pass():
    from compliant_docking.sweep.directories import job_dir_problems

    assert job_dir_problems({0: "0_a", 1: "1_a", 2: "2_tool.mjcf=my_parts/tool.xml", 3: "x/../3_b"}) == []


@pytest.mark.parametrize(
    ("subdir", "message"),
    [
        ("same", "job 1 would write the same directory as job 0"),  # before: 1 job counted, exit 0
        ("..", "job 0's is '..'"),  # before: the jobs wrote into the sweep's parent
        ("/tmp/elsewhere", "job 0's is '/tmp/elsewhere'"),
    ],
)
def test_a_sweep_whose_jobs_share_or_leave_its_directory_is_refused(
    tmp_path, monkeypatch, capsys, subdir, message
):
    monkeypatch.chdir(tmp_path)
    code, err = cli_in_process(
        capsys, "-m", *TINY, f"hydra.sweep.dir={tmp_path / 'sweep'}", f"hydra.sweep.subdir={subdir}"
    )
    assert code == 2 and message in err
    assert err.startswith("compliant-docking: the sweep is refused; nothing was run or written.")
    assert sorted(os.listdir(tmp_path)) == []


# --------------------------------------------------------------------------- explicit directories
def test_a_run_into_a_used_run_directory_is_refused_and_mixes_nothing(tmp_path, monkeypatch, capsys):
    """Before: the second run overwrote the first's metrics and kept its figures."""
    monkeypatch.chdir(tmp_path)
    used = tmp_path / "run"
    (used / "figures").mkdir(parents=True)
    (used / "figures" / "contact_force.png").write_bytes(b"\x89PNG first run")
    (used / "metrics.json").write_text('{"status": "ok", "controller": "first"}')
    before = _tree(used)
    code, err = cli_in_process(
        capsys, "trajectory.duration=0.2", "task.progress=false", f"hydra.run.dir={used}"
    )
    assert code == 2
    assert (
        f"hydra.run.dir={used} is not empty (figures, metrics.json): a run writes into a new or empty" in err
    )
    assert "choose another directory or remove this one." in err and "resume" not in err
    assert _tree(used) == before


def test_a_sweep_into_a_used_sweep_directory_is_refused_and_keeps_it_resumable(tmp_path, monkeypatch, capsys):
    """Before: the second sweep's jobs joined the first's in the summary, and its
    multirun.yaml replaced the first's, which could then no longer be resumed."""
    monkeypatch.chdir(tmp_path)
    used = tmp_path / "sweep"
    (used / "0_controller.k=50").mkdir(parents=True)
    (used / "0_controller.k=50" / "metrics.json").write_text('{"status": "ok"}')
    (used / "multirun.yaml").write_text("hydra: {overrides: {task: [controller.k=50]}}\n")
    before = _tree(used)
    code, err = cli_in_process(capsys, "-m", *TINY, f"hydra.sweep.dir={used}")
    assert code == 2
    assert f"hydra.sweep.dir={used} is not empty (0_controller.k=50, multirun.yaml)" in err
    assert f"to finish the sweep in it, run that sweep's command with resume={used}" in err
    assert _tree(used) == before


def test_an_explicit_directory_inside_a_sweep_is_refused(tmp_path, monkeypatch, capsys):
    """A run or sweep inside another sweep's directory would join that sweep's summary and resume."""
    monkeypatch.chdir(tmp_path)
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    (sweep / "multirun.yaml").write_text("hydra: {}\n")
    code, err = cli_in_process(
        capsys, "trajectory.duration=0.2", "task.progress=false", f"hydra.run.dir={sweep}/extra"
    )
    assert code == 2 and f"hydra.run.dir={sweep}/extra lies inside the sweep directory {sweep}" in err
    code, err = cli_in_process(capsys, "-m", *TINY, f"hydra.sweep.dir={sweep}/a/b")
    assert code == 2 and "lies inside the sweep directory" in err
    assert sorted(p.name for p in sweep.iterdir()) == ["multirun.yaml"]


def test_the_claim_rule(tmp_path):
    """Default names take the next free one; explicit ones must be new or empty; continued
    ones are used as they are."""
    from compliant_docking.run import directories
    from compliant_docking.run.directories import claim

    def config(kind: str, path: Path, explicit: bool):
        overrides = [f"hydra.{kind}.dir={path}"] if explicit else []
        return OmegaConf.create({"hydra": {kind: {"dir": str(path)}, "overrides": {"hydra": overrides}}})

    empty, held = tmp_path / "empty", tmp_path / "held"
    empty.mkdir()
    held.mkdir()
    (held / "x").write_text("")
    assert claim(config("run", empty, True), "run") is None  # an empty directory: fine
    assert claim(config("run", tmp_path / "new", True), "run") is None and (tmp_path / "new").is_dir()
    assert "is not empty (x)" in claim(config("run", held, True), "run")
    assert claim(config("sweep", held, True), "sweep", continued=True) is None  # resume=, a study
    cfg = config("sweep", held, False)
    assert claim(cfg, "sweep") is None and cfg.hydra.sweep.dir == f"{held}_2"  # a default name
    directories.release_empty()
    assert not (tmp_path / "new").exists() and not empty.with_name("held_2").exists() and empty.is_dir()


# --------------------------------------------------------------------------- resume
def _sweep(capsys, *extra: str) -> SimpleNamespace:
    """The TINY sweep with ``extra`` through the command line's main, in this process (its
    jobs too: Hydra's basic launcher): returncode, stdout, stderr."""
    code, out, err = cli_in_process_output(capsys, "-m", *TINY, *extra)
    return SimpleNamespace(returncode=code, stdout=out, stderr=err)


@pytest.fixture(scope="module")
def finished_sweep(tmp_path_factory):
    """A two-job sweep whose second job is left unfinished (its metrics.json removed), so that
    a resume would rerun it: the job a moved directory would aim elsewhere."""
    from compliant_docking.cli import main

    sweep_dir = tmp_path_factory.mktemp("resume") / "sweep"
    assert main(["-m", *TINY, f"hydra.sweep.dir={sweep_dir}"]) == 0
    jobs = sorted(p for p in sweep_dir.iterdir() if p.is_dir() and p.name[0].isdigit())
    (jobs[1] / "metrics.json").unlink(missing_ok=True)
    return sweep_dir


@pytest.mark.parametrize(
    ("moves", "message"),
    [
        (("hydra.sweep.subdir={victim}",), "named its jobs' directories with"),
        (("hydra.sweep.subdir=..",), "named its jobs' directories with"),
        (("hydra.sweep.subdir=same",), "named its jobs' directories with"),
        (("hydra.job.config.override_dirname.item_sep=+",), "named its jobs' directories with"),
    ],
)
def test_a_resume_that_would_move_its_jobs_is_refused_and_touches_nothing(
    finished_sweep, tmp_path, capsys, moves, message
):
    """Before: rerunning a job emptied the directory its composed path pointed to, even
    outside the sweep (another directory, the sweep's parent)."""
    victim = tmp_path / "precious"
    victim.mkdir()
    (victim / "data.txt").write_text("keep me")
    sweep_before, parent_before = _tree(finished_sweep), _tree(finished_sweep.parent)
    result = _sweep(capsys, f"resume={finished_sweep}", *(m.format(victim=victim) for m in moves))
    assert result.returncode == 2, result.stdout[-2000:] + result.stderr[-2000:]
    assert result.stderr.startswith("resume: ") and message in result.stderr
    assert "Traceback" not in result.stderr
    assert (victim / "data.txt").read_text() == "keep me" and sorted(os.listdir(victim)) == ["data.txt"]
    assert _tree(finished_sweep) == sweep_before and _tree(finished_sweep.parent) == parent_before


def test_a_resume_that_finds_job_directories_it_would_not_write_is_refused(finished_sweep, tmp_path, capsys):
    """Jobs named otherwise than when the sweep ran (here: a job directory of another
    naming, as an edited default would leave): the summary would mix both."""
    copy = tmp_path / "sweep"
    subprocess.run(["cp", "-a", str(finished_sweep), str(copy)], check=True)
    stray = copy / "7_controller.k=70"
    (stray / ".hydra").mkdir(parents=True)
    before = _tree(copy)
    result = _sweep(capsys, f"resume={copy}")
    assert result.returncode == 2
    assert (
        "the sweep holds job directories that none of this command's jobs would write (7_controller.k=70)"
        in (result.stderr)
    )
    assert _tree(copy) == before


def test_the_resume_of_an_untouched_sweep_still_finishes_it(finished_sweep, tmp_path, capsys):
    copy = tmp_path / "sweep"
    subprocess.run(["cp", "-a", str(finished_sweep), str(copy)], check=True)
    result = _sweep(capsys, f"resume={copy}")
    assert result.returncode == 0, result.stderr[-3000:]
    assert "skipped: finished earlier with the same config" in result.stdout
    records = [json.loads(p.read_text()) for p in copy.glob("*/metrics.json")]
    assert len(records) == 2 and all(r["status"] == "ok" for r in records)


# --------------------------------------------------------------------------- long job names
def test_a_job_name_too_long_for_a_file_name_is_shortened_with_a_hash():
    from compliant_docking.config.resolvers import NAME_BYTES, job_dir

    assert job_dir(3, "controller.k=50,robot=fr3") == "3_controller.k=50,robot=fr3"  # as Hydra named it
    assert job_dir(0, "") == "0_" and job_dir(2, "tool.mjcf=tool.xml") == "2_tool.mjcf=tool.xml"
    long = "robot.max_torque=[" + ",".join(["10.000000000001"] * 7) + "]," + "x" * 300
    name = job_dir(12, long)
    assert len(name.encode()) <= NAME_BYTES and "/" not in name
    assert name.startswith("12_robot.max_torque=[10.000000000001,") and name == job_dir(12, long)
    assert name != job_dir(13, long) and name != job_dir(12, long + "y")  # unique
    wide = job_dir(1, "task.note=" + "é" * 200)  # two bytes a character: cut between characters
    assert len(wide.encode()) <= NAME_BYTES and wide.encode().decode() == wide


def test_a_file_path_in_a_job_name_is_its_folder_and_stem_one_directory_deep():
    """Before: the README's CAD sweep named its jobs ``0_…,target.mjcf=assets/interfaces/
    keyed_cad/target.xml,tool.mjcf=assets/…/tool.xml``, seven directories deep, and every job
    was called ``tool.xml`` in the progress lines, summary.md and load_runs."""
    from compliant_docking.config.resolvers import job_dir

    cad = "assets/interfaces/keyed_cad"
    name = job_dir(0, f"controller=hqp,robot=fr3,target.mjcf={cad}/target.xml,tool.mjcf={cad}/tool.xml")
    assert name == "0_controller=hqp,robot=fr3,target.mjcf=keyed_cad-target,tool.mjcf=keyed_cad-tool"
    assert job_dir(1, "tool.mjcf=/home/me/parts/plug.xml") == "1_tool.mjcf=parts-plug"
    # two paths of one job that would read the same: a hash of each path tells them apart
    twins = job_dir(2, "tool.mjcf=a/parts/plug.xml,target.mjcf=b/parts/plug.xml")
    first, second = (part.split("=")[1] for part in twins.split(","))
    assert "/" not in twins and first != second and first.startswith("parts-plug~")
    assert twins == job_dir(2, "tool.mjcf=a/parts/plug.xml,target.mjcf=b/parts/plug.xml")  # stable
    # values with Hydra's own syntax are left as Hydra wrote them
    assert job_dir(3, "controller.m=tag(log,interval(1,10))") == "3_controller.m=tag(log,interval(1,10))"


def test_the_sweep_job_directory_template_shortens_long_names():
    """conf/config.yaml's hydra.sweep.subdir through Hydra's own composition (the resolver is
    registered wherever the config is used)."""
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    from compliant_docking import CONF_DIR
    from compliant_docking.config import register_schemas

    register_schemas()
    GlobalHydra.instance().clear()
    torque = "robot.torque_limits=[" + ",".join(["320.000000000000001"] * 7) + "]"
    velocity = "robot.velocity_limits=[" + ",".join(["1.48350000000000001"] * 7) + "]"
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose("config", overrides=["controller.k=50", torque, velocity], return_hydra_config=True)
    OmegaConf.set_readonly(cfg.hydra, False)
    cfg.hydra.job.num = 4
    cfg.hydra.job.override_dirname = f"controller.k=50,{torque},{velocity}"
    subdir = str(cfg.hydra.sweep.subdir)
    assert subdir.startswith("4_controller.k=50,robot.torque_limits=[320.") and len(subdir.encode()) <= 255
    cfg.hydra.job.override_dirname = "controller.k=50"
    assert str(cfg.hydra.sweep.subdir) == "4_controller.k=50"


@pytest.mark.slow
def test_a_sweep_with_long_job_names_runs_and_resumes(tmp_path, capsys):
    """Before: the sweep aborted with a traceback (File name too long), and the suggested
    resume= failed the same way."""
    torque = "robot.torque_limits=[" + ",".join(["320.000000000000001"] * 7) + "]"
    velocity = "robot.velocity_limits=[" + ",".join(["1.48350000000000001"] * 7) + "]"
    sweep = tmp_path / "sweep"
    first = _sweep(capsys, torque, velocity, f"hydra.sweep.dir={sweep}")
    assert first.returncode == 0, first.stderr[-3000:]
    jobs = sorted(p for p in sweep.iterdir() if p.is_dir())
    assert len(jobs) == 2 and all(
        len(p.name.encode()) <= 255 and (p / "metrics.json").is_file() for p in jobs
    )
    again = _sweep(capsys, torque, velocity, f"resume={sweep}")
    assert again.returncode == 0, again.stderr[-3000:]
    assert again.stdout.count("skipped: finished earlier with the same config") == 2


def test_a_jobs_sweep_directory_is_found_also_after_hydra_job_chdir(tmp_path, monkeypatch):
    """hydra.job.chdir=true moves a job into its own directory: a relative sweep directory
    is taken from where the command started (before: the rerun of a resumed job was
    refused as outside its sweep, and progress lines lost their count)."""
    from compliant_docking.sweep.directories import sweep_dir_of

    job = tmp_path / "runs" / "sweep" / "0_x"
    job.mkdir(parents=True)
    monkeypatch.chdir(job)
    hydra_cfg = OmegaConf.create({"sweep": {"dir": "runs/sweep"}, "runtime": {"cwd": str(tmp_path)}})
    assert sweep_dir_of(hydra_cfg) == (tmp_path / "runs" / "sweep").resolve()
    absolute = OmegaConf.create({"sweep": {"dir": str(tmp_path / "elsewhere")}, "runtime": {"cwd": "/"}})
    assert sweep_dir_of(absolute) == (tmp_path / "elsewhere").resolve()
