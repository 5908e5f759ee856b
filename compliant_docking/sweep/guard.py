"""Refusing bad input before anything is written; a directory of its own for every command.

The Hydra callback :class:`Guard` (``hydra.callbacks.guard`` in conf/config.yaml, listed
before the sweep callback) runs in the launching process after Hydra composed the
config and before Hydra creates any directory:

- **one run** (``on_run_start``): the composed config is validated
  (:func:`job_problems`: unknown keys added with ``+``/``++``, NaN, inf, values outside
  their ranges, relations, files, memory; then what needs the robot's model or the
  planner, :mod:`compliant_docking.run.preflight`), ``viewer=true`` needs a display, and
  the run directory is claimed (below);
- **a sweep** (``on_multirun_start``): the launcher can run here (Slurm's ``sbatch`` for
  ``submitit_slurm``), every job's config is composed exactly as Hydra's basic sweeper
  will compose it and checked like a run's, so an unknown option (``robot=ur5``), a bad
  value in one job or ``viewer=true`` refuses the whole sweep before its directory exists;
  then the sweep directory is claimed. Hydra's sweeper composes every job a second time to check
  it (``validate_batch_is_legal``, after it created the sweep directory); the guard hands
  it the configs it composed (:class:`_Composed`), so the check costs nothing extra.

A refusal prints every problem (one paragraph each, naming the config key) and exits
with status 2 through :class:`Refused` (a ``SystemExit``: Hydra lets it through its
callback guard); nothing is created, and the command line neither summarises the sweep
nor suggests a resume.

**Claiming a directory** (:mod:`compliant_docking.sweep.directories`, after every check
passed): a default name that is taken becomes ``<name>_2``, ``<name>_3``… (two commands in
the same second); an explicit one (``hydra.run.dir=…``, ``hydra.sweep.dir=…``) must be new
or empty and outside any other sweep; a resumed sweep (``resume=…``) and a tuning study
continue their own directory. Every job of a sweep must get a directory of its own inside
the sweep's (``hydra.sweep.subdir``). A sweeper other than Hydra's basic one that offers
``problems(config)`` (the tuning sweeper: search space, objective, its stored study) is
asked before the claim too.

**Orphaned workers.** In a joblib sweep the guard also starts a watchdog in every worker
process (``on_job_start``): when the launching process is gone (killed with SIGKILL, its
workers re-parented), the worker exits within ``sweep.watchdog.PERIOD_S`` instead of
waiting for work that never comes (loky's idle timeout is 300 s).
"""

from __future__ import annotations

import os
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from compliant_docking import exit_codes
from compliant_docking.run import interrupt
from compliant_docking.sweep.directories import claim, job_dir_problems, job_subdir
from compliant_docking.sweep.watchdog import start_watchdog


class Refused(SystemExit):
    """A command refused before anything ran or was written (exit status 2)."""

    def __init__(self, report: str) -> None:
        super().__init__(exit_codes.REFUSED)
        self.report = report


def refuse(header: str, problems: list[str]) -> Refused:
    """Print ``header`` and the problems (one paragraph each) on stderr; the exception to raise."""
    report = "\n".join(
        [f"compliant-docking: {header}; nothing was run or written.", *(f"  {p}" for p in problems)]
    )
    print(report, file=sys.stderr, flush=True)
    return Refused(report)


class Guard(Callback):
    """The checks of a command before Hydra writes anything (see the module docstring)."""

    def __init__(self) -> None:
        self.launcher_pid: int | None = None  # set in the launching process, carried to workers by pickle
        self.watch_parent = False

    # -- one run
    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        from hydra.core.hydra_config import HydraConfig

        problems = job_problems(config)
        if not problems and config.get("viewer"):
            from compliant_docking.viz.viewer import refusal

            why = refusal(multirun=False)
            problems += [why + "."] if why else []
        if problems:
            raise refuse("the configuration is refused", problems)
        HydraConfig.instance().set_config(config)  # hydra.run.dir reads ${hydra:runtime.choices…}
        # from the claim on, a signal waits until the runner can record it (run/interrupt.py)
        interrupt.hold()
        problem = claim(config, "run")
        if problem:
            raise refuse("the run cannot start", [problem])

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
            _Composed.attach(config, jobs)
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
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
    from hydra.core.global_hydra import GlobalHydra
    from hydra.core.override_parser.overrides_parser import OverridesParser

    sweeper = config.hydra.sweeper
    if not str(sweeper.get("_target_", "")).endswith("BasicSweeper"):
        return None
    params = [f"{k}={v}" for k, v in (sweeper.get("params") or {}).items()]
    params += [str(o) for o in config.hydra.overrides.task]
    parser = OverridesParser.create(config_loader=GlobalHydra.instance().config_loader())
    batches = BasicSweeper.split_arguments(parser.parse_overrides(params), None)
    return [list(job) for batch in batches for job in batch]


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


def job_problems(config: DictConfig) -> list[str]:
    """Every problem of one job's composed config: the config layer's check, then what
    needs the robot's model or the planner (:mod:`compliant_docking.run.preflight`)."""
    from compliant_docking.config.validate import check
    from compliant_docking.run import preflight

    return check(config) or preflight.problems(config)


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


class _Composed:
    """Hands Hydra's sweeper the job configs the guard composed.

    Hydra's basic sweeper composes every job once in the launching process to check that
    it composes (``validate_batch_is_legal``), through its config loader's
    ``load_sweep_config``. The guard composed them already, before the sweep directory
    existed; this replaces ``load_sweep_config`` on that one loader instance by a lookup of
    those configs, each used once, and removes itself when all were used. An overrides
    list it does not hold is composed as usual. The pool launcher (sweep/pool.py) wraps
    whatever ``load_sweep_config`` it finds to keep the checked configs and send them to
    the jobs, so with it each job's config is composed once in all, by the guard.
    """

    def __init__(self, loader: Any, configs: dict[tuple[str, ...], DictConfig]) -> None:
        self.loader, self.configs = loader, dict(configs)

    def __getstate__(self) -> dict:  # pickled with the loader (if not all were used): a pass-through
        return {"loader": self.loader, "configs": {}}

    @classmethod
    def attach(cls, config: DictConfig, configs: dict[tuple[str, ...], DictConfig]) -> None:
        from hydra.core.global_hydra import GlobalHydra

        loader = GlobalHydra.instance().config_loader()
        loader.load_sweep_config = cls(loader, configs)  # type: ignore[method-assign]

    def __call__(self, master_config: DictConfig, sweep_overrides: list[str]) -> DictConfig:
        found = self.configs.pop(tuple(sweep_overrides), None)
        if not self.configs and vars(self.loader).get("load_sweep_config") is self:
            del self.loader.load_sweep_config  # all used: the loader's own method again
        if found is not None:
            return found
        return type(self.loader).load_sweep_config(self.loader, master_config, sweep_overrides)
