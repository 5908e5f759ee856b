"""Sweeps beyond joblib: the submitit presets, and jobs that behave the same on every launcher."""

from __future__ import annotations

import json
import os
import re
import sys
import warnings
from pathlib import Path

import pandas as pd
import pytest
from hydra import compose, initialize_config_dir
from hydra.core.config_store import ConfigStore
from hydra.core.global_hydra import GlobalHydra
from omegaconf import OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.config import register_schemas
from compliant_docking.results import RunSkippedWarning, load_runs
from compliant_docking.run import provenance
from compliant_docking.sweep import launchers
from compliant_docking.sweep.launchers import describe, is_submitit
from compliant_docking.sweep.progress import ProgressWatcher

#: keys that may differ between two launches of one config: timing, start time, and the
#: provenance of the process (same machine here, but a commit could land in between)
VARYING = provenance.VOLATILE_KEYS | {"git_commit", "git_dirty"}


def _compose(*overrides: str):
    register_schemas()
    launchers.register_schemas(ConfigStore.instance())
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose("config", overrides=list(overrides), return_hydra_config=True)


def _files(job_dir: Path) -> set[str]:
    return {str(p.relative_to(job_dir)) for p in job_dir.rglob("*") if p.is_file()}


#: the launchers compared with the default pool: Hydra's joblib launcher in the fast suite,
#: submitit's local launcher (a process per job) in the nightly suite (`slow`); both compose
#: each job's config again where the job runs, which is what the comparison is about, so the
#: joblib pair proves the pool's configs in the fast suite
OTHER_LAUNCHERS = [
    "joblib",
    pytest.param("submitit", marks=pytest.mark.slow(reason="the joblib pair is fast")),
]


@pytest.mark.parametrize("other", OTHER_LAUNCHERS)
def test_the_default_pool_and_another_launcher_give_the_same_outputs(failing_sweeps, other):
    """Same job directories, metrics (timing and start time aside), time series, failure
    records, summary rows, end-of-sweep summary and exit status (1: a job failed);
    submitit's logs stay in .submitit/. The default launcher (sweep/pool.py) sends each
    job the config composed in the launching process; Hydra's joblib launcher composes it
    again in the worker, submitit in the job's own process: the jobs must not tell. The
    pool run is the shared failing sweep (tests/sweep/conftest.py), which also draws the
    comparison figures (a directory, not compared here)."""
    failing_sweeps.start(other)  # side by side with the pool run if it is not done yet
    runs = {name: failing_sweeps.result(name) for name in ("pool", other)}
    tmp_path = runs["pool"].sweep_dir.parent
    out = {name: (run.stdout, run.stderr) for name, run in runs.items()}
    for name, run in runs.items():
        assert run.returncode == 1, (name, run.stderr[-3000:])
        stdout = out[name][0]
        assert (
            "sweep finished in" in stdout
            and "3 jobs: 2 finished (0 docked, 0 not docked, 2 without a gate), 1 failed" in stdout
        )
        assert "FAILED 2_" in stdout and "inverse kinematics" in stdout
        assert sorted(line[:6] for line in stdout.splitlines() if re.match(r"\[\d/3\] ", line)) == [
            "[1/3] ",
            "[2/3] ",
            "[3/3] ",
        ]  # one progress line per job
    assert "PoolLauncher(2 workers) is launching 3 jobs" in out["pool"][0]

    jobs = {
        name: sorted(p for p in (tmp_path / name).iterdir() if p.is_dir() and p.name[0].isdigit())
        for name in runs
    }
    assert [p.name for p in jobs["pool"]] == [p.name for p in jobs[other]]
    assert len(jobs["pool"]) == 3
    for a, b in zip(jobs["pool"], jobs[other]):
        assert _files(a) == _files(b), a.name
        ma = json.loads((a / "metrics.json").read_text())
        mb = json.loads((b / "metrics.json").read_text())
        assert ma.keys() == mb.keys()
        assert {k for k in ma if ma[k] != mb[k]} <= VARYING
        assert ma["config_hash"] == mb["config_hash"]
        if ma["status"] == "failed":
            assert a.name.startswith("2_") and not (a / "timeseries.parquet").exists()
            continue
        assert ma["status"] == "ok"
        ta, tb = pd.read_parquet(a / "timeseries.parquet"), pd.read_parquet(b / "timeseries.parquet")
        pd.testing.assert_frame_equal(ta, tb, check_exact=True)
        for name in ("overrides.yaml", "config.yaml"):
            assert (a / ".hydra" / name).read_text() == (b / ".hydra" / name).read_text()

    # the summaries: same files, same rows
    for name in runs:
        assert {p.name for p in (tmp_path / name).iterdir() if p.is_file()} == {
            "multirun.yaml",
            "summary.md",
            "summary.csv",
            "summary.parquet",
            "comparison.csv",
            "comparison.parquet",
            "paired.csv",
            "paired.parquet",
        }
    sa = pd.read_parquet(tmp_path / "pool" / "summary.parquet")
    sb = pd.read_parquet(tmp_path / other / "summary.parquet")
    assert list(sa.columns) == list(sb.columns) and len(sa) == len(sb) == 3
    keep = [c for c in sa.columns if c not in VARYING | {"run_dir"}]
    pd.testing.assert_frame_equal(sa[keep], sb[keep], check_exact=True)

    if other == "submitit":
        assert "as local submitit processes" in out["submitit"][0]
        # submitit's logs and pickles: a hidden folder of the sweep, which load_runs never reads
        logs = list((tmp_path / "submitit" / ".submitit").rglob("*_log.out"))
        assert len(logs) == 3
        assert any("· finished ·" in log.read_text() for log in logs)  # the job's own progress line
        with warnings.catch_warnings():
            warnings.simplefilter("error", RunSkippedWarning)
            assert len(load_runs(tmp_path / "submitit")) == 3


