"""One three-job sweep with a failing job, shared by the sweep tests that read it.

tests/sweep/test_callback.py checks failure isolation, the summary files and the console
on the default (pool) launcher; tests/sweep/test_launchers.py compares it with the same
sweep on Hydra's joblib launcher and on submitit. Each launch starts at most once per test session, in the background,
so that the two launchers run side by side when both are wanted.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT

#: 3 short jobs (free space, 2 s simulated); the third fails: its start is out of reach, a
#: failure only the run finds (a value the config check refuses, e.g. a zero duration,
#: refuses the whole sweep before it starts: tests/sweep/test_guard.py)
JOBS = (
    "trajectory=hold",
    "trajectory.duration=1",
    "target=none",
    "task.init_pos=[0.55,0,0.35],[0.55,0,0.4],[3,0,0.35]",
    "task.settle_time=1",
    "task.progress=false",
)
#: the launcher overrides of each launch; only the default pool draws the comparison figures
LAUNCHERS = {
    "pool": ("hydra.launcher.n_jobs=2",),
    "joblib": ("hydra/launcher=joblib", "hydra.launcher.n_jobs=2", "hydra.callbacks.sweep.figures=false"),
    "submitit": ("hydra/launcher=submitit_local", "hydra.callbacks.sweep.figures=false"),
}


@dataclass
class Finished:
    sweep_dir: Path
    returncode: int
    stdout: str
    stderr: str


class FailingSweeps:
    """Start a launch (once) and wait for its result (once)."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self._running: dict[str, subprocess.Popen] = {}
        self._done: dict[str, Finished] = {}

    def start(self, launcher: str) -> None:
        if launcher in self._running or launcher in self._done:
            return
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        self._running[launcher] = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "compliant_docking",
                "-m",
                *JOBS,
                f"hydra.sweep.dir={self.root / launcher}",
                *LAUNCHERS[launcher],
            ],
            cwd=REPO_ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )

    def result(self, launcher: str) -> Finished:
        if launcher not in self._done:
            self.start(launcher)
            proc = self._running.pop(launcher)
            out, err = proc.communicate(timeout=300)
            self._done[launcher] = Finished(self.root / launcher, proc.returncode, out, err)
        return self._done[launcher]

    def close(self) -> None:
        for proc in self._running.values():
            proc.kill()
            proc.communicate()


@pytest.fixture(scope="session")
def failing_sweeps(tmp_path_factory):
    sweeps = FailingSweeps(tmp_path_factory.mktemp("failing_sweep"))
    yield sweeps
    sweeps.close()
