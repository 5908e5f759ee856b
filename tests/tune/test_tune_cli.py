"""+experiment=tune from the command line: a small study (6 trials, 2 at a time, short
runs) that finishes, writes the best gains, and resumes when the command is run again."""

from __future__ import annotations

import json

import optuna
import pytest
import yaml

from tests.helpers import cli_in_process, make_cfg, sweep_cli

#: short docking runs that dock: a 2 cm stroke in 1 s, then 1.5 s to settle
SHORT_TUNE = (
    "+experiment=tune",
    "trajectory.duration=1",
    "task.settle_time=1.5",
    "task.stroke=[0,0,-0.02]",
    "task.steady_window=0.5",
    "task.progress=false",
    "hydra.sweeper.draws={task.misalignment.seed:'range(2)'}",
)
DRAWS = 2


def recomputed(sweep_dir, trial, metric: str) -> float:
    """The trial's value from its jobs' metrics.json, computed here: the mean of the
    metric when every draw docked, else the penalty for the share that did not."""
    records = [json.loads((sweep_dir / job / "metrics.json").read_text()) for job in trial.user_attrs["jobs"]]
    if all(r["status"] != "failed" and r["success"] is True for r in records):
        return sum(r[metric] for r in records) / len(records)
    bad = sum(1 for r in records if r["status"] == "failed" or r["success"] is not True)
    return 1000.0 * (1 + bad / len(records))


@pytest.mark.slow  # 1-2.5 min: the same properties, in-process, are proved fast by
# tests/tune/test_sweeper.py (trials scored, penalised and written with the best gains; a rerun
# resumes the study; Pareto fronts) and tests/sweep/test_callback.py (the tune preset composes;
# its expected jobs are trials × draws); this runs them through the real command and launcher
def test_a_small_study_finishes_writes_the_best_gains_and_resumes(sweep_dir):
    sweep = sweep_dir
    first = sweep_cli(sweep, *SHORT_TUNE, "hydra.sweeper.n_trials=4")
    assert first.returncode == 0, first.stdout[-3000:] + first.stderr[-3000:]
    assert "tune finished: 4 trials told" in first.stdout
    study = optuna.load_study(study_name="fr3_impedance", storage=f"sqlite:///{sweep / 'study.db'}")
    assert len(study.trials) == 4
    earlier = {p: p.stat().st_mtime_ns for p in sweep.glob("trial*/metrics.json")}
    assert len(earlier) == 4 * DRAWS

    # the same command with a larger budget continues the study: 2 more trials only
    again = sweep_cli(sweep, *SHORT_TUNE, "hydra.sweeper.n_trials=6")
    assert again.returncode == 0, again.stdout[-3000:] + again.stderr[-3000:]
    assert "budget 6 trials, 2 at a time (4 jobs per batch); 4 told earlier" in again.stdout
    study = optuna.load_study(study_name="fr3_impedance", storage=f"sqlite:///{sweep / 'study.db'}")
    trials = study.get_trials()
    assert [t.state.name for t in trials] == ["COMPLETE"] * 6
    assert len(list(sweep.glob("trial*/metrics.json"))) == 6 * DRAWS
    assert all(p.stat().st_mtime_ns == m for p, m in earlier.items())  # the first jobs untouched

    # every trial's value is what its jobs' metrics.json say
    metric = trials[0].user_attrs["force_metric"]
    for t in trials:
        assert t.value == pytest.approx(recomputed(sweep, t, metric), rel=1e-9)
    feasible = [t for t in trials if t.user_attrs["feasible"]]
    assert feasible, "some short run with FR3 gains in the preset's range docks in both draws"
    best = min(feasible, key=lambda t: t.value)
    assert f"best trial {best.number} ·" in again.stdout

    # the ready file: the FR3 impedance file's keys with the best k and d, and it composes
    gains = yaml.safe_load((sweep / "fr3_impedance.yaml").read_text())
    assert gains["k"] == pytest.approx(best.params["controller.k"], rel=1e-5)
    assert gains["d"] == pytest.approx(best.params["controller.d"], rel=1e-5)
    cfg = make_cfg("robot=fr3", *(f"controller.{k}={v}" for k, v in gains.items()))
    assert cfg.controller.k == gains["k"] and cfg.controller.m == gains["m"]
    assert (sweep / "best_params.yaml").is_file() and (sweep / "trials.csv").is_file()
    assert (sweep / "tuning" / "optimisation_history.png").is_file()
    # the sweep's own summary covers every job (one row each)
    assert len((sweep / "summary.csv").read_text().strip().splitlines()) == 1 + 6 * DRAWS


