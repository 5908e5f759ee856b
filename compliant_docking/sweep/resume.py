"""Resuming a sweep: ``python -m compliant_docking -m <the sweep's overrides> resume=<sweep dir>``.

A sweep's job directories are deterministic: ``<job number>_<overrides>`` under the
sweep directory. Resuming runs the same sweep again into the same directory:

- :func:`translate_argv` (``__main__.main()``, before Hydra parses the command line)
  turns ``resume=<sweep dir>`` (or ``resume=last``: the newest sweep under
  ``runs/multirun``; or ``resume=true`` beside an explicit ``hydra.sweep.dir=…``) into
  the Hydra overrides ``hydra.sweep.dir=<dir> hydra.callbacks.sweep.resume=true
  hydra.output_subdir=null``. ``resume`` is not a task override, so the jobs' names,
  ``.hydra/overrides.yaml`` and composed configs are the same as in the first run.
- :func:`check_sweep` (the guard, launching process, before anything is created)
  refuses a directory without ``multirun.yaml``, a command whose task overrides or
  preset lists differ from the ones the sweep was started with (jobs would get other
  numbers and names), or whose Hydra overrides name the jobs' directories otherwise
  (``hydra.sweep.subdir``, ``hydra.job.*``). The guard then checks that every job's
  directory lies inside the sweep directory, one per job, and that the sweep holds no job
  directory this command's jobs would not write (:func:`foreign_job_dirs`); the sweep
  callback prints what the resume will find (:func:`status_lines`).
- In each job, :func:`assess` keeps a job whose ``metrics.json`` has status "ok" or
  "incomplete" (a finished simulation: a rerun would give the same result), the
  ``config_hash`` of the job's composed config now, and sound files beside it (the time
  series readable with one row per step, the summary, figures, video): the job returns
  without touching any file of its directory (Hydra writes no ``.hydra/`` either:
  ``hydra.output_subdir=null``). Every other job — failed or interrupted, half-written
  (no metrics.json, or not valid JSON), with a broken artefact, from another config (an
  edited ``conf/`` file), or never started — runs again, and its progress line says why
  (``· rerun: <why>``): :func:`prepare_rerun` removes its previous outputs
  (``metrics.json`` first, so the directory reads as unfinished from then on) and writes
  ``.hydra/`` as Hydra would; it never touches a directory outside the sweep directory.
- At the end the sweep callback summarises the whole directory as usual: every job, kept
  or rerun, is a row.

Start a resume only when no job of the sweep is still running (with the submitit
launchers, jobs outlive an interrupted launching process: ``squeue`` / ``ps``).
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path
from typing import Any

from compliant_docking import exit_codes
from compliant_docking.run.files import atomic_write_text
from compliant_docking.run.rundir import (
    HYDRA_DIR,
    MULTIRUN_FILE,
    find_job_dirs,
    read_metrics,
)

#: the job's return value when :func:`finished_record` kept it (seen by the sweep callback)
SKIPPED = "skipped: finished earlier with the same config"
#: the start of the job's return value when a resume reruns it: ``rerun: <why>``
RERUN = "rerun: "
#: statuses of a finished simulation: kept by a resume when the config is unchanged
KEEP_STATUSES = ("ok", "incomplete")
#: where ``resume=last`` looks for the newest sweep (relative to the working directory)
RUNS_MULTIRUN = "runs/multirun"
#: the Hydra overrides a resume adds after ``hydra.sweep.dir``
RESUME_OVERRIDES = ("hydra.callbacks.sweep.resume=true", "hydra.output_subdir=null")


class ResumeError(ValueError):
    """A resume that cannot go ahead; the message says why and what to type instead."""


# --------------------------------------------------------------------------- command line
def translate_argv(args: list[str]) -> list[str]:
    """The command-line arguments with ``resume=…`` replaced by Hydra overrides.

    ``resume=<dir>``, ``resume=last`` or ``resume=true`` (with ``hydra.sweep.dir=<dir>``);
    ``resume=false`` is dropped. Raises :class:`ResumeError` for a resume without ``-m``,
    a directory without a sweep, or conflicting directories.
    """
    picks = [a for a in args if a.startswith("resume=")]
    if not picks:
        return list(args)
    if len(picks) > 1:
        raise ResumeError("resume= is given more than once")
    value = picks[0].split("=", 1)[1].strip()
    rest = [a for a in args if a != picks[0]]
    if value.lower() in ("false", "no", "0", "null", ""):
        return rest
    if not any(a in ("-m", "--multirun") for a in rest):
        raise ResumeError(
            "a resume continues a sweep: run the sweep's own command (with -m) and add resume=<sweep dir>"
        )
    explicit = [a.split("=", 1)[1].strip("'\"") for a in rest if a.startswith("hydra.sweep.dir=")]
    if value.lower() in ("true", "yes", "1"):
        if not explicit:
            raise ResumeError("resume=true needs hydra.sweep.dir=<sweep dir> (or write resume=<sweep dir>)")
        sweep_dir = explicit[-1]
    elif value == "last":
        from compliant_docking.results.load import newest_sweep

        newest = newest_sweep(RUNS_MULTIRUN)
        if newest is None:
            raise ResumeError(f"resume=last: no sweep under {RUNS_MULTIRUN}")
        sweep_dir = str(newest)
    else:
        sweep_dir = value
    if explicit and Path(explicit[-1]).resolve() != Path(sweep_dir).resolve():
        raise ResumeError(
            f"resume={value} and hydra.sweep.dir={explicit[-1]} name different directories: give one of them"
        )
    if not (Path(sweep_dir) / MULTIRUN_FILE).is_file():
        raise ResumeError(f"no sweep to resume in {sweep_dir} (it has no multirun.yaml)")
    rest = [a for a in rest if not a.startswith("hydra.sweep.dir=")]
    return rest + [f"hydra.sweep.dir={_override_value(sweep_dir)}", *RESUME_OVERRIDES]


def _override_value(path: str) -> str:
    """``path`` as the value of a Hydra override (quoted when it needs to be)."""
    from compliant_docking.run.directories import override_value

    value = override_value(path)
    if value is None:
        raise ResumeError(
            f"cannot resume {path!r}: quotes, backslashes and $ in the path are "
            "not supported; rename or link the directory"
        )
    return value


def resuming(hydra_cfg) -> bool:
    """True in the jobs of a resumed sweep (``hydra.callbacks.sweep.resume``)."""
    from omegaconf import OmegaConf

    return bool(OmegaConf.select(hydra_cfg, "callbacks.sweep.resume", default=False))


# --------------------------------------------------------------------------- launching process
def check_sweep(config) -> None:
    """Check that the sweep of ``config`` (the launching process's, before anything is
    created: the guard calls it) can resume the one in its ``hydra.sweep.dir``.

    Raises :class:`ResumeError` when the directory has no ``multirun.yaml``, when the
    sweeper is not Hydra's basic one, when the task overrides or the sweeper's lists
    (``hydra.sweeper.params``, the presets') differ from the ones the sweep was started
    with, or when the Hydra overrides that name the jobs' directories differ.
    """
    from omegaconf import OmegaConf

    sweep_dir = Path(str(config.hydra.sweep.dir))
    saved = sweep_dir / MULTIRUN_FILE
    if not saved.is_file():
        raise ResumeError(f"no sweep to resume in {sweep_dir} (it has no multirun.yaml)")
    sweeper = str(OmegaConf.select(config, "hydra.sweeper._target_", default="") or "")
    if sweeper and not sweeper.endswith("BasicSweeper"):
        raise ResumeError(
            "resume= continues a sweep of Hydra's basic sweeper; a tuning study continues when its "
            "own command is run again (without resume=)"
        )
    old = OmegaConf.load(saved)
    moved = _job_naming(old) != _job_naming(config)
    if moved:
        raise ResumeError(
            f"the sweep in {sweep_dir} named its jobs' directories with\n    {_job_naming(old)}\n"
            f"  and this command would name them with\n    {_job_naming(config)}\n"
            "  A resume must keep the sweep's job directories (it reruns a job by emptying its "
            "directory): repeat the sweep's hydra.sweep.subdir and hydra.job.* overrides, or none."
        )
    old_task = _as_list(OmegaConf.select(old, "hydra.overrides.task"))
    new_task = _as_list(OmegaConf.select(config, "hydra.overrides.task"))
    if old_task != new_task:
        raise ResumeError(
            f"the sweep in {sweep_dir} was started with the overrides\n    {' '.join(old_task)}\n"
            f"  and this command has\n    {' '.join(new_task)}\n"
            "  A resume must repeat the sweep's overrides, in the same order (they number and "
            "name its jobs); for other values start a new sweep."
        )
    old_params = _as_plain(OmegaConf.select(old, "hydra.sweeper.params"))
    new_params = _as_plain(OmegaConf.select(config, "hydra.sweeper.params"))
    if old_params != new_params:
        raise ResumeError(
            f"the lists to sweep (hydra.sweeper.params, from a preset) changed since the sweep "
            f"in {sweep_dir} started: {old_params} → {new_params}; start a new sweep"
        )


#: Hydra overrides that decide where a job writes (its directory's name); a resume keeps them
JOB_NAMING = ("hydra.sweep.subdir", "hydra.job.")


def _job_naming(config) -> list[str]:
    """The Hydra overrides of ``config`` that name the jobs' directories, in order."""
    from omegaconf import OmegaConf

    given = _as_list(OmegaConf.select(config, "hydra.overrides.hydra"))
    return [o for o in given if o.lstrip("+~").startswith(JOB_NAMING)]


def foreign_job_dirs(sweep_dir: Path, subdirs: list[str]) -> str | None:
    """Why a resume whose jobs have the directories ``subdirs`` (relative to ``sweep_dir``)
    must not run: the sweep holds job directories that are none of them (the jobs would be
    named otherwise than when the sweep ran, and its summary would mix both); or None."""
    import os

    mine = {Path(os.path.normpath(sweep_dir / sub)).resolve() for sub in subdirs}
    foreign = [
        d for d in find_job_dirs(sweep_dir) if d.resolve() not in mine and d.resolve() != sweep_dir.resolve()
    ]
    if not foreign:
        return None
    shown = ", ".join(d.name for d in foreign[:3]) + (
        f", … ({len(foreign)} in all)" if len(foreign) > 3 else ""
    )
    return (
        f"resume={sweep_dir}: the sweep holds job directories that none of this command's jobs would "
        f"write ({shown}): a resume must name its jobs as the sweep did (the same overrides, the same "
        "hydra.sweep.subdir); for other jobs start a new sweep."
    )


def _as_list(node) -> list[str]:
    from omegaconf import OmegaConf

    if node is None:
        return []
    return [str(x) for x in OmegaConf.to_container(node, resolve=False) or []]


def _as_plain(node):
    from omegaconf import OmegaConf

    return OmegaConf.to_container(node, resolve=False) if OmegaConf.is_config(node) else node


def status_lines(sweep_dir: Path) -> list[str]:
    """What the resume will find: kept candidates, reruns, and a provenance note."""
    from compliant_docking.run import provenance

    kept, failed, unfinished, other_code = 0, 0, 0, 0
    here = {**provenance.git_state(), **provenance.versions()}
    for job_dir in find_job_dirs(sweep_dir):
        record, _ = read_metrics(job_dir)
        if record is None:
            unfinished += 1
        elif record.get("status") in KEEP_STATUSES:
            kept += 1
            if any(key in record and record[key] != value for key, value in here.items()):
                other_code += 1
        else:
            failed += 1
    lines = [
        f"resume: {kept} finished job{'s' * (kept != 1)} kept if their config is "
        f"unchanged; rerun: {failed} failed or interrupted, {unfinished} without a "
        "finished metrics.json, and the jobs that never started"
    ]
    if other_code:
        lines.append(
            f"  note: {other_code} of the finished jobs ran at another git commit, "
            "with a dirty tree, or with other library versions (the config hash "
            "covers the config, not the code; see the git_* and version_* columns)"
        )
    return lines


# --------------------------------------------------------------------------- in the job
def finished_record(cfg, out_dir: Path) -> dict | None:
    """The stored record of a job that a resume keeps, or None when the job must run
    (:func:`assess` says why)."""
    return assess(cfg, out_dir)[0]


def assess(cfg, out_dir: Path) -> tuple[dict | None, str]:
    """(the stored record, "") for a job that a resume keeps; (None, why) when it must run.

    Kept: ``metrics.json`` is a JSON object with status "ok" or "incomplete", its
    ``config_hash`` equals the hash of ``cfg`` (the job's composed config now), and every
    artefact beside it is sound (:func:`compliant_docking.run.rundir.artefact_problem`:
    the time series readable with one row per step, the summary, the figures, the video).
    """
    from compliant_docking.run.provenance import config_hash
    from compliant_docking.run.rundir import artefact_problem

    if not Path(out_dir).is_dir():
        return None, "it never started"
    record, problem = read_metrics(out_dir)
    if record is None:
        return None, str(problem)
    status = record.get("status")
    if status not in KEEP_STATUSES:
        return None, f"its last attempt {status}: {record.get('error')}"
    stored, now = record.get("config_hash"), config_hash(cfg)
    if stored is None:
        return None, "its metrics.json has no config_hash (written before config hashes)"
    if stored != now:
        return None, (
            f"its config changed since it ran (config hash {stored} → {now}: an edited conf/ "
            "file, or other defaults)"
        )
    problem = artefact_problem(out_dir, record)
    if problem:
        return None, problem
    return record, ""


def rerun_note(why: str) -> str:
    """The job's return value (and progress-line suffix) when a resume reruns it."""
    return f"{RERUN}{why}"


def prepare_rerun(cfg, out_dir: Path, sweep_dir: Path) -> None:
    """Clear the job directory ``out_dir`` of the sweep in ``sweep_dir`` for its rerun and
    write its ``.hydra/`` (when Hydra did not).

    Removes ``metrics.json`` first, then everything else of the previous attempt except
    ``.hydra/``: time series, summary, figures, video, temporary files. Raises
    RuntimeError, removing nothing, for a directory that is not strictly inside
    ``sweep_dir`` or that is a sweep directory itself.
    """
    from compliant_docking.run.rundir import METRICS_FILE

    out_dir = Path(out_dir)
    if (out_dir / MULTIRUN_FILE).exists():  # a sweep directory, not a job's: keep it
        raise RuntimeError(f"{out_dir} is a sweep directory, not a job directory")
    if Path(sweep_dir).resolve() not in out_dir.resolve().parents:
        raise RuntimeError(
            f"{out_dir} is not inside the sweep directory {sweep_dir}: nothing of it is removed"
        )
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / METRICS_FILE).unlink(missing_ok=True)
    for entry in out_dir.iterdir():
        if entry.name == HYDRA_DIR:
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
    write_hydra_dir(cfg, out_dir)


