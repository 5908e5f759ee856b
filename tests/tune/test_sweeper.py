"""The tuning sweeper's ask-and-tell loop, on a stand-in launcher that writes each job's
metrics.json from a known rule: batches, penalties, a launcher that fails, the outputs,
and resuming a study (a raised budget, a trial left running)."""

from __future__ import annotations

import json
from pathlib import Path

import optuna
import pytest
import yaml
from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from omegaconf import OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.config import register_schemas
from compliant_docking.sweep.session import SweepSession
from compliant_docking.tune.sweeper import TuningSweeper, job_name

DRAWS = 2


class RuleLauncher:
    """Writes each job's metrics.json as a run would: force = 10⁴/k plus the draw's seed,
    seated after 14 s (+ the seed), docked except draw 1 of trials 2, 5, 8, …
    ``fail_batches``: batch numbers (0-based) whose launch raises, as joblib does when a
    worker process dies."""

    def __init__(self, sweep_dir: Path, fail_batches=()):
        self.sweep_dir, self.fail_batches, self.batches = sweep_dir, set(fail_batches), []

    def launch(self, job_overrides, initial_job_idx):
        self.batches.append([list(o) for o in job_overrides])
        for overrides in job_overrides:
            values = dict(o.split("=", 1) for o in overrides)
            job_dir = self.sweep_dir / values["hydra.sweep.subdir"]
            job_dir.mkdir(parents=True)  # a job directory is never written twice
            if len(self.batches) - 1 in self.fail_batches:
                continue  # the worker died before the job wrote its metrics.json
            k, seed = float(values["controller.k"]), int(values["task.misalignment.seed"])
            trial = int(values["hydra.sweep.subdir"][len("trial") :].split("_")[0])
            docked = not (trial % 3 == 2 and seed == 1)
            record = {
                "status": "ok",
                "success": docked,
                "gate_failures": None if docked else "seat depth error 2 mm > 1 mm",
                "first_strike_force_N": 1e4 / k + seed,  # the objective's force
                "peak_axial_force_N": 1e4 / k + seed,  # its fallback
                "docking_time_s": 14.0 + seed,
            }
            (job_dir / "metrics.json").write_text(json.dumps(record))
        if len(self.batches) - 1 in self.fail_batches:
            raise RuntimeError("A worker process managed by the executor was unexpectedly terminated.")
        return [None] * len(job_overrides)


def make_sweeper(
    sweep_dir: Path, n_trials: int = 6, objective: str = "mean_force", **launcher
) -> TuningSweeper:
    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose(
            config_name="config",
            overrides=["+experiment=tune", f"hydra.sweep.dir={sweep_dir}"],
            return_hydra_config=True,
        )
    node = cfg.hydra.sweeper
    sweeper = TuningSweeper(
        study_name=str(node.study_name),
        storage=None,
        n_trials=n_trials,
        parallel_trials=2,
        params={"controller.k": "interval(100, 1000)", "controller.d": "interval(30, 300)"},
        draws={"task.misalignment.seed": f"range({DRAWS})"},
        objective=OmegaConf.merge(node.objective, {"name": objective}),
        sampler={"name": "random", "seed": 0, "n_startup_trials": 8},
    )
    sweeper.config = cfg
    sweeper.launcher = RuleLauncher(sweep_dir, **launcher)
    sweeper._validate = lambda *args: None  # composing jobs needs Hydra's loader: the CLI test does it
    return sweeper


@pytest.fixture
def no_figures(monkeypatch):
    """Skip drawing (about a second a study) where a test does not look at the figures."""
    from compliant_docking.tune import figures

    monkeypatch.setattr(figures, "plot_history", lambda *a, **k: [])
    monkeypatch.setattr(figures, "plot_pareto", lambda *a, **k: [])


def load(sweep_dir: Path):
    return optuna.load_study(study_name="fr3_impedance", storage=f"sqlite:///{sweep_dir / 'study.db'}")


def feasible(trial) -> bool:
    return trial.number % 3 != 2


def expected_value(trial) -> float:
    """The rule's objective: the mean force over the draws when both docked, else the
    penalty for 1 of 2 draws not docking."""
    k = trial.params["controller.k"]
    return sum(1e4 / k + s for s in range(DRAWS)) / DRAWS if feasible(trial) else 1000.0 * 1.5


