"""Session set-up shared by every test."""

from __future__ import annotations

import subprocess
import sys
import warnings

import pytest

#: compile one law's numba kernel (control/jit.py) by running a few steps of it
_WARM = (
    "import sys\n"
    "from compliant_docking.config import load_config\n"
    "from compliant_docking.sim.simulate import prepare\n"
    "prepare(load_config(f'controller={sys.argv[1]}', 'task.duration=0.005', 'task.progress=false')).run()\n"
)


def pytest_configure(config) -> None:
    """Compile the compiled laws' kernels once, before pytest-xdist starts its workers.

    numba caches a kernel's machine code on first use (``__pycache__``), but on a fresh
    clone every process that reaches se3_lie or hqp before the cache exists compiles them
    itself: each xdist worker, and each command-line run and sweep worker the tests start
    (20-75 s for hqp on a shared 2-core machine). Here the two kernels compile side by
    side in two processes and every later process loads them. Only for a distributed run
    (``-n``): a single targeted test pays nothing when the cache is warm.
    """
    if hasattr(config, "workerinput") or config.getoption("collectonly", False):
        return  # an xdist worker (the controller did it), or nothing will run
    workers = config.getoption("numprocesses", None)
    if not workers:
        return
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", _WARM, law], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
        )
        for law in ("hqp", "se3_lie")
    ]
    for proc in procs:
        _, err = proc.communicate(timeout=900)
        if proc.returncode:  # the tests of that law will report it; say why here too
            sys.stderr.write(f"compiling a kernel before the workers failed:\n{err.decode()[-2000:]}\n")


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
    for item in items:
        used = getattr(item, "fixturenames", ())
        group = next((name for name in SESSION_FIXTURES if name in used), None)
        if group is None:
            module = next((name for name in MODULE_FIXTURES if name in used), None)
            group = None if module is None else f"{item.module.__name__}:{module}"
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))


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
