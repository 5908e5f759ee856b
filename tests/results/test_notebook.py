"""analysis/compare_runs.ipynb executes top to bottom against a small sweep made here, named
by a path relative to the repository root (as the sweep prints it)."""

from __future__ import annotations

import contextlib
import json
import re
import shutil
import signal
import sys
import tempfile
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT, SWEEP_LAUNCHERS, sweep_with
from tests.helpers import SHORT_SWEEP as SHORT

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

NOTEBOOK = REPO_ROOT / "analysis" / "compare_runs.ipynb"
KERNEL = "compliant-docking-tests"


@pytest.fixture
def this_interpreter_kernel(tmp_path, monkeypatch) -> str:
    """A kernelspec running this very interpreter, found through JUPYTER_PATH.

    So the notebook runs with the packages under test whatever kernels the machine
    has registered (a fresh `make test` registers none).
    """
    spec_dir = tmp_path / "jupyter" / "kernels" / KERNEL
    spec_dir.mkdir(parents=True)
    (spec_dir / "kernel.json").write_text(
        json.dumps(
            {
                "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
                "display_name": "compliant-docking (tests)",
                "language": "python",
            }
        )
    )
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")  # silence jupyter_core's notice
    monkeypatch.setenv("MPLBACKEND", "Agg")
    return KERNEL


@pytest.fixture
def sweep_in_the_repository():
    """A temporary folder under the repository's runs/ (git-ignored), removed afterwards:
    the notebook must find a sweep given relative to the repository root."""
    runs = REPO_ROOT / "runs"
    runs.mkdir(exist_ok=True)
    folder = Path(tempfile.mkdtemp(prefix="notebook-test-", dir=runs))
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


@contextlib.contextmanager
def _stop_signal_handlers_kept():
    """nbclient installs its own SIGINT and SIGTERM handlers while it runs the kernel
    (asyncio's ``add_signal_handler``) and never puts back the ones it found (at best it
    resets Python's defaults): put back the ones this process had, so that a later test in
    this worker (the interruption tests) runs under its own."""
    before = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for signum, handler in before.items():
            signal.signal(signum, handler)


@pytest.mark.parametrize("launcher", SWEEP_LAUNCHERS)
def test_notebook_runs_top_to_bottom_on_a_sweep(
    monkeypatch, capsys, this_interpreter_kernel, sweep_in_the_repository, launcher
):
    sweep = sweep_in_the_repository / "sweep"
    # two controllers over the same two draws of the socket's pose (short runs)
    short = [o for o in SHORT if not o.startswith("controller=")]
    draws = ("task.misalignment.seed=range(2)", "task.misalignment.x_range=[-0.001,0.001]")
    result = sweep_with(
        launcher,
        capsys,
        sweep,
        *short,
        "controller=impedance,hqp",
        *draws,
        "hydra.callbacks.sweep.figures=false",
    )
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]  # none failed
    assert (sweep / "summary.md").is_file()
    # the console's end: the paired comparison in words (the details are in summary.md)
    assert "paired comparisons (Holm-corrected, 5 %; the rest in summary.md):" in result.stdout
    assert "- **peak axial force (raw, per step) [N]**, 1 comparison: " in result.stdout

    # as the sweep prints it: relative to the repository root, while the notebook runs in
    # analysis/ (so the path does not exist from the notebook's working directory)
    relative = sweep.relative_to(REPO_ROOT)
    assert not (NOTEBOOK.parent / relative).exists()
    monkeypatch.setenv("COMPLIANT_DOCKING_SWEEP", str(relative))
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(
        nb,
        kernel_name=this_interpreter_kernel,
        timeout=180,
        resources={"metadata": {"path": str(NOTEBOOK.parent)}},
    )
    with _stop_signal_handlers_kept():
        client.execute()  # raises CellExecutionError on the first failing cell

    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    text = "\n".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    assert f"reading {sweep}" in text
    assert "4 jobs: 4 finished" in text and ", 0 failed" in text
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) >= 3  # the bars, the success against the lateral error, the force overlay
    tables = [o["data"]["text/markdown"] for o in outputs if "text/markdown" in o.get("data", {})]
    assert any("**contact safety**" in t and "impedance" in t and "hqp" in t for t in tables)
    # the comparison with intervals: success rates with Wilson's, means and medians with
    # bootstrap intervals, and the paired test of the two controllers on the same draws
    assert any("success rate [95 % CI]" in t and "hqp" in t for t in tables)
    assert any("mean [95 % CI]" in t and re.search(r"\d \[-?\d", t) for t in tables)
    assert any("**peak axial force (raw, per step) [N]**, 1 comparison:" in t for t in tables)  # in words
    assert any("| hqp − impedance |     2 |" in t and "p Holm" in t for t in tables)  # 2 pairs


def test_notebook_is_committed_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    assert all(not cell.get("outputs") for cell in nb.cells if cell.cell_type == "code")
    assert any("parameters" in cell.metadata.get("tags", []) for cell in nb.cells)