def write_hydra_dir(cfg, out_dir: Path) -> None:
    """``.hydra/{config,hydra,overrides}.yaml`` as Hydra writes them, when it did not
    (``hydra.output_subdir`` null in a resumed sweep). Each file atomically."""
    from hydra.core.hydra_config import HydraConfig
    from omegaconf import OmegaConf

    hydra_node: Any = HydraConfig.instance().cfg  # {"hydra": …} of this job
    if hydra_node is None or OmegaConf.select(hydra_node, "hydra.output_subdir") is not None:
        return  # not under Hydra, or Hydra wrote them itself
    folder = Path(out_dir) / HYDRA_DIR
    folder.mkdir(parents=True, exist_ok=True)
    for name, node in (
        ("config.yaml", cfg),
        ("hydra.yaml", hydra_node),
        ("overrides.yaml", hydra_node.hydra.overrides.task),
    ):
        atomic_write_text(folder / name, OmegaConf.to_yaml(node))


#: exit status of a refused resume: a refusal, like every refusal of the command line
EXIT_REFUSED = exit_codes.REFUSED


def fail(exc: ResumeError) -> int:
    """Print a refused resume; the exit status (2: refused, nothing ran or was written)."""
    print(f"resume: {exc}", file=sys.stderr)
    return EXIT_REFUSED
