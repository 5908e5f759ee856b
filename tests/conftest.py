"""Shared test helpers: compose configs with Hydra's compose API (no run directory)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra

from compliant_docking import CONF_DIR, REPO_ROOT
from compliant_docking.config import register_schemas

register_schemas()


def make_cfg(*overrides: str):
    """The composed config for these overrides, exactly as the CLI would build it."""
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(config_name="config", overrides=list(overrides))


def run_cli(*args: str, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m compliant_docking args…`` in a subprocess, from the repository root."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.run([sys.executable, "-m", "compliant_docking", *args],
                          cwd=cwd or REPO_ROOT, capture_output=True, text=True,
                          timeout=timeout, env=env)


@pytest.fixture
def cfg_factory():
    return make_cfg
