"""The package's shape (docs/design.md): layers that import only the layers below them, no
import cycle, at most 12 modules at the top of the package, no module over 450 lines.

Imports are read from the source with ``ast`` (those inside functions and under
``TYPE_CHECKING`` count too), so a lazy import cannot hide a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT

PACKAGE = REPO_ROOT / "compliant_docking"
#: the layers, lowest first; a module may import its own layer and the ones below
LAYERS = (
    "root",
    "config",
    "planning",
    "sim",
    "control",
    "evaluation",
    "viz",
    "run",
    "results",
    "env",
    "sweep",
    "logger",
    "tune",
    "cli",
)
#: top-level modules of the package and their layer (the rest of the top is the command line)
ROOT_MODULES = {
    "compliant_docking",
    "compliant_docking.gl",
    "compliant_docking.extras",
    "compliant_docking.exit_codes",
}
MAX_TOP_LEVEL_MODULES = 12
MAX_LINES = 450


def _modules() -> dict[str, Path]:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(REPO_ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        found[name] = path
    return found


MODULES = _modules()


def _imports(name: str, path: Path) -> set[str]:
    """The package's modules that ``name`` imports (resolved to existing modules)."""
    out: set[str] = set()
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([node.module] if node.module else []))
            targets = [base] + [f"{base}.{alias.name}" for alias in node.names]
        for target in targets:
            while target and target not in MODULES:
                target = target.rpartition(".")[0]
            if target and target != name:
                out.add(target)
    return out


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


def layer(name: str) -> str:
    if name in ROOT_MODULES:
        return "root"
    parts = name.split(".")
    if len(parts) >= 2 and parts[1] in LAYERS and (MODULES[name].name == "__init__.py" or len(parts) > 2):
        return parts[1]
    return "cli"  # __main__, cli, report: the command line on top


def test_every_module_has_a_known_layer():
    unknown = [m for m in MODULES if layer(m) == "cli" and m.count(".") > 1]
    assert not unknown, f"modules in a sub-package that is not a layer: {unknown}"


def test_each_layer_imports_only_the_layers_below_it():
    rank = {name: i for i, name in enumerate(LAYERS)}
    upward = sorted(
        f"{m} ({layer(m)}) imports {t} ({layer(t)})"
        for m, targets in GRAPH.items()
        for t in targets
        if rank[layer(t)] > rank[layer(m)]
    )
    assert not upward, "imports against the layering:\n" + "\n".join(upward)


def test_no_import_cycle():
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in GRAPH:
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


def test_top_of_the_package_stays_small():
    top = sorted(m for m, p in MODULES.items() if m.count(".") == 1 and p.name != "__init__.py")
    assert len(top) <= MAX_TOP_LEVEL_MODULES, top


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_module_is_over_450_lines(name):
    lines = len(MODULES[name].read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{name}: {lines} lines"


def test_the_layering_check_sees_an_upward_import(tmp_path):
    """The checks can fail: an import of the run layer from the sim layer is flagged."""
    rank = {name: i for i, name in enumerate(LAYERS)}
    assert layer("compliant_docking.sim.simulate") == "sim"
    assert layer("compliant_docking.run.runner") == "run"
    assert rank[layer("compliant_docking.run.runner")] > rank[layer("compliant_docking.sim.simulate")]
    fake = tmp_path / "m.py"
    fake.write_text("from compliant_docking.run.runner import execute\n")
    assert "compliant_docking.run.runner" in _imports("compliant_docking.sim.fake", fake)
