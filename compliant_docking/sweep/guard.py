"""Refusing bad input before anything is written; a directory of its own for every command.

The Hydra callback :class:`Guard` (``hydra.callbacks.guard`` in conf/config.yaml, listed
before the sweep callback) runs in the launching process after Hydra composed the
config and before Hydra creates any directory:

- **one run** (``on_run_start``): the composed config is validated
  (:func:`compliant_docking.config.validate.validate`: unknown keys added with ``+``/``++``,
  NaN, inf, values outside their ranges, relations, memory), ``viewer=true`` needs a
  display, and the run directory is claimed (below);
- **a sweep** (``on_multirun_start``): every job's config is composed exactly as Hydra's
  basic sweeper will compose it, so an unknown option (``robot=ur5``), a bad value in one
  job or ``viewer=true`` refuses the whole sweep before its directory exists; then the
  sweep directory is claimed. Hydra's sweeper composes every job a second time to check
  it (``validate_batch_is_legal``, after it created the sweep directory); the guard hands
  it the configs it composed (:class:`_Composed`), so the check costs nothing extra.

A refusal prints every problem (one paragraph each, naming the config key) and exits
with status 1 through :class:`Refused` (a ``SystemExit``: Hydra lets it through its
callback guard); nothing is created, and the command line neither summarises the sweep
nor suggests a resume.

**Claiming a directory.** The default names (``runs/<date>/<time>_<robot>_…``,
``runs/multirun/<date>/<time>``) have a resolution of one second: two commands started in
the same second would share a directory. The guard creates the directory itself
(``os.mkdir`` is atomic: of two processes exactly one creates a name) and, when the name
is taken, takes the next free ``<name>_2``, ``<name>_3``… A directory given explicitly
(``hydra.run.dir=…``, ``hydra.sweep.dir=…``, ``resume=…``) is used as given, after
checking that it can be written.

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
from omegaconf import DictConfig, OmegaConf, read_write

from compliant_docking.sweep.watchdog import start_watchdog

#: largest suffix tried for a taken directory name (``<name>_2`` … ``<name>_999``)
MAX_SUFFIX = 999


class Refused(SystemExit):
    """A command refused before anything ran or was written (exit status 1)."""

    def __init__(self, report: str) -> None:
        super().__init__(1)
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
        problem = claim(config, "run")
        if problem:
            raise refuse("the run cannot start", [problem])

    # -- a sweep
    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        from compliant_docking.sweep.launchers import is_submitit, launcher_problem
        from compliant_docking.sweep.pool import start_early
        from compliant_docking.sweep.workers import stop_early

        launcher = launcher_problem(config.hydra.launcher)
        workers_started = not launcher and start_early(
            config.hydra.launcher
        )  # they import while the jobs are checked
        problems: list[str] = [launcher] if launcher else []
        jobs = check_jobs(config, problems)
        composed_for = str(config.hydra.sweep.dir)
        if not problems:
            problem = claim(config, "sweep")
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


def job_problems(config: DictConfig) -> list[str]:
    """Every problem of one job's composed config: the config layer's check, then what
    needs the robot's model or the planner (:mod:`compliant_docking.run.preflight`)."""
    from compliant_docking.config.validate import check
    from compliant_docking.run import preflight

    return check(config) or preflight.problems(config)


