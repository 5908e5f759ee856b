"""Shared test helpers: composed configs (no run directory), the command line, sweeps, and
a push on the tool."""

from __future__ import annotations

import functools
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from compliant_docking.config import load_config

#: the checkout the tests run from (its commands, benchmarks, notebook and docs)
REPO_ROOT = Path(__file__).resolve().parents[1]

#: the composed config for some overrides, exactly as the CLI would build it
make_cfg = load_config


def per_option(options: list[tuple[str, str]]) -> list:
    """``(group, option)`` cells for ``parametrize``, each in the xdist group of its option:
    the tests of every file that compose one option run in one worker, where the
    composition memo (config/hydra_adapter.py) composes it once."""
    return [pytest.param(g, o, marks=pytest.mark.xdist_group(f"option:{g}={o}")) for g, o in options]


def misalignment(**given):
    """``task.misalignment`` as the simulation gets it (the schema's ``MisalignmentConfig``):
    the default config's (nothing misaligned) with the settings ``given``."""
    from dataclasses import replace

    return replace(_default_settings().task.misalignment, **given)


@functools.cache
def _default_settings():
    from compliant_docking.sim.settings import sim_settings

    return sim_settings(make_cfg())


# the arm held still in free space at a reachable point (no socket): push and hold tests
FREE_SPACE_HOLD = ("target=none", "trajectory=hold", "task.init_pos=[0.55,0.0,0.35]", "task.settle_time=0.0")


def run_cli(*args: str, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m compliant_docking args…`` in a subprocess, from the repository root."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.run(
        [sys.executable, "-m", "compliant_docking", *args],
        cwd=cwd or REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


def cli_in_process(capsys, *args: str) -> tuple[int, str]:
    """``python -m compliant_docking args…`` in this process: (exit status, stderr). For
    commands refused before anything runs (no worker processes, no subprocess start-up)."""
    code, _, err = cli_in_process_output(capsys, *args)
    return code, err


def cli_in_process_output(capsys, *args: str) -> tuple[int, str, str]:
    """``python -m compliant_docking args…`` in this process: (exit status, stdout, stderr).
    For a property of the command, not of its process: a refusal, a run's exit status, a
    sweep on Hydra's basic launcher (``hydra/launcher=basic``: its jobs run here too). What
    is about the process itself (the console script, signals, worker processes, a fresh
    interpreter) keeps a subprocess (:func:`run_cli`)."""
    from compliant_docking.cli import main

    try:
        code = main(list(args))
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def push_at_tcp(sim, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0)) -> None:
    """A wrench acting at the TCP (world axes), applied through the tool body's
    ``xfrc_applied``. MuJoCo applies that at the body's centre of mass, so the moment gets
    r × F. Uses the kinematics already in ``sim.data`` (``prepare`` leaves them current).
    """
    data, scene = sim.data, sim.scene
    r = data.site_xpos[scene.tcp_site] - data.xipos[scene.tool_body]
    force, moment = np.asarray(force, float), np.asarray(moment, float)
    data.xfrc_applied[scene.tool_body, :3] = force
    data.xfrc_applied[scene.tool_body, 3:] = moment + np.cross(r, force)


#: the tests folder (on PYTHONPATH for helpers a sweep's workers must import)
TESTS = Path(__file__).parent
#: short jobs: 1 s of motion + 1 s of settling (2 000 steps)
SHORT_SWEEP = (
    "controller=impedance",
    "trajectory=quintic",
    "trajectory.duration=1",
    "task.settle_time=1",
    "task.progress=false",
)


def sweep_cli(
    sweep_dir: Path,
    *args: str,
    pythonpath: Path | None = None,
    timeout: float = 300,
    env: dict[str, str] | None = None,
) -> subprocess.CompletedProcess:
    """``python -m compliant_docking -m args…`` with 2 workers into ``sweep_dir``
    (``env``: variables to set for it)."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})}
    if pythonpath is not None:
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(pythonpath), env.get("PYTHONPATH")]))
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "compliant_docking",
            "-m",
            *args,
            f"hydra.sweep.dir={sweep_dir}",
            "hydra.launcher.n_jobs=2",
        ],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


#: how a sweep test runs its command: ``basic``, the command's main in this process on Hydra's
#: basic launcher (its jobs run here too: no process start-up; the fast suite), ``pool``, a
#: command-line process whose jobs run in the worker pool (end to end; `slow`, nightly)
SWEEP_LAUNCHERS = ("basic", pytest.param("pool", marks=pytest.mark.slow))


def sweep_with(
    launcher: str, capsys, sweep_dir: Path, *args: str, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess:
    """The sweep ``-m args…`` into ``sweep_dir`` as :data:`SWEEP_LAUNCHERS` says
    (``env``: variables to set for it); its exit status and output."""
    if launcher == "pool":
        return sweep_cli(sweep_dir, *args, env=env)
    command = ("-m", *args, "hydra/launcher=basic", f"hydra.sweep.dir={sweep_dir}")
    with pytest.MonkeyPatch.context() as patch:
        for name, value in (env or {}).items():
            patch.setenv(name, value)
        code, out, err = cli_in_process_output(capsys, *command)
    return subprocess.CompletedProcess(["compliant-docking", *command], code, out, err)


#: a short held-contact scene: the plug starts 10 mm above the seat, inside the bore, moves
#: to the seat in 1 s and the reference is pressed 5 mm deeper (the default press), 4 s in
#: all: the same held contact as the last 2 s of a full docking run, at a quarter of its cost
SHORT_CONTACT = (
    "task.stroke=[0,0,-0.01]",
    "trajectory.duration=1.0",
    "task.settle_time=3.0",
    "task.progress=false",
)


def steady_contact(sim, window: float = 2.0) -> tuple[float, float, float]:
    """(make/break events per second, |F| mean, |F| std) over the last ``window`` seconds of a
    finished simulation, as /work/shared/tools/steady_window.py computes them."""
    log = sim.telemetry
    n = log.count
    k = n - int(round(window / sim.scene.model.opt.timestep))
    touching = (log.contacts[k:n] > 0).astype(int)
    force = np.linalg.norm(log.wrench[k:n, :3], axis=1)
    return float(np.abs(np.diff(touching)).sum() / window), float(force.mean()), float(force.std(ddof=1))


def calm(rate: float, mean: float, std: float) -> bool:
    """The docking gate's calm hold: ≤ 5 make/break events per second, std ≤ max(0.5 N, 20 % of the mean)."""
    return rate <= 5.0 and std <= max(0.5, 0.2 * mean)