# --------------------------------------------------------------------------- refused up front


def test_a_search_space_outside_a_settings_range_is_refused_before_anything(tmp_path, monkeypatch, capsys):
    """Before: every trial's jobs failed the run's check (96 failed jobs), and the study exited 0."""
    monkeypatch.chdir(tmp_path)
    code, err = cli_in_process(capsys, "-m", *SHORT_TUNE, "controller.k=interval(-100,1000)")
    assert code == 2
    assert err.startswith("compliant-docking: the sweep is refused; nothing was run or written.")
    assert "controller.k must be a finite number >= 0 N/m; got -100.0." in err
    assert (
        "[the search space reaches this job: controller.d=30.0 controller.k=-100.0, draw task.misalignment.seed=0]"
        in err
    )
    assert not (tmp_path / "runs").exists()  # no directory, no .finished_jobs


@pytest.mark.parametrize("content", [b"", b"not a database at all" * 100])
def test_a_corrupt_study_is_refused_clearly_and_left_as_it_is(tmp_path, monkeypatch, capsys, content):
    """Before: the same command started runs/tune/<study>_2 without a word."""
    monkeypatch.chdir(tmp_path)
    study_dir = tmp_path / "runs" / "tune" / "fr3_impedance"
    study_dir.mkdir(parents=True)
    (study_dir / "study.db").write_bytes(content)
    (study_dir / "multirun.yaml").write_text("hydra:\n  sweeper:\n    study_name: fr3_impedance\n")
    code, err = cli_in_process(capsys, "-m", *SHORT_TUNE)
    assert code == 2
    assert f"the study storage {study_dir / 'study.db'} cannot be read (" in err
    assert "move it away to start the study afresh" in err
    assert (study_dir / "study.db").read_bytes() == content
    assert sorted(p.name for p in study_dir.iterdir()) == ["multirun.yaml", "study.db"]
    assert sorted(p.name for p in study_dir.parent.iterdir()) == ["fr3_impedance"]  # no fr3_impedance_2


def test_a_study_directory_holding_something_else_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    other = tmp_path / "runs" / "tune" / "fr3_impedance"
    other.mkdir(parents=True)
    (other / "notes.txt").write_text("mine")
    code, err = cli_in_process(capsys, "-m", *SHORT_TUNE)
    assert code == 2 and "hydra.sweep.dir=runs/tune/fr3_impedance holds something other than" in err
    assert sorted(p.name for p in other.parent.iterdir()) == ["fr3_impedance"]


@pytest.mark.slow
def test_the_same_command_continues_the_study_in_its_directory(tmp_path):
    """The documented command, twice, with the preset's own directory (runs/tune/<study>):
    the second continues the study there. Before: it started runs/tune/<study>_2."""
    import os
    import subprocess
    import sys

    from tests.helpers import REPO_ROOT

    def tune(n_trials: int) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "compliant_docking", "-m", *SHORT_TUNE, f"hydra.sweeper.n_trials={n_trials}",
             "hydra.sweeper.parallel_trials=1", "hydra.sweeper.draws={task.misalignment.seed:'range(1)'}",
             "hydra/launcher=basic"],
            cwd=tmp_path, capture_output=True, text=True, timeout=600,
            env={**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONPATH": str(REPO_ROOT)},
        )  # fmt: skip

    first = tune(1)
    assert first.returncode == 0, first.stderr[-3000:]
    again = tune(2)
    assert again.returncode == 0, again.stderr[-3000:]
    assert "study fr3_impedance in runs/tune/fr3_impedance/study.db" in again.stdout
    assert "1 told earlier" in again.stdout
    assert sorted(p.name for p in (tmp_path / "runs" / "tune").iterdir()) == ["fr3_impedance"]
    study = optuna.load_study(
        study_name="fr3_impedance", storage=f"sqlite:///{tmp_path / 'runs/tune/fr3_impedance/study.db'}"
    )
    assert len(study.trials) == 2
