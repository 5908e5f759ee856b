"""The console script ``compliant-docking`` and Hydra's shell completion through it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT

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


def test_console_script_help_is_the_module_help():
    script = _run("--help")
    module = subprocess.run(
        [sys.executable, "-m", "compliant_docking", "--help"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert script.returncode == 0, script.stderr[-2000:]
    assert "Configuration groups" in script.stdout and "controller" in script.stdout
    assert "compliant-docking -m +experiment=tune" in script.stdout
    assert script.stdout == module.stdout  # one command, two spellings
    # every group on one line with its options, the default first
    for group, options in (
        ("controller", "impedance, hqp, hqp_observer, se3_lie"),
        ("sensor", "ideal, wrist_ft"),
        ("robot", "iiwa14, fr3"),
        ("trajectory", "quintic"),
        ("experiment", "controller_comparison"),
    ):
        line = next(line for line in module.stdout.splitlines() if line.strip().startswith(group + " "))
        assert options in line, (group, line)
    assert (
        "Exit status (the same for every command" in module.stdout
        and "The composed configuration" in module.stdout
    )


def test_completion_install_script_registers_the_console_script():
    result = _run("-sc", "install=bash")
    assert result.returncode == 0, result.stderr[-2000:]
    assert "hydra_bash_completion()" in result.stdout
    last = result.stdout.strip().splitlines()[-1]
    assert last.endswith("-F hydra_bash_completion compliant-docking"), last


@pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")
def test_bash_completes_groups_options_and_keys(tmp_path):
    """Source the install script in bash and complete as the shell would (from another
    directory: the config tree is found from the installed package)."""
    env = {**os.environ, "PATH": os.pathsep.join([str(SCRIPT.parent), os.environ.get("PATH", "")])}
    # the install script, written once as a user's ~/.bashrc line would produce it
    install = subprocess.run(
        ["bash", "-c", "compliant-docking -sc install=bash > install.sh"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert install.returncode == 0, install.stderr[-2000:]

    def complete(line: str) -> list[str]:
        words = line.split(" ")
        script = (
            "source install.sh\n"
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
