"""+experiment=tune from the command line: a small study (6 trials, 2 at a time, short
runs) that finishes, writes the best gains, and resumes when the command is run again."""

from __future__ import annotations

import json

import optuna
import pytest
import yaml

from tests.helpers import make_cfg, sweep_cli

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