def check_jobs(config: DictConfig, problems: list[str]) -> dict[tuple[str, ...], DictConfig]:
    """Compose and validate every job of the sweep; append the problems (each distinct
    problem once, with the jobs that have it); the composed configs by overrides."""
    from hydra.core.global_hydra import GlobalHydra

    from compliant_docking.config.validate import composition_problem

    try:
        jobs = job_overrides(config)
    except Exception as exc:  # a malformed sweep list
        problems.append(composition_problem(exc))
        return {}
    if jobs is None:  # another sweeper: check the primary config only
        problems += job_problems(config)
        return {}
    loader = GlobalHydra.instance().config_loader()
    found: dict[str, list[int]] = defaultdict(list)
    composed: dict[tuple[str, ...], DictConfig] = {}
    for num, overrides in enumerate(jobs):
        try:
            job = loader.load_sweep_config(config, list(overrides))
        except Exception as exc:  # an unknown option or key, a wrong type
            found[composition_problem(exc)].append(num)
            continue
        composed[tuple(overrides)] = job
        problems_of_job = job_problems(job)
        if job.get("viewer"):
            from compliant_docking.viz.viewer import refusal

            problems_of_job.append(f"{refusal(multirun=True)}.")
        for problem in problems_of_job:
            found[problem].append(num)
    for problem, nums in found.items():
        example = f"job {nums[0]}: {' '.join(jobs[nums[0]]) or 'no overrides'}"
        if len(nums) > 1:
            example = f"jobs {', '.join(map(str, nums[:10]))}{', …' if len(nums) > 10 else ''}; {example}"
        problems.append(f"{problem} [{example}]")
    return composed


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


# --------------------------------------------------------------------------- directories
def claim(config: DictConfig, kind: str, *, explicit: bool | None = None) -> str | None:
    """Make sure the run or sweep (``kind``) directory of ``config`` is this command's and
    writable: a default name that is taken becomes ``<name>_2``, ``<name>_3``… (updated in
    ``config``); an explicit one is checked for writing only. Why not, or None.

    ``explicit``: the directory was named by the user (default: ``hydra.<kind>.dir`` is
    among the command's Hydra overrides).
    """
    key = f"hydra.{kind}.dir"
    path = Path(str(OmegaConf.select(config, key)))
    if explicit is None:
        explicit = any(str(o).split("=", 1)[0].lstrip("+") == key for o in config.hydra.overrides.hydra)
    if explicit:
        return _writable(path, key)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        for n in range(1, MAX_SUFFIX + 1):
            candidate = path if n == 1 else path.with_name(f"{path.name}_{n}")
            try:
                candidate.mkdir()
                break
            except FileExistsError:
                continue
        else:
            return f"{key}: {path} and its {MAX_SUFFIX - 1} numbered variants are all taken; set {key}=<dir>."
    except OSError as exc:
        return (
            f"{key}: cannot create {path}: {exc.strerror or exc}; choose another directory with {key}=<dir>."
        )
    CLAIMED.append(candidate)
    if candidate != path:
        with read_write(config.hydra):
            OmegaConf.update(config, key, str(candidate))
            if kind == "sweep":  # the jobs compose their config again from the overrides
                config.hydra.overrides.hydra.append(f"{key}={_quoted(str(candidate))}")
    return None


#: the directories :func:`claim` created in this process (see :func:`release_empty`)
CLAIMED: list[Path] = []


def release_empty() -> None:
    """Remove the directories this process claimed that stayed empty (a sweep sweeper that
    refused its set-up after the claim, e.g. the tuning sweeper): a refused command leaves
    nothing behind. A directory with anything in it stays."""
    while CLAIMED:
        path = CLAIMED.pop()
        try:
            path.rmdir()  # only an empty directory
        except OSError:
            pass


def _writable(path: Path, key: str) -> str | None:
    """Why ``path`` (existing, or to be created) cannot be written, or None. Tried for real
    (a probe directory created and removed in ``path`` or its nearest existing parent):
    permission bits do not tell for root or a read-only file system."""
    import tempfile

    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"{key}={path}: {existing} is not a directory; choose another directory with {key}=<dir>."
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".write-probe-", dir=existing))
    except OSError as exc:
        return (
            f"{key}={path}: cannot write in {existing} ({exc.strerror or exc}); "
            f"choose another directory with {key}=<dir>."
        )
    return None


def _quoted(path: str) -> str:
    """``path`` as the value of a Hydra override."""
    from compliant_docking.sweep.resume import ResumeError, _override_value

    try:
        return _override_value(path)
    except ResumeError:
        return path
