"""A sweep directory for the tuning tests."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest


@pytest.fixture
def sweep_dir(tmp_path) -> Path:
    """A fresh directory on tmpfs (/dev/shm) when the machine has one, else under tmp_path.

    SQLite syncs each of the study's commits to disk (about 10 ms each here, ~100 per
    study); on tmpfs that costs nothing and the study behaves the same.
    """
    shm = Path("/dev/shm")
    if not (shm.is_dir() and os.access(shm, os.W_OK)):
        yield tmp_path / "sweep"
        return
    folder = Path(tempfile.mkdtemp(prefix="compliant-docking-tune-", dir=shm))
    yield folder / "sweep"
    shutil.rmtree(folder, ignore_errors=True)
