"""A sweep refused before anything is written: every job checked as a run is checked.

The Hydra callback :class:`SweepGuard` (``hydra.callbacks.sweep_guard`` in
conf/config.yaml, after the run guard and before the sweep callback) runs in the
launching process after Hydra composed the config and before Hydra creates any
directory (``on_multirun_start``): the launcher can run here (Slurm's ``sbatch`` for
``submitit_slurm``), every job's config is composed exactly as Hydra's basic sweeper
will compose it and checked like a run's (:func:`compliant_docking.run.guard.job_problems`),
so an unknown option (``robot=ur5``), a bad value in one job or ``viewer=true`` refuses
the whole sweep before its directory exists; then the sweep directory is claimed
(:mod:`compliant_docking.run.directories`). Hydra's sweeper composes every job a second
time to check it (``validate_batch_is_legal``, after it created the sweep directory); the
guard offers it the configs it composed (``config.hydra_adapter.share_compositions``),
so the check costs nothing extra. One run is checked by the run guard alone
(compliant_docking/run/guard.py).

A refusal prints every problem and exits with status 2 (``run.guard.refuse``); nothing
is created. A resumed sweep (``resume=…``) and a tuning study continue their own
directory. Every job of a sweep must get a directory of its own inside the sweep's
(``hydra.sweep.subdir``, :mod:`compliant_docking.sweep.directories`). A sweeper other
than Hydra's basic one that offers ``problems(config)`` (the tuning sweeper: search
space, objective, its stored study) is asked before the claim too.

**Orphaned workers.** In a joblib sweep the guard also starts a watchdog in every worker
process (``on_job_start``): when the launching process is gone (killed with SIGKILL, its
workers re-parented), the worker exits within ``sweep.watchdog.PERIOD_S`` instead of
waiting for work that never comes (loky's idle timeout is 300 s).
"""

from __future__ import annotations

import os
from collections import defaultdict
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from compliant_docking.config.hydra_adapter import share_compositions, split_sweep
from compliant_docking.run.directories import claim
from compliant_docking.run.guard import job_problems, refuse
from compliant_docking.sweep.directories import job_dir_problems, job_subdir
from compliant_docking.sweep.watchdog import start_watchdog


class SweepGuard(Callback):
    """The checks of a sweep before Hydra writes anything (see the module docstring)."""

    def __init__(self) -> None:
        self.launcher_pid: int | None = None  # set in the launching process, carried to workers by pickle
        self.watch_parent = False

    # -- a sweep
    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        from compliant_docking.sweep.launchers import is_submitit, launcher_problem
        from compliant_docking.sweep.pool import start_early
        from compliant_docking.sweep.workers import stop_early

        resumed = bool(OmegaConf.select(config, "hydra.callbacks.sweep.resume", default=False))
        if resumed:  # the command must be the sweep's (sweep/resume.py)
            from compliant_docking.sweep import resume

            try:
                resume.check_sweep(config)
            except resume.ResumeError as exc:
                raise SystemExit(resume.fail(exc)) from None
        launcher = launcher_problem(config.hydra.launcher)
        # the pool's workers import the libraries while the jobs are checked
        workers_started = not launcher and start_early(config.hydra.launcher)
        problems: list[str] = [launcher] if launcher else []
        jobs, subdirs = check_jobs(config, problems)
        sweeper = checking_sweeper(config)  # e.g. the tuning sweeper: its set-up, its study
        if sweeper is not None and not problems:
            problems += sweeper.problems(config)
        sweep_dir = Path(str(config.hydra.sweep.dir))
        if resumed and subdirs and not problems and sweep_dir.is_dir():
            from compliant_docking.sweep.resume import foreign_job_dirs

            foreign = foreign_job_dirs(sweep_dir, subdirs)
            problems += [foreign] if foreign else []
        composed_for = str(config.hydra.sweep.dir)
        if not problems:  # a resumed sweep or a tuning study continues its directory
            problem = claim(config, "sweep", continued=resumed or sweeper is not None)
            if problem:
                problems.append(problem)
        if problems:
            if workers_started:
                stop_early()
            raise refuse("the sweep is refused", problems)
        if jobs and str(config.hydra.sweep.dir) == composed_for:  # else compose again: new directory
            from hydra.core.global_hydra import GlobalHydra

            share_compositions(GlobalHydra.instance().config_loader()).offer(jobs)
        self.launcher_pid = os.getpid()
        self.watch_parent = not is_submitit(config.hydra.launcher)  # submitit jobs outlive the launcher

    # -- a worker process, before each job
    def on_job_start(self, config: DictConfig, **kwargs: Any) -> None:
        if self.watch_parent and self.launcher_pid not in (None, os.getpid()):
            start_watchdog()