@pytest.mark.parametrize("launcher", ["submitit_local", "submitit_slurm"])
def test_submitit_presets_compose_typed_and_without_warnings(launcher):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "automatic schema matching" deprecation
        cfg = _compose(f"hydra/launcher={launcher}")
    node = cfg.hydra.launcher
    assert is_submitit(node)
    assert node.submitit_folder == f"{cfg.hydra.sweep.dir}/.submitit/%j"  # hidden, in the sweep
    assert node.name == "compliant_docking"
    assert OmegaConf.get_type(node).__name__ in ("LocalQueueConf", "SlurmQueueConf")
    with pytest.raises(Exception, match="partiton"):  # misspelled keys are refused
        _compose(f"hydra/launcher={launcher}", "hydra.launcher.partiton=x")
    with pytest.raises(Exception, match="cpus_per_task"):  # and wrong types
        _compose(f"hydra/launcher={launcher}", "hydra.launcher.cpus_per_task=many")
    # our files replace the plugin's presets of the same names
    assert ConfigStore.instance().repo["schema"]["launcher"][f"{launcher}.yaml"]
    assert f"{launcher}.yaml" not in ConfigStore.instance().repo["hydra"]["launcher"]


def test_slurm_preset_becomes_the_sbatch_options_a_lab_needs(tmp_path, monkeypatch):
    """Our preset through the plugin's own launch() into submitit's sbatch script (the
    submission itself is intercepted: no Slurm here)."""
    from hydra_plugins.hydra_submitit_launcher.submitit_launcher import SlurmLauncher
    from submitit.slurm import slurm

    fake_bin = tmp_path / "bin"  # submitit checks that srun exists
    fake_bin.mkdir()
    (fake_bin / "srun").write_text("#!/bin/sh\nexit 1\n")
    (fake_bin / "srun").chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake_bin}{os.pathsep}{os.environ['PATH']}")

    class Submitted(Exception):
        pass

    def capture(self, command):
        raise Submitted(self._make_submission_file_text(command, "uid"))

    monkeypatch.setattr(slurm.SlurmExecutor, "_submit_command", capture)
    sweep = tmp_path / "sweep"
    cfg = _compose(
        "hydra/launcher=submitit_slurm",
        "hydra.launcher.partition=short",
        "hydra.launcher.account=lab",
        "hydra.launcher.timeout_min=30",
        "hydra.launcher.array_parallelism=2",
        f"hydra.sweep.dir={sweep}",
    )
    assert describe(cfg.hydra.launcher) == (
        "as a Slurm job array on short, at most 2 at a time (logs in .submitit/)"
    )
    params = OmegaConf.to_container(cfg.hydra.launcher, resolve=True)
    params.pop("_target_")
    launcher = SlurmLauncher(**params)
    launcher.setup(hydra_context=None, task_function=print, config=cfg)
    with pytest.raises(Submitted) as submitted:
        launcher.launch(
            [["controller=hqp"], ["controller=impedance"], ["controller=se3_lie"]], initial_job_idx=0
        )
    script = submitted.value.args[0]
    for line in (
        "#SBATCH --partition=short",
        "#SBATCH --account=lab",
        "#SBATCH --time=30",
        "#SBATCH --cpus-per-task=1",
        "#SBATCH --mem=2GB",
        "#SBATCH --array=0-2%2",
        "#SBATCH --job-name=compliant_docking",
        f"#SBATCH --output={sweep}/.submitit/%A_%a/%A_%a_0_log.out",
        "export OMP_NUM_THREADS=1",
    ):
        assert line in script, line
    assert sys.executable in script  # the jobs run this environment's interpreter


def test_progress_watcher_prints_each_finished_job_once(tmp_path, capsys):
    sweep = tmp_path / "sweep"
    (sweep / "0_a").mkdir(parents=True)
    (sweep / "0_a" / "metrics.json").write_text(json.dumps({"status": "ok", "success": True}))
    watcher = ProgressWatcher(sweep, total=3, interval_s=60)  # polled by hand here
    watcher.poll()
    assert capsys.readouterr().out == ""  # finished before the sweep (re)started: no line
    for name, status in (("1_b", "ok"), ("2_c", "failed")):
        (sweep / name).mkdir()
        (sweep / name / "metrics.json").write_text(
            json.dumps({"status": status, "success": status == "ok", "wall_time_s": 1.0})
        )
    (sweep / ".submitit").mkdir()  # never looked into
    watcher.poll()
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("[2/3] 1_b · finished") and lines[1].startswith("[3/3] 2_c · FAILED")
    watcher.poll()
    assert capsys.readouterr().out == ""
