"""Every command the README prints works as printed.

The commands are read from the README's ``bash`` and ``python`` code blocks (a line ending
in ``\\`` continues on the next; ``# …`` is a comment). The default suite checks each in
well under a second: every command is of a kind checked here; a ``compliant-docking``
command's group options, keys, launchers and sweepers exist; a ``make`` target exists
(``make -n``); a ``python -m`` module and a script exist; the names the Python blocks import
are defined. The ``slow`` tests compose and check each command's first job as a run checks
it before it starts, and run the commands shortened by overrides (0.3 s of stroke) into a
temporary directory.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from omegaconf import OmegaConf

from tests.helpers import REPO_ROOT

README = REPO_ROOT / "README.md"
#: overrides that shorten a run (0.3 s of the stroke, 0.1 s settling) or a sweep's jobs
SHORTER = (
    "trajectory.duration=0.3",
    "task.settle_time=0.1",
    "task.press_duration=0.1",
    "task.progress=false",
    "figures=false",
)
#: the same for the free-space tracking gate's planner, which has no single duration
SHORTER_TRACKING = (
    "trajectory.transition_duration=0.1",
    "trajectory.circle_duration=0.1",
    "trajectory.figure8_duration=0.1",
    "task.settle_time=0.1",
    "task.progress=false",
    "figures=false",
)
#: README placeholders and a value a test can use in their place
PLACEHOLDERS = {"<partition>": "debug", "<server>": "localhost"}


def blocks(language: str) -> list[str]:
    """The README's code blocks in ``language``."""
    return re.findall(rf"^```{language}\n(.*?)^```", README.read_text(), flags=re.M | re.S)


def commands() -> list[str]:
    """Every shell command of the README's bash blocks, continuation lines joined, comments
    left out."""
    found = []
    for block in blocks("bash"):
        for line in block.replace("\\\n", " ").splitlines():
            text = line.split(" #")[0].strip() if not line.lstrip().startswith("#") else ""
            if text:
                found.append(" ".join(text.split()))
    return found


def words(command: str) -> list[str]:
    """The command's words after its environment assignments and ``make setup &&``."""
    parts = shlex.split(command.split("&&")[-1])
    while parts and re.match(r"^[A-Z_]+=", parts[0]):
        parts.pop(0)
    return parts


def kind(command: str) -> str:
    first = words(command)[0] if words(command) else ""
    if first in ("compliant-docking", ".venv/bin/compliant-docking") or command.startswith("eval"):
        return "cli"
    if first == "make":
        return "make"
    if first in ("python", ".venv/bin/python") and words(command)[1] == "-m":
        return "module"
    if first in ("python", ".venv/bin/python"):
        return "script"
    if first == "source":
        return "shell"
    return "unknown"


def cli_argv(command: str) -> list[str]:
    argv = words(command)[1:]
    return [PLACEHOLDERS.get(a, a) for a in argv]


