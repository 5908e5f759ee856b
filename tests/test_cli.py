"""The console script ``compliant-docking`` and Hydra's shell completion through it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT, cli_in_process_output

#: the console script pip installed beside this interpreter ([project.scripts])
SCRIPT = Path(sys.executable).parent / "compliant-docking"


def _run(*args: str, env: dict | None = None, cwd: Path = REPO_ROOT) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(SCRIPT), *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        env=env or dict(os.environ),
    )


def test_console_script_is_installed():
    assert SCRIPT.is_file(), f"{SCRIPT} missing: reinstall the project (pip install -e '.[test]')"


def test_console_script_help_is_the_module_help(capsys):
    script = _run("--help")
    # the module's spelling (``python -m compliant_docking``, whose __main__ calls cli.main)
    # in this process: one process start less, the same main
    code, module, _ = cli_in_process_output(capsys, "--help")
    assert script.returncode == 0, script.stderr[-2000:]
    assert code == 0
    assert "Configuration groups" in script.stdout and "controller" in script.stdout
    assert "compliant-docking -m +experiment=tune" in script.stdout
    assert script.stdout == module  # one command, two spellings
    # every group on one line with its options, the default first
    for group, options in (
        ("controller", "impedance, hqp, hqp_observer, se3_lie"),
        ("sensor", "ideal, wrist_ft"),
        ("robot", "iiwa14, fr3"),
        ("trajectory", "quintic"),
        ("experiment", "controller_comparison"),
    ):
        line = next(line for line in module.splitlines() if line.strip().startswith(group + " "))
        assert options in line, (group, line)
    assert "Exit status (the same for every command" in module and "The composed configuration" in module


@pytest.fixture(scope="module")
def completion_script(tmp_path_factory) -> Path:
    """The install script, written once (as a user's ~/.bashrc line would produce it) by the
    console script from a directory that is not the checkout: the registration test reads
    it and the completion test sources it (one process start for both)."""
    where = tmp_path_factory.mktemp("completion")
    result = _run("-sc", "install=bash", cwd=where)
    assert result.returncode == 0, result.stderr[-2000:]
    (where / "install.sh").write_text(result.stdout)
    return where / "install.sh"


def test_completion_install_script_registers_the_console_script(completion_script):
    text = completion_script.read_text()
    assert "hydra_bash_completion()" in text
    last = text.strip().splitlines()[-1]
    assert last.endswith("-F hydra_bash_completion compliant-docking"), last


@pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")
def test_bash_completes_groups_options_and_keys(completion_script, tmp_path):
    """Source the install script in bash and complete as the shell would (from another
    directory: the config tree is found from the installed package)."""
    env = {**os.environ, "PATH": os.pathsep.join([str(SCRIPT.parent), os.environ.get("PATH", "")])}

    def complete(line: str) -> list[str]:
        words = line.split(" ")
        script = (
            f"source {completion_script}\n"
            f'COMP_LINE="{line}"; COMP_POINT=${{#COMP_LINE}}\n'
            f"COMP_WORDS=({' '.join(words)}); COMP_CWORD={len(words) - 1}\n"
            'hydra_bash_completion; printf "%s\\n" "${COMPREPLY[@]}"\n'
        )
        out = subprocess.run(
            ["bash", "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=120, env=env
        )
        assert out.returncode == 0, out.stderr[-2000:]
        return sorted(filter(None, out.stdout.splitlines()))

    assert complete("compliant-docking controller=") == [
        "controller=hqp",
        "controller=hqp_observer",
        "controller=impedance",
        "controller=se3_lie",
    ]
    assert "controller.k_rot=" in complete("compliant-docking controller.k")