# --------------------------------------------------------------------------- the jobs of a sweep
def job_overrides(config: DictConfig) -> list[list[str]] | None:
    """The overrides of every job of the sweep, as Hydra's basic sweeper splits them
    (None for another sweeper)."""
    from hydra.core.global_hydra import GlobalHydra
    from hydra.core.override_parser.overrides_parser import OverridesParser

    sweeper = config.hydra.sweeper
    if not str(sweeper.get("_target_", "")).endswith("BasicSweeper"):
        return None
    params = [f"{k}={v}" for k, v in (sweeper.get("params") or {}).items()]
    params += [str(o) for o in config.hydra.overrides.task]
    parser = OverridesParser.create(config_loader=GlobalHydra.instance().config_loader())
    return split_sweep(parser.parse_overrides(params))


def checking_sweeper(config: DictConfig) -> Any:
    """The sweep's sweeper when it is not Hydra's basic one and checks its own set-up before
    anything is created (a ``problems(config)`` method, like the tuning sweeper's), else None.
    Such a sweeper keeps its study in its directory and continues it when run again."""
    from hydra.utils import get_class, instantiate

    target = str(config.hydra.sweeper.get("_target_", ""))
    if not target or target.endswith("BasicSweeper"):
        return None
    try:
        if not callable(getattr(get_class(target), "problems", None)):
            return None
    except Exception:  # not importable: Hydra says so when it instantiates it
        return None
    return instantiate(config.hydra.sweeper)


def check_jobs(
    config: DictConfig, problems: list[str]
) -> tuple[dict[tuple[str, ...], DictConfig], list[str]]:
    """Compose and validate every job of the sweep; append the problems (each distinct
    problem once, with the jobs that have it); the composed configs by overrides, and each
    job's directory relative to the sweep's (in job order; [] for another sweeper)."""
    from hydra.core.global_hydra import GlobalHydra

    from compliant_docking.config.validate import composition_problem

    try:
        jobs = job_overrides(config)
    except Exception as exc:  # a malformed sweep list
        problems.append(composition_problem(exc))
        return {}, []
    if jobs is None:  # another sweeper: check the primary config only
        problems += job_problems(config)
        return {}, []
    loader = GlobalHydra.instance().config_loader()
    found: dict[str, list[int]] = defaultdict(list)
    composed: dict[tuple[str, ...], DictConfig] = {}
    subdirs: dict[int, str] = {}  # each job's directory in the sweep
    for num, overrides in enumerate(jobs):
        try:
            job = loader.load_sweep_config(config, list(overrides))
        except Exception as exc:  # an unknown option or key, a wrong type
            found[composition_problem(exc)].append(num)
            continue
        composed[tuple(overrides)] = job
        subdirs[num] = job_subdir(job, num)
        problems_of_job = job_problems(job)
        if job.get("viewer"):
            from compliant_docking.viz.viewer import refusal

            problems_of_job.append(f"{refusal(multirun=True)}.")
        for problem in problems_of_job:
            found[problem].append(num)
    if not found:  # every job composes: each must get a directory of its own inside the sweep
        problems += job_dir_problems(subdirs)
    for problem, nums in found.items():
        example = f"job {nums[0]}: {' '.join(jobs[nums[0]]) or 'no overrides'}"
        if len(nums) > 1:
            example = f"jobs {', '.join(map(str, nums[:10]))}{', …' if len(nums) > 10 else ''}; {example}"
        problems.append(f"{problem} [{example}]")
    return composed, [subdirs[num] for num in sorted(subdirs)]