def first_job(argv: list[str]) -> tuple[list[str], dict[str, list[str]]]:
    """The overrides of the first job of ``argv`` (a sweep's first value of each swept key),
    without Hydra's own keys, ``resume=`` and the tuning sweeper's search spaces; and the
    swept config groups with their options."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    keep = [
        a for a in argv if "=" in a and not a.startswith(("hydra", "-", "resume=")) and "interval(" not in a
    ]
    first, groups = [], {}
    for o in OverridesParser.create().parse_overrides(keep):
        if o.is_sweep_override():
            values = list(o.sweep_string_iterator())
            first.append(f"{o.get_key_element()}={values[0]}")
            if "." not in o.get_key_element():
                groups[o.get_key_element()] = values
        else:
            first.append(o.input_line)
    return first, groups


def test_the_readme_shows_commands_of_known_kinds():
    """A new kind of command in the README needs a check here."""
    found = commands()
    assert len(found) > 30
    assert [c for c in found if kind(c) == "unknown"] == []


def test_each_compliant_docking_command_names_existing_options_and_keys():
    """The fast twin of the composition test below: every ``group=option`` of the commands
    is a file of conf/, every ``key=value`` a key of the default config or of the preset
    the command adds."""
    from compliant_docking.config import load_config

    default = load_config()
    cli = [c for c in commands() if kind(c) == "cli" and "-sc" not in c and "--help" not in c]
    for command in cli:
        argv = cli_argv(command)
        overrides, groups = first_job(argv)
        for override in overrides:
            key, value = override.split("=", 1)
            key = key.lstrip("+")
            if (REPO_ROOT / "conf" / key).is_dir():
                assert (REPO_ROOT / "conf" / key / f"{value}.yaml").is_file(), (command, override)
            elif not any(o.startswith("+experiment=") for o in overrides):  # a preset may add keys
                assert OmegaConf.select(default, key, default=MISSING_KEY) is not MISSING_KEY, (command, key)
        for group, options in groups.items():
            for option in options:
                assert (REPO_ROOT / "conf" / group.lstrip("+") / f"{option}.yaml").is_file(), (group, option)
        for arg in argv:  # the launchers and sweepers the commands name
            if arg.startswith("hydra/"):
                group, option = arg.split("=")
                assert (REPO_ROOT / "conf" / group / f"{option}.yaml").is_file(), arg
    assert len(cli) >= 15


MISSING_KEY = object()


@pytest.mark.slow
def test_each_compliant_docking_command_composes_and_passes_the_checks():
    """Every command's first job composed and checked as a run checks it before it starts
    (about 1 s a command: slow; the twin above is the fast check)."""
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    from compliant_docking import CONF_DIR
    from compliant_docking.config import hydra_adapter, register_schemas
    from compliant_docking.config.validate import check

    hydra_adapter.install()  # what the command line's compositions share, memoized
    register_schemas()
    GlobalHydra.instance().clear()
    cli = [c for c in commands() if kind(c) == "cli" and "-sc" not in c and "--help" not in c]
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        for command in cli:
            argv = cli_argv(command)
            overrides, groups = first_job(argv)
            problems = [p for p in check(compose("config", overrides=overrides)) if "viewer" not in p]
            assert problems == [], (command, overrides)  # viewer=true needs a display, not checked
            for group, options in groups.items():  # the other jobs: their options exist
                for option in options:
                    assert (REPO_ROOT / "conf" / group.lstrip("+") / f"{option}.yaml").is_file(), (
                        group,
                        option,
                    )
            for arg in argv:  # the launchers and sweepers the commands name
                if arg.startswith("hydra/"):
                    group, option = arg.split("=")
                    assert (REPO_ROOT / "conf" / group / f"{option}.yaml").is_file(), arg
    GlobalHydra.instance().clear()
    assert len(cli) >= 15


@pytest.mark.parametrize("command", [c for c in commands() if kind(c) == "make"])
def test_each_make_target_exists(command):
    target = [w for w in words(command)[1:] if "=" not in w]
    result = subprocess.run(
        ["make", "-n", *target], cwd=REPO_ROOT, capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr


def test_each_python_module_and_script_exists():
    """Found, not imported (the slow test runs them)."""
    from importlib.util import find_spec

    found = [c for c in commands() if kind(c) in ("module", "script")]
    for command in found:
        argv = words(command)
        if kind(command) == "script":
            assert (REPO_ROOT / argv[1]).is_file(), command
        else:
            assert find_spec(argv[2]) is not None, command
    assert len(found) >= 5


def test_the_python_blocks_import_what_they_use():
    """Each name a block imports is defined or imported by its module's source (found, not
    imported: the slow test runs the blocks)."""
    import ast
    from importlib.util import find_spec

    imported = 0
    for block in blocks("python"):
        for node in ast.walk(ast.parse(block)):
            if isinstance(node, ast.ImportFrom) and node.module:
                spec = find_spec(node.module)
                assert spec is not None and spec.origin, node.module
                source = Path(spec.origin).read_text()
                for alias in node.names:
                    name = alias.name
                    defined = rf'^\s*(def|class) {name}\b|^\s*"{name}",$|import .*\b{name}\b'
                    assert re.search(defined, source, flags=re.M), (node.module, name)
                    imported += 1
    assert imported >= 3


# --------------------------------------------------------------------------- run as printed
@pytest.mark.slow
def test_the_readme_commands_run_as_printed_shortened(tmp_path):
    """The ``compliant-docking`` commands, each run shortened (0.3 s of stroke), the
    Python blocks on a sweep they made, and the report command on it. The presets' sweeps
    (tens to hundreds of jobs, their own tests in tests/sweep and tests/tune) are composed
    and checked above, not run here."""
    ran = []
    for command in commands():
        argv = cli_argv(command)
        if kind(command) != "cli" or any(a in argv for a in ("--help", "viewer=true")) or "-sc" in command:
            continue
        if (
            any("submitit_slurm" in a or "MLFLOW" in command or "interval(" in a for a in argv)
            or "resume=" in command
            or ("-m" in argv and any(a.startswith("+experiment=") for a in argv))
        ):
            continue  # a cluster, a server, a search space: tests/sweep, tests/logger, tests/tune
        swept = "-m" in argv
        shorter = SHORTER_TRACKING if "+experiment=tracking_gate" in argv else SHORTER
        extra = [*shorter, f"hydra.{'sweep' if swept else 'run'}.dir={tmp_path / str(len(ran))}"]
        if swept:
            extra.append("hydra.callbacks.sweep.figures=false")
        mlflow = {"MLFLOW_TRACKING_URI": (tmp_path / "mlruns").as_uri()}  # not the checkout's runs/
        result = subprocess.run(
            [sys.executable, "-m", "compliant_docking", *argv, *extra],
            env={**os.environ, **mlflow},
            cwd=REPO_ROOT, capture_output=True, text=True, timeout=1200,
        )  # fmt: skip
        assert result.returncode in (0, 3), (command, result.stderr[-2000:])
        ran.append(command)
    assert len(ran) >= 8
    sweep = next(p for p in sorted(tmp_path.iterdir()) if (p / "summary.csv").is_file())
    for block in blocks("python"):
        if "load_runs" in block:
            code = block.replace('newest_sweep("runs/multirun")', repr(str(sweep)))
            namespace: dict = {}
            exec(code, namespace)  # noqa: S102 - the README's example
            assert len(namespace["runs"]) >= 2
    out = tmp_path / "report"
    result = subprocess.run(
        [sys.executable, "-m", "compliant_docking.report", str(sweep), "--out", str(out)],
        cwd=REPO_ROOT, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0 and (out / "summary.md").is_file(), result.stderr[-2000:]
    assert json.loads(next(sweep.glob("*/metrics.json")).read_text())["status"] in ("ok", "incomplete")
