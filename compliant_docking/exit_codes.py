"""The exit status of every command of the package, one table for all of them.

======  ===========  ==============================================================
status  name         meaning
======  ===========  ==============================================================
0       OK           the command did what was asked: the run docked (or passed its
                     tracking gate, or had no gate); a sweep whose jobs all ran
                     (jobs that did not dock are results, counted in its summary)
1       FAILED       something ran and failed: a run's error or divergence, a sweep
                     with a failed job (or a worker process that died), a tuning
                     study in which every job failed, a conversion that failed its
                     own checks
2       REFUSED      refused before anything ran or was written: a bad option, key,
                     value, file or directory (also a command-line option the
                     argument parser rejects, which exits 2 too)
3       NOT_DOCKED   a single run finished but its gate did not pass (not seated,
                     force over budget, tracking gate FAIL or INCOMPLETE)
128+N   INTERRUPTED  stopped by signal N: 130 Ctrl-C (SIGINT), 143 SIGTERM, 129
                     SIGHUP; what finished is recorded
======  ===========  ==============================================================

The commands: ``compliant-docking`` (one run or a sweep with ``-m``),
``python -m compliant_docking.report``, ``python -m compliant_docking.results.findings``,
``python -m compliant_docking.results.convergence``, ``python -m
compliant_docking.interface``. docs/exit_codes.md is this table for users.
"""

from __future__ import annotations

import signal

OK = 0
FAILED = 1
REFUSED = 2
NOT_DOCKED = 3


def interrupted(signum: int = signal.SIGINT) -> int:
    """``128 + signum``: 130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP (the shell's rule)."""
    return 128 + int(signum)
