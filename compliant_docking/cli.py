"""The command line: ``compliant-docking [overrides]`` (the console script of
``[project.scripts]``, or ``python -m compliant_docking``) — one run, or a sweep with ``-m``.

Exit status (one table for every command: compliant_docking/exit_codes.py,
docs/exit_codes.md): 0 the run docked (or passed its tracking gate), 1 the run failed
(error or divergence), 2 the command was refused before anything ran (a bad key or value,
a directory that is not new, a resume or tuning study that cannot continue:
compliant_docking/run/guard.py, sweep/guard.py), 3 the run finished but its gate did not pass (not
docked), 130 / 143 / 129 stopped by Ctrl-C / SIGTERM / SIGHUP (a single run records status
"interrupted" with its time series so far: compliant_docking/run/interrupt.py).
A sweep (``-m``): 1 if any job failed (or its worker died), else 0 — jobs that did not
dock are results, counted in the summary (compliant_docking/sweep/outcome.py); with
``hydra.callbacks.sweep.strict=false`` (the tuning presets) 1 only when every job failed;
130 / 143 / 129 stopped by a signal (the workers are stopped, the summary of what
finished is written). No traceback is printed for an interruption or a worker process
that died; the summary says what happened.

``--help`` lists the config groups and their options (Hydra's own help would also list
the typed schemas, which are not choices).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
import sys
import traceback
from collections.abc import Iterator
from pathlib import Path

import hydra
from hydra.core.config_store import ConfigStore
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf

from compliant_docking import CONF_DIR, exit_codes
from compliant_docking.config import hydra_adapter, register_schemas
from compliant_docking.run import interrupt
from compliant_docking.run.directories import release_empty
from compliant_docking.run.guard import Refused, refuse
from compliant_docking.sweep import launchers, progress, resume
from compliant_docking.sweep.session import SweepSession

# Hydra composes each job's config in the launching process and again in the worker that
# runs it: memoize what the compositions share (config/hydra_adapter.py). At import, so
# the sweep's workers, which import this module to run the task, have it too.
hydra_adapter.install()


class CommandLine:
    """One invocation: the records of the jobs run in this process (single runs, and
    sweeps launched in-process) and the sweep session (jobs run by workers)."""

    def __init__(self) -> None:
        self.records: list[dict] = []

    def task(self, cfg: DictConfig) -> str | None:
        """Hydra's task function: one job into Hydra's output directory."""
        from compliant_docking.run.figures import wanted
        from compliant_docking.run.runner import execute

        hydra_cfg = HydraConfig.get()
        out_dir = Path(hydra_cfg.runtime.output_dir)
        sweep = hydra_cfg.mode == RunMode.MULTIRUN
        if not sweep:  # one run: its summary on the console, its figures
            self.records.append(execute(cfg, out_dir, figures=wanted(cfg, sweep=False), echo=True))
            return None
        note = None
        if resume.resuming(hydra_cfg):  # resume=<sweep dir>: keep a finished job untouched
            from compliant_docking.sweep.directories import sweep_dir_of

            kept, why = resume.assess(cfg, out_dir)
            if kept is not None:
                self.records.append(kept)
                return resume.SKIPPED
            note = resume.rerun_note(why)  # the progress line says why it runs again
            resume.prepare_rerun(cfg, out_dir, sweep_dir_of(hydra_cfg))
        # in a sweep, each job prints one progress line (SweepCallback), not its summary,
        # and draws no figures unless `figures=true` (report --runs draws them later)
        self.records.append(execute(cfg, out_dir, figures=wanted(cfg, sweep=True), echo=False))
        return note

    def run(self, argv: list[str]) -> int:
        """Run the command ``argv`` (without the program name); the exit status."""
        if any(arg in ("--help", "-h") for arg in argv):
            print_help(argv)
            return 0
        argv = progress.verbose_argv(argv)  # -v: the launchers' per-job launch lines too
        if any(arg.startswith("resume=") for arg in argv):
            try:
                argv = resume.translate_argv(argv)  # resume=<sweep dir> → Hydra overrides
            except resume.ResumeError as exc:
                return resume.fail(exc)
        register_schemas()
        launchers.register_schemas(ConfigStore.instance())  # hydra/launcher=submitit_*
        # Ctrl-C, SIGTERM, SIGHUP: a run records itself as interrupted (run/runner.py); a
        # sweep stops its workers and summarises what finished (run/interrupt.py)
        app = hydra.main(version_base="1.3", config_path=str(CONF_DIR), config_name="config")(self.task)
        saved, sys.argv[1:] = sys.argv[1:], argv  # Hydra parses sys.argv
        interrupt.forget()
        with (
            SweepSession.open() as session,
            _handled(interrupt.SIGNALS, interrupt.raise_stop),
            _hydra_config_kept(),
        ):
            try:
                with _errors_reported():
                    app()
            except Refused:  # nothing was created: nothing to summarise, no resume to suggest
                raise
            except (SystemExit, KeyboardInterrupt) as exc:
                session.finish_aborted()  # a sweep cut short (worker crash, a signal): summarise it
                if isinstance(exc, KeyboardInterrupt):  # no traceback: the record says what happened
                    return interrupt.exit_status(exc)
                raise
            finally:
                interrupt.release(stop=False)  # never leave the signals held (a refused run)
                sys.argv[1:] = saved
                release_empty()  # a directory claimed for a command that then wrote nothing
            if session.outcome is not None:  # the jobs ran in worker processes
                return session.outcome.exit_status
        from compliant_docking.run.runner import exit_status

        return max((exit_status(r) for r in self.records), default=0)


def main(argv: list[str] | None = None) -> int:
    """``compliant-docking`` and ``python -m compliant_docking``; the exit status.

    Hydra's shell completion (``-sc install=bash``) registers the completion for the
    program's file name, so it works with the console script, not with ``python -m``.
    """
    status = CommandLine().run(sys.argv[1:] if argv is None else list(argv))
    from compliant_docking.sweep.pool import abandoned_threads

    if abandoned_threads():  # an aborted sweep: loky's threads may never finish (sweep/pool.py)
        sys.stdout.flush()
        sys.stderr.flush()
        logging.shutdown()
        os._exit(status)
    return status


@contextlib.contextmanager
def _handled(signums: tuple[int, ...], handler) -> Iterator[None]:
    """``handler`` for each of ``signums`` during the command; the previous ones put back
    at the end (a command run inside a test process)."""
    previous = {s: signal.signal(s, handler) for s in signums}
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)


@contextlib.contextmanager
def _errors_reported() -> Iterator[None]:
    """Errors Hydra's error reporter would print its own way, reported ours: a config that
    does not compose (an unknown key, a wrong type: one paragraph naming the key and the
    nearest valid keys, never a schema class, and no hint to append the key with ``+``),
    a sweep whose worker process died (joblib's ``TerminatedWorkerError``: one line
    instead of a traceback; the aborted sweep's summary then says which jobs were lost),
    and an error raised after a stop signal (the signal's exception cut some library's
    code short, e.g. OmegaConf's between the jobs of an in-process sweep): the stop,
    without a traceback.

    Hydra hands an error to the caller of ``hydra.main`` instead of reporting it when
    ``HYDRA_FULL_ERROR=1`` (its documented switch): set for the command only. Any other
    error is reported as Hydra reports it — a Hydra error in one line (and its OmegaConf
    cause), else the traceback — and exits with status 1; with ``HYDRA_FULL_ERROR=1`` set
    by the user it propagates, as with Hydra.
    """
    from hydra.errors import CompactHydraException, ConfigCompositionException
    from omegaconf.errors import OmegaConfBaseException

    from compliant_docking.config.validate import composition_problem

    full_error = os.environ.get("HYDRA_FULL_ERROR")
    os.environ["HYDRA_FULL_ERROR"] = "1"
    try:
        yield
    except ConfigCompositionException as exc:
        raise refuse("the configuration is refused", [composition_problem(exc)]) from None
    except Exception as exc:
        stopped_by = interrupt.received()
        if stopped_by is not None:  # an error of code the signal cut short: the stop it is
            raise interrupt.Stopped(stopped_by) from None
        if type(exc).__name__ in ("TerminatedWorkerError", "BrokenProcessPool"):
            first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            codes = re.search(r"exit codes of the workers are \{([^}]*)\}", str(exc))
            detail = f" (exit codes {codes.group(1)})" if codes else ""
            print(f"sweep: a worker process died{detail}: {first}", file=sys.stderr, flush=True)
            raise SystemExit(exit_codes.FAILED) from None
        if full_error == "1":
            raise
        if isinstance(exc, CompactHydraException):
            print(exc, file=sys.stderr)
            if isinstance(exc.__cause__, OmegaConfBaseException):
                print(exc.__cause__, file=sys.stderr)
        else:
            traceback.print_exc()
        raise SystemExit(exit_codes.FAILED) from None
    finally:
        if full_error is None:
            os.environ.pop("HYDRA_FULL_ERROR", None)
        else:
            os.environ["HYDRA_FULL_ERROR"] = full_error


@contextlib.contextmanager
def _hydra_config_kept() -> Iterator[None]:
    """Hydra's process-wide ``HydraConfig`` as it was before the command: Hydra leaves the
    last job's config set in it after the command returns, and a run started later in the
    same process through the Python API (a test, a notebook) would record this command's
    overrides and choices as its own (run.runner.job_identity)."""
    hydra_config = HydraConfig.instance()
    saved = hydra_config.cfg
    try:
        yield
    finally:
        hydra_config.cfg = saved


# --------------------------------------------------------------------------- --help
GROUPS = {
    "robot": "the arm",
    "tool": "the plug on the flange",
    "target": "the socket; none: free space",
    "physics": "MuJoCo options and gravity",
    "controller": "the control law",
    "trajectory": "the planner",
    "task": "start pose, run length, success criteria",
    "render": "video of the run: render=video writes docking.mp4",
    "sensor": "what the controller's F/T sensor and encoders read (ideal: exact)",
    "model_error": "the controller's model against the plant (none: exact)",
    "dynamics": "the plug-socket contact drawn per seed (nominal: as configured)",
    "experiment": "presets, added with +experiment=NAME",
    "logger": "log every job to MLflow, added with +logger=mlflow",
    "tracking": "deprecated: +tracking=mlflow is the old spelling of +logger=mlflow",
    "robot_controller": "per-robot gains, applied automatically as ${robot}_${controller}",
}
#: groups that are not for composing by hand
HIDDEN = ("hydra", "schema")

USAGE = """\
compliant-docking: simulate a robot arm docking a plug into a socket under compliant control.

Usage (`compliant-docking` is the same command as `python -m compliant_docking`):
  compliant-docking [group=option ...] [key=value ...]      one run into runs/
  compliant-docking -m group=a,b [key=v1,v2 ...]            a sweep into runs/multirun/

Examples:
  compliant-docking controller=hqp robot=fr3
  compliant-docking physics=earth controller.k=100
  compliant-docking -m controller=impedance,hqp,se3_lie robot=iiwa14,fr3
  compliant-docking -m +experiment=controller_comparison    (presets: conf/experiment)
  compliant-docking -m <same overrides> resume=last          (finish an interrupted sweep)
  compliant-docking -m <overrides> hydra/launcher=submitit_slurm hydra.launcher.partition=P
  compliant-docking -m +experiment=tune                      (tune gains with Optuna: docs/tuning.md)
  compliant-docking +logger=mlflow ...                       (log to MLflow: docs/logger.md)
  python -m compliant_docking.report runs/multirun/<date>/<time>      (tables and figures again)

Exit status (the same for every command; docs/exit_codes.md):
  0    the run docked (tracking gate: PASS); a sweep whose jobs all ran
  1    failed: the run's error or divergence; a sweep with a failed job
  2    refused before anything ran or was written (a bad key, value, file or directory)
  3    not docked: the run finished but its gate did not pass (tracking gate: FAIL)
  130 / 143 / 129  interrupted by Ctrl-C / SIGTERM / SIGHUP (what finished is recorded)
-v (--verbose) with -m: also Hydra's launch line of every job before the first result.
Hydra's own options: --hydra-help, --cfg job (print the composed config), --info,
-sc install=bash (shell completion: eval "$(compliant-docking -sc install=bash)").
"""


def print_help(overrides: list[str]) -> None:
    """The usage, the groups with their options (default first), the composed config."""
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        loader = GlobalHydra.instance().config_loader()
        print(USAGE)
        print("Configuration groups (group=option; default first):")
        cfg = compose(
            config_name="config", overrides=[o for o in overrides if "=" in o and not o.startswith("-")]
        )
        groups = [g for g in loader.list_groups("") if not g.startswith(HIDDEN)]
        for group in sorted(groups, key=lambda g: (list(GROUPS).index(g) if g in GROUPS else 99, g)):
            options = sorted(loader.get_group_options(group))
            node = cfg.get(group)
            default = node.get("name") if hasattr(node, "get") else None
            ordered = [default] + [o for o in options if o != default] if default in options else options
            what = f"  — {GROUPS[group]}" if group in GROUPS else ""
            print(f"  {group:<17} {', '.join(ordered)}{what}")
        print("\nThe composed configuration (override any key as key=value):\n")
        print(OmegaConf.to_yaml(cfg))
