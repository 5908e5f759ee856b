"""The package's shape (docs/design.md): layers that import only the layers below them, no
import cycle, at most 12 modules at the top of the package, no module over 450 lines.

The layers and the cycles are import-linter's contracts in pyproject.toml
(``[tool.importlinter]``, also run by ``make lint`` as ``lint-imports``); its import graph is
read from the source (grimp), imports inside functions and under ``TYPE_CHECKING`` included,
so a lazy import cannot hide a dependency. The sizes are counted here: import-linter has no
contract for them.
"""

from __future__ import annotations

import shutil
import sys

import pytest
from importlinter.cli import lint_imports

from tests.helpers import REPO_ROOT

PACKAGE = REPO_ROOT / "compliant_docking"
PYPROJECT = REPO_ROOT / "pyproject.toml"
MAX_TOP_LEVEL_MODULES = 12
MAX_LINES = 450
MODULES = {
    ".".join(path.relative_to(REPO_ROOT).with_suffix("").parts): path for path in PACKAGE.rglob("*.py")
}


def _lint(capsys) -> tuple[int, str]:
    """import-linter's verdict on pyproject.toml's contracts: exit code and report (it puts
    the working directory on ``sys.path``: restored by the callers' monkeypatch)."""
    code = lint_imports(config_filename=str(PYPROJECT), no_cache=True, no_logo=True)
    return code, capsys.readouterr().out


def test_the_import_contracts_are_kept(monkeypatch, capsys):
    monkeypatch.setattr(sys, "path", list(sys.path))
    code, report = _lint(capsys)
    assert code == 0, "imports against the layering or an import cycle:\n" + report


def test_the_import_contracts_see_lazy_and_type_checking_imports(tmp_path, monkeypatch, capsys):
    """The contracts can fail: in a copy of the package, an import of the run layer inside a
    function of the sim layer, and one of the results layer under ``TYPE_CHECKING`` in the
    planning layer, both break the layering; a pair of modules importing each other is a
    cycle."""
    copy = tmp_path / "compliant_docking"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    with (copy / "sim" / "progress.py").open("a") as f:
        f.write("\n\ndef _late():\n    from compliant_docking.run import runner\n")
    with (copy / "planning" / "__init__.py").open("a") as f:
        f.write("\nfrom typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n")
        f.write("    from compliant_docking.results import load\n")
    with (copy / "results" / "tables.py").open("a") as f:
        f.write("\nfrom compliant_docking.results import summary\n")
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.chdir(tmp_path)  # lint-imports puts the working directory first on sys.path
    monkeypatch.delitem(sys.modules, "compliant_docking")
    code, report = _lint(capsys)
    assert code == 1, report
    assert "compliant_docking.sim is not allowed to import compliant_docking.run" in report
    assert "compliant_docking.planning is not allowed to import compliant_docking.results" in report
    assert "No cycles are allowed in compliant_docking.results" in report
    assert "- .tables -> .summary" in report


def test_top_of_the_package_stays_small():
    top = sorted(m for m in MODULES if m.count(".") == 1 and not m.endswith(".__init__"))
    assert len(top) <= MAX_TOP_LEVEL_MODULES, top


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_module_is_over_450_lines(name):
    lines = len(MODULES[name].read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{name}: {lines} lines"
