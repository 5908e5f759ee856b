"""Shared test helpers: composed configs (no run directory) and the command line."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from compliant_docking import REPO_ROOT
from compliant_docking.config import load_config

#: the composed config for some overrides, exactly as the CLI would build it
make_cfg = load_config


def run_cli(*args: str, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m compliant_docking args…`` in a subprocess, from the repository root."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.run([sys.executable, "-m", "compliant_docking", *args],
                          cwd=cwd or REPO_ROOT, capture_output=True, text=True,
                          timeout=timeout, env=env)
