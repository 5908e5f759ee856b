"""Provenance in metrics.json, the config hash, and reproducibility (same config → same run)."""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
import textwrap
from datetime import datetime
from importlib import metadata

import numpy as np
import pandas as pd
import pytest
from omegaconf import OmegaConf

from compliant_docking.results import load_runs
from compliant_docking.run import provenance
from compliant_docking.run.runner import execute
from tests.helpers import REPO_ROOT, make_cfg

SHORT = ("task.progress=false", "trajectory.duration=1", "task.settle_time=1")
PROVENANCE_KEYS = (
    "config_hash",
    "started_at",
    "host",
    "git_commit",
    "git_dirty",
    "version_python",
    "version_mujoco",
    "version_pin",
    "version_proxsuite",
    "version_numpy",
    "version_hydra_core",
    "version_compliant_docking",
)


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    run_dir = tmp_path_factory.mktemp("prov") / "run"
    record = execute(make_cfg(*SHORT), run_dir, figures=False, echo=False)
    return run_dir, record


def test_every_run_records_its_provenance(short_run):
    run_dir, record = short_run
    saved = json.loads((run_dir / "metrics.json").read_text())
    assert set(PROVENANCE_KEYS) <= saved.keys()
    assert saved["version_python"] == ".".join(map(str, sys.version_info[:3]))
    for key, dist in (
        ("mujoco", "mujoco"),
        ("pin", "pin"),
        ("proxsuite", "proxsuite"),
        ("numpy", "numpy"),
        ("hydra_core", "hydra-core"),
        ("compliant_docking", "compliant-docking"),
    ):
        assert saved[f"version_{key}"] == metadata.version(dist)
    assert saved["host"] == socket.gethostname()
    started = datetime.fromisoformat(saved["started_at"])
    assert started.tzinfo is not None  # ISO 8601 with the UTC offset
    assert abs((datetime.now().astimezone() - started).total_seconds()) < 600
    assert saved["config_hash"] == provenance.config_hash(make_cfg(*SHORT))
    if (REPO_ROOT / ".git").exists():  # run from a checkout (CI, make test): its HEAD
        head = subprocess.run(
            ["git", "-C", str(REPO_ROOT), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()
        assert saved["git_commit"] == head
        assert isinstance(saved["git_dirty"], bool)
    # load_runs surfaces every key as a column
    row = load_runs(run_dir).iloc[0]
    for key in PROVENANCE_KEYS:
        assert key in row.index
    assert row["config_hash"] == saved["config_hash"]


def test_versions_and_git_are_computed_once_per_process(monkeypatch):
    provenance.git_state.cache_clear()
    provenance.versions.cache_clear()
    calls = []
    real_run = subprocess.run

    def counting_run(*args, **kwargs):
        calls.append(args[0])
        return real_run(*args, **kwargs)

    monkeypatch.setattr(provenance.subprocess, "run", counting_run)
    cfg = make_cfg(*SHORT)
    first = provenance.collect(cfg, started_at=provenance.now_iso())
    second = provenance.collect(cfg, started_at=provenance.now_iso())
    expected = 1 if (REPO_ROOT / ".git").exists() else 0
    assert len(calls) == expected  # one `git status` for the process, not one per job
    assert {k: v for k, v in first.items() if k != "started_at"} == {
        k: v for k, v in second.items() if k != "started_at"
    }


def _git(repo, *args: str) -> str:
    env = {
        "GIT_AUTHOR_NAME": "t",
        "GIT_AUTHOR_EMAIL": "t@t",
        "GIT_COMMITTER_NAME": "t",
        "GIT_COMMITTER_EMAIL": "t@t",
    }
    return subprocess.run(
        ["git", "-C", str(repo), *args], capture_output=True, text=True, check=True, env={**os.environ, **env}
    ).stdout.strip()


def _state_of(monkeypatch, root):
    monkeypatch.setattr(provenance, "REPO_ROOT", root)
    provenance.git_state.cache_clear()
    try:
        return provenance.git_state()
    finally:
        provenance.git_state.cache_clear()


def test_git_commit_is_head_and_git_dirty_follows_the_tree(monkeypatch, tmp_path):
    """In a checkout of its own: clean → dirty false; an edited, a staged or an untracked
    file → true; an ignored file → false; a linked worktree (.git is a file) works too."""
    repo = tmp_path / "repo"
    repo.mkdir()
    _git(repo, "init", "-q")
    (repo / "a.py").write_text("x = 1\n")
    (repo / ".gitignore").write_text("runs/\n")
    _git(repo, "add", "-A")
    _git(repo, "commit", "-q", "-m", "first")
    head = _git(repo, "rev-parse", "HEAD")
    assert _state_of(monkeypatch, repo) == {"git_commit": head, "git_dirty": False}
    (repo / "runs").mkdir()
    (repo / "runs" / "metrics.json").write_text("{}")  # ignored: still clean
    assert _state_of(monkeypatch, repo)["git_dirty"] is False
    (repo / "a.py").write_text("x = 2\n")  # edited
    assert _state_of(monkeypatch, repo) == {"git_commit": head, "git_dirty": True}
    _git(repo, "add", "a.py")  # staged
    assert _state_of(monkeypatch, repo)["git_dirty"] is True
    _git(repo, "commit", "-q", "-m", "second")
    second = _git(repo, "rev-parse", "HEAD")
    assert second != head and _state_of(monkeypatch, repo) == {"git_commit": second, "git_dirty": False}
    (repo / "new.py").write_text("")  # untracked
    assert _state_of(monkeypatch, repo)["git_dirty"] is True
    _git(repo, "worktree", "add", "-q", str(tmp_path / "linked"), "HEAD")
    assert (tmp_path / "linked" / ".git").is_file()
    assert _state_of(monkeypatch, tmp_path / "linked") == {"git_commit": second, "git_dirty": False}


def test_git_fields_are_null_outside_a_checkout(monkeypatch, tmp_path):
    provenance.git_state.cache_clear()
    monkeypatch.setattr(provenance, "REPO_ROOT", tmp_path)  # an installed wheel: no .git
    try:
        assert provenance.git_state() == {"git_commit": None, "git_dirty": None}
    finally:
        provenance.git_state.cache_clear()


def test_config_hash_covers_the_config_not_how_it_reports():
    base = provenance.config_hash(make_cfg(*SHORT))
    assert re.fullmatch(r"[0-9a-f]{16}", base)
    assert provenance.config_hash(make_cfg(*SHORT)) == base  # stable
    assert provenance.config_hash(make_cfg(*SHORT, "task.progress=true")) == base  # cosmetic
    for figures in ("true", "false"):  # which files a job draws, not what it computes
        assert provenance.config_hash(make_cfg(*SHORT, f"figures={figures}")) == base
    for change in (
        "controller.k=51",
        "robot=fr3",
        "task.misalignment.seed=1",
        "physics.timestep=0.0005",
        "render=video",
        "tool.geometry.radius=0.0051",
    ):
        assert provenance.config_hash(make_cfg(*SHORT, change)) != base, change
    # an interpolation counts by its value: the socket's plug radius follows the tool's
    cfg = make_cfg(*SHORT)
    assert OmegaConf.is_interpolation(cfg.target.geometry, "plug_radius")
    # Hydra's own node (sweep dir, launcher, job number) is left out
    assert provenance.config_hash(_compose_with_hydra(*SHORT)) == base
    assert (
        provenance.config_hash(
            _compose_with_hydra(*SHORT, "hydra.job.num=7", "hydra/launcher=submitit_local")
        )
        == base
    )


def _compose_with_hydra(*overrides: str):
    from hydra import compose, initialize_config_dir
    from hydra.core.config_store import ConfigStore
    from hydra.core.global_hydra import GlobalHydra

    from compliant_docking import CONF_DIR
    from compliant_docking.config import register_schemas
    from compliant_docking.sweep import launchers

    register_schemas()
    launchers.register_schemas(ConfigStore.instance())
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose("config", overrides=list(overrides), return_hydra_config=True)
    assert "hydra" in cfg
    return cfg


# fast proof: tests/run/test_provenance.py::test_a_fresh_process_gives_the_same_run (the fresh
# process's metrics.json carries the same config_hash, which is not a volatile key)
@pytest.mark.slow
def test_config_hash_is_the_same_in_a_fresh_process():
    code = textwrap.dedent(f"""
        from compliant_docking.config import load_config
        from compliant_docking.run.provenance import config_hash
        print(config_hash(load_config(*{list(SHORT)!r})))
    """)
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO_ROOT, timeout=120, check=True
    ).stdout.strip()
    assert out == provenance.config_hash(make_cfg(*SHORT))


# --------------------------------------------------------------------------- reproducibility
def assert_same_run(dir_a, dir_b) -> None:
    """Every metric equal except timing and start time; the time series bit for bit."""
    a = json.loads((dir_a / "metrics.json").read_text())
    b = json.loads((dir_b / "metrics.json").read_text())
    assert a.keys() == b.keys()
    differing = {k for k in a if a[k] != b[k]}
    assert differing <= provenance.VOLATILE_KEYS, {k: (a[k], b[k]) for k in differing}
    assert a["status"] == "ok"
    ta = pd.read_parquet(dir_a / "timeseries.parquet")
    tb = pd.read_parquet(dir_b / "timeseries.parquet")
    assert list(ta.columns) == list(tb.columns) and ta.shape == tb.shape
    for column in ta.columns:
        x, y = ta[column].to_numpy(), tb[column].to_numpy()
        assert x.dtype == y.dtype, column
        assert np.ascontiguousarray(x).tobytes() == np.ascontiguousarray(y).tobytes(), column


REPRO_CONFIGS = {
    "impedance, drawn misalignment": (
        "controller=impedance",
        "task.misalignment.seed=3",
        "task.misalignment.x_range=[-0.002,0.002]",
        "task.misalignment.tilt_deg_range=[0,1]",
    ),
    "hqp": ("controller=hqp",),
    "se3_lie on fr3 under gravity": ("controller=se3_lie", "robot=fr3", "physics=earth"),
}


@pytest.mark.parametrize("overrides", REPRO_CONFIGS.values(), ids=REPRO_CONFIGS.keys())
def test_the_same_config_gives_the_same_run(tmp_path, overrides):
    for name in ("a", "b"):  # composed anew each time, as a sweep job would be
        execute(make_cfg(*SHORT, *overrides), tmp_path / name, figures=False, echo=False)
    assert_same_run(tmp_path / "a", tmp_path / "b")


def test_a_fresh_process_gives_the_same_run(tmp_path, short_run):
    """No state carried between jobs of a reused worker: a new process gives the same run
    (and the same config_hash: a new process hashes the config as this one does)."""
    run_dir, _ = short_run
    code = textwrap.dedent(f"""
        from compliant_docking.config import load_config
        from compliant_docking.run.runner import execute
        execute(load_config(*{list(SHORT)!r}), {str(tmp_path / "fresh")!r}, figures=False,
                echo=False)
    """)
    subprocess.run([sys.executable, "-c", code], cwd=REPO_ROOT, timeout=300, check=True, capture_output=True)
    assert_same_run(run_dir, tmp_path / "fresh")
