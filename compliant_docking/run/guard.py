"""Refusing bad input before anything is written, and a directory of its own for one run.

The Hydra callback :class:`RunGuard` (``hydra.callbacks.guard`` in conf/config.yaml,
listed first) runs in the command's process after Hydra composed the config and before
Hydra creates any directory (``on_run_start``): the composed config is validated
(:func:`job_problems`: unknown keys added with ``+``/``++``, NaN, inf, values outside
their ranges, relations, files, memory; then what needs the robot's model or the
planner, :mod:`compliant_docking.run.preflight`), ``viewer=true`` needs a display, and
the run directory is claimed (:mod:`compliant_docking.run.directories`). A sweep's jobs
are checked the same way, by the sweep's guard (compliant_docking/sweep/guard.py).

A refusal prints every problem (one paragraph each, naming the config key) and exits
with status 2 through :class:`Refused` (a ``SystemExit``: Hydra lets it through its
callback guard); nothing is created, and the command line neither summarises a sweep
nor suggests a resume.
"""

from __future__ import annotations

import sys
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig

from compliant_docking import exit_codes
from compliant_docking.run import interrupt
from compliant_docking.run.directories import claim


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


def job_problems(config: DictConfig) -> list[str]:
    """Every problem of one job's composed config: the config layer's check, then what
    needs the robot's model or the planner (:mod:`compliant_docking.run.preflight`)."""
    from compliant_docking.config.validate import check
    from compliant_docking.run import preflight

    return check(config) or preflight.problems(config)


class RunGuard(Callback):
    """The checks of one run before Hydra writes anything (see the module docstring)."""

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
