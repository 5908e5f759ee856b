"""Session set-up shared by every test."""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import pytest

#: compile the laws' numba kernels (control/jit.py) by running a few steps of each law named
#: on the command line, one after the other
_WARM = (
    "import sys\n"
    "from compliant_docking.config import load_config\n"
    "from compliant_docking.sim.simulate import prepare\n"
    "for law in sys.argv[1:]:\n"
    "    prepare(load_config(f'controller={law}', 'task.duration=0.005', 'task.progress=false')).run()\n"
)
#: two processes, for two cores: hqp's kernels take longest to compile
_WARM_LAWS = (("hqp",), ("se3_lie", "impedance"))
#: the lock file the compiling processes hold until the last one is done (set for xdist's workers)
WARM_LOCK = "COMPLIANT_DOCKING_TESTS_KERNEL_LOCK"
#: test files that build no controller: they run first, while the kernels compile (a file
#: here that did build one would only compile a kernel a second time, not fail). Each was
#: run alone with an empty NUMBA_CACHE_DIR, which stayed empty.
_NO_KERNEL = (
    "tests/config/test_defaults.py",
    "tests/config/test_hydra_adapter.py",
    "tests/config/test_presets.py",
    "tests/config/test_validate.py",
    "tests/env/test_config.py",
    "tests/evaluation/test_contact.py",
    "tests/evaluation/test_docking_time.py",
    "tests/evaluation/test_filtered_peak.py",
    "tests/evaluation/test_map_boundaries.py",
    "tests/evaluation/test_peg_in_hole.py",
    "tests/planning/test_quintic.py",
    "tests/planning/test_tracking.py",
    "tests/planning/test_twophase.py",
    "tests/results/test_compare.py",
    "tests/results/test_convergence.py",
    "tests/results/test_figure_bounds.py",
    "tests/results/test_figures.py",
    "tests/results/test_findings.py",
    "tests/results/test_jamming_map.py",
    "tests/results/test_load_config.py",
    "tests/results/test_peg_in_hole.py",
    "tests/results/test_stats.py",
    "tests/run/test_figure_content.py",
    "tests/sim/test_compliance_rig.py",
    "tests/sim/test_conform.py",
    "tests/sim/test_geometry.py",
    "tests/sim/test_models.py",
    "tests/sim/test_telemetry.py",
    "tests/sweep/test_progress.py",
    "tests/sweep/test_watchdog.py",
    "tests/sweep/test_workers.py",
    "tests/test_cli.py",
    "tests/test_layout.py",
    "tests/test_references.py",
    "tests/test_readme.py",
    "tests/tune/test_space.py",
)


def pytest_configure(config) -> None:
    """Compile the compiled laws' kernels once, beside pytest-xdist's workers.

    numba caches a kernel's machine code on first use (``__pycache__``), but on a fresh
    clone every process that reaches a law before the cache exists compiles it itself:
    each xdist worker, and each command-line run and sweep worker the tests start (20-75 s
    for hqp on a shared 2-core machine). Here the kernels compile in two processes that
    start before the workers; the workers collect meanwhile and run the tests that build no
    controller (:data:`_NO_KERNEL`, ordered first), and every other test waits until the
    compiling processes have exited (:func:`pytest_runtest_setup`), then loads the cache. Only
    for a distributed run (``-n``): a single targeted test pays nothing when the cache is warm.
    """
    if hasattr(config, "workerinput") or config.getoption("collectonly", False):
        return  # an xdist worker (the controller did it), or nothing will run
    if not config.getoption("numprocesses", None):
        return
    handle, lock = tempfile.mkstemp(prefix="compliant-docking-kernels-", suffix=".lock")
    fcntl.flock(handle, fcntl.LOCK_EX)  # held by the children's copies until the last exits
    procs = []
    for laws in _WARM_LAWS:
        log = tempfile.TemporaryFile()
        procs.append(
            (
                subprocess.Popen(
                    [sys.executable, "-c", _WARM, *laws],
                    stdout=subprocess.DEVNULL,
                    stderr=log,
                    pass_fds=(handle,),
                ),
                log,
            )
        )
    os.close(handle)
    os.environ[WARM_LOCK] = lock  # the workers start after this hook and inherit it
    config.stash[_warm_key] = (lock, procs)


_warm_key = pytest.StashKey[tuple]()


def pytest_unconfigure(config) -> None:
    """Reap the compiling processes; say why one failed (the tests of that law report it)."""
    if _warm_key not in config.stash:
        return
    lock, procs = config.stash[_warm_key]
    for proc, log in procs:
        if proc.wait() != 0:
            log.seek(0)
            sys.stderr.write(
                f"compiling the kernels before the tests failed:\n{log.read().decode()[-2000:]}\n"
            )
        log.close()
    os.environ.pop(WARM_LOCK, None)
    Path(lock).unlink(missing_ok=True)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item) -> None:
    """A test that may build a controller waits for the compiling processes before any of
    its fixtures (a module's sweep) is set up; once they are done the lock is free at once."""
    lock = os.environ.get(WARM_LOCK)
    if lock and not item.nodeid.startswith(_NO_KERNEL):
        try:
            handle = os.open(lock, os.O_RDONLY)
        except FileNotFoundError:  # the session is over
            return
        try:
            fcntl.flock(handle, fcntl.LOCK_SH)
        finally:
            os.close(handle)


#: fixtures that build something expensive once per session (a CAD conversion, a sweep) or
#: per module (a sweep, a run): every test using one joins one xdist group, so that under
#: ``--dist loadgroup`` (pyproject's addopts, with ``-n``) one worker builds it once, instead
#: of each worker that happens to get one of its tests (xdist keeps a session fixture per worker)
SESSION_FIXTURES = ("converted", "failing_sweeps")
MODULE_FIXTURES = (
    "killed",
    "finished_sweep",
    "finished_job",
    "two_runs",
    "real_run",
    "short_run",
    "completion_script",
)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items) -> None:
    """Each test that uses a shared fixture joins that fixture's xdist group (per module for
    a module-scoped one). First among the hooks: an xdist worker's own hook reads the groups
    (it suffixes each grouped test's id with its group) and runs before this one otherwise,
    as conftest files register before the worker's plugin, so no test was ever grouped."""
    items.sort(key=lambda item: not item.nodeid.startswith(_NO_KERNEL))  # stable: run while compiling
    for item in items:
        used = getattr(item, "fixturenames", ())
        group = next((name for name in SESSION_FIXTURES if name in used), None)
        if group is None:
            module = next((name for name in MODULE_FIXTURES if name in used), None)
            group = None if module is None else f"{item.module.__name__}:{module}"
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))


@pytest.fixture(autouse=True)
def _figures_closed():
    """Every figure a test opened through pyplot is closed after it: the figure functions
    that return a figure leave it to the caller (a notebook), and tests that inspect one
    would otherwise pile them up in their worker (matplotlib warns past 20)."""
    yield
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close("all")


_STOP_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")


@pytest.fixture(autouse=True)
def _signal_handlers_left_as_found(request):
    """Every test leaves the stop signals' handlers as it found them: one that does not is
    named in a warning and its handlers are put back, so a later test in the same worker
    process (the interruption tests) is not judged under a handler it never set."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = {name: signal.getsignal(getattr(signal, name)) for name in _STOP_SIGNALS}
    yield
    for name, handler in before.items():
        if signal.getsignal(getattr(signal, name)) is not handler:
            warnings.warn(f"{request.node.nodeid} left the {name} handler changed", stacklevel=1)
            signal.signal(getattr(signal, name), handler)