def test_trials_run_in_batches_are_scored_penalised_and_written(sweep_dir, capsys):
    sweeper = make_sweeper(sweep_dir)
    sweeper.sweep(["+experiment=tune"])
    batches = sweeper.launcher.batches
    assert [len(b) for b in batches] == [4, 4, 4]  # 2 trials × 2 draws at a time
    assert batches[0][0][-1] == f"hydra.sweep.subdir={job_name(0, 0)}"
    assert "+experiment=tune" in batches[0][0] and "task.misalignment.seed=1" in batches[0][1]

    study = load(sweep_dir)
    trials = study.get_trials()
    assert [t.state.name for t in trials] == ["COMPLETE"] * 6
    for t in trials:
        assert t.value == pytest.approx(expected_value(t))
        assert t.user_attrs["feasible"] == feasible(t)
        assert t.user_attrs["jobs"] == [job_name(t.number, 0), job_name(t.number, 1)]
    assert trials[2].user_attrs["problems"] == ["trial002_draw1: not docked: seat depth error 2 mm > 1 mm"]

    best = min((t for t in trials if t.user_attrs["feasible"]), key=lambda t: t.value)
    record = yaml.safe_load((sweep_dir / "best_params.yaml").read_text())
    assert record["best"][0]["trial"] == best.number
    assert record["best"][0]["params"]["controller.k"] == pytest.approx(best.params["controller.k"], rel=1e-5)
    ready = (sweep_dir / "fr3_impedance.yaml").read_text()
    assert ready.startswith("# @package controller\n")
    gains = yaml.safe_load(ready)
    current = yaml.safe_load((CONF_DIR / "robot_controller" / "fr3_impedance.yaml").read_text())
    assert set(gains) == set(current)  # the file's keys, k and d tuned, the others kept
    assert gains["k"] == pytest.approx(best.params["controller.k"], rel=1e-5)
    assert gains["m"] == current["m"] and gains["m_rot"] == current["m_rot"]

    frame = __import__("pandas").read_csv(sweep_dir / "trials.csv")
    assert len(frame) == 6 and {"force_N", "feasible", "controller.k", "docked"} <= set(frame.columns)
    assert (sweep_dir / "trials.parquet").is_file()
    assert (sweep_dir / "tuning" / "optimisation_history.png").is_file()
    out = capsys.readouterr().out
    assert f"best trial {best.number} · controller.k=" in out and "PENALISED" in out


def test_a_failing_launcher_penalises_its_batch_and_the_study_goes_on(sweep_dir, capsys, no_figures):
    sweeper = make_sweeper(sweep_dir, n_trials=4, fail_batches=[0])
    sweeper.sweep([])
    trials = load(sweep_dir).get_trials()
    assert [t.state.name for t in trials] == ["COMPLETE"] * 4
    for t in trials[:2]:  # the first batch: no result, penalised with the launcher's error
        assert t.value == pytest.approx(2000.0) and "worker process" in t.user_attrs["launcher_error"]
        assert t.user_attrs["problems"][0].startswith(f"{job_name(t.number, 0)}: failed: interrupted")
        # every job directory ends with a metrics.json (an "interrupted" failed record)
        assert json.loads((sweep_dir / job_name(t.number, 0) / "metrics.json").read_text())["interrupted"]
    for t in trials[2:]:
        assert t.value == pytest.approx(expected_value(t))
    assert "the launcher failed for trials [0, 1]" in capsys.readouterr().out


def test_a_rerun_resumes_the_study_with_a_raised_budget_and_retries_an_interrupted_trial(
    sweep_dir, capsys, no_figures
):
    make_sweeper(sweep_dir, n_trials=4).sweep([])
    # a command stopped while trial 4 ran: it is left RUNNING in the study
    study = load(sweep_dir)
    left = study.ask({"controller.k": optuna.distributions.FloatDistribution(100, 1000)})
    left_k = left.params["controller.k"]
    capsys.readouterr()

    sweeper = make_sweeper(sweep_dir, n_trials=6)
    sweeper.sweep([])
    out = capsys.readouterr().out
    assert "4 told earlier, trials [4] were interrupted and are asked again" in out
    trials = load(sweep_dir).get_trials()
    assert [t.state.name for t in trials] == ["COMPLETE"] * 4 + ["FAIL"] + ["COMPLETE"] * 2
    assert trials[5].params["controller.k"] == left_k and trials[5].user_attrs["retry_of"] == 4
    assert len(sweeper.launcher.batches) == 1  # only the two missing trials ran
    # the resumed sampler was reseeded: no repeat of the first run's samples
    first = {round(t.params["controller.k"], 9) for t in trials[:4]}
    assert round(trials[6].params["controller.k"], 9) not in first


def test_a_rerun_with_other_draws_is_refused_before_any_job(sweep_dir, capsys, no_figures):
    make_sweeper(sweep_dir, n_trials=2).sweep([])
    sweeper = make_sweeper(sweep_dir, n_trials=4)
    sweeper.draws = {"task.misalignment.seed": "range(3)"}
    with SweepSession.open(), pytest.raises(SystemExit) as stop:
        sweeper.sweep([])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("compliant-docking: the tuning study is refused; nothing was run or written.")
    assert "started with another definition (draws:" in err
    assert not sweeper.launcher.batches


def test_two_objectives_give_a_pareto_front_and_a_gain_file_per_optimal_trial(sweep_dir):
    make_sweeper(sweep_dir, n_trials=6, objective="force_time").sweep([])
    trials = [t for t in load(sweep_dir).get_trials() if t.user_attrs["feasible"]]
    # the rule makes time independent of the gains: the front is the lowest-force trial
    best = min(trials, key=lambda t: t.values[0])
    record = yaml.safe_load((sweep_dir / "best_params.yaml").read_text())
    assert [b["trial"] for b in record["best"]] == [best.number]
    assert record["best"][0]["time_s"] == pytest.approx(14.5)
    assert (sweep_dir / "pareto" / f"trial{best.number:03d}" / "fr3_impedance.yaml").is_file()
    assert (sweep_dir / "tuning" / "pareto_front.png").is_file()
