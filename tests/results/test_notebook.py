"""analysis/compare_runs.ipynb executes top to bottom against a small sweep made here, named
by a path relative to the repository root (as the sweep prints it)."""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

from compliant_docking import REPO_ROOT
from tests.helpers import SHORT_SWEEP as SHORT
from tests.helpers import sweep_cli

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


def test_notebook_runs_top_to_bottom_on_a_sweep(
    monkeypatch, this_interpreter_kernel, sweep_in_the_repository
):
    sweep = sweep_in_the_repository / "sweep"
    result = sweep_cli(sweep, *SHORT, "robot=iiwa14,fr3", "hydra.callbacks.sweep.figures=false")
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]  # none failed
    assert (sweep / "summary.md").is_file()

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
    client.execute()  # raises CellExecutionError on the first failing cell

    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    text = "\n".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    assert f"reading {sweep}" in text
    assert "2 jobs: 2 succeeded, 0 failed" in text
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) >= 2  # the bars and the force overlay
    tables = [o["data"]["text/markdown"] for o in outputs if "text/markdown" in o.get("data", {})]
    assert any("**contact safety**" in t and "iiwa14" in t and "fr3" in t for t in tables)


def test_notebook_is_committed_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    assert all(not cell.get("outputs") for cell in nb.cells if cell.cell_type == "code")
    assert any("parameters" in cell.metadata.get("tags", []) for cell in nb.cells)
