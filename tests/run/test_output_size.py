"""What a run saves beside its metrics (``output.*``, docs/run_directory.md "Output size"):
the default keeps every step in float64; float32, every N-th step and metrics-only save
less, and the metrics stay those of the full series."""

import json

import numpy as np
import pandas as pd
import pytest
from omegaconf import OmegaConf

from compliant_docking.run import rundir
from compliant_docking.run.runner import execute
from tests.helpers import make_cfg

#: a short run in free space (0.3 s, 300 steps): the saving is what is tested
SHORT = ("target=none", "trajectory=hold", "task.init_pos=[0.55,0.0,0.35]", "task.settle_time=0.0")
SHORT += ("trajectory.duration=0.3", "task.progress=false")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The same run saved in full and metrics only: {name: (run directory, record)}."""
    root = tmp_path_factory.mktemp("output")
    options = {"default": (), "metrics_only": ("output.timeseries=false",)}
    return {
        name: (root / name, execute(make_cfg(*SHORT, *extra), root / name, figures=False, echo=False))
        for name, extra in options.items()
    }


def saved(runs, tmp_path, **output) -> pd.DataFrame:
    """The default run's full series saved with ``output`` settings and read back."""
    full = pd.read_parquet(runs["default"][0] / rundir.TIMESERIES_FILE)
    settings = OmegaConf.create({"timeseries": True, "precision": "float64", "every": 1, **output})
    rundir.write_timeseries(tmp_path, rundir.saved_timeseries(full, settings))
    return pd.read_parquet(tmp_path / rundir.TIMESERIES_FILE)


def test_the_default_saves_every_step_in_full_precision(runs):
    run_dir, record = runs["default"]
    ts = pd.read_parquet(run_dir / rundir.TIMESERIES_FILE)
    assert len(ts) == record["steps"] == record["timeseries_rows"] == 300
    assert (ts.dtypes == np.float64).sum() > 20 and not (ts.dtypes == np.float32).any()


def test_float32_rounds_each_value_once_and_keeps_the_rows(runs, tmp_path):
    full = pd.read_parquet(runs["default"][0] / rundir.TIMESERIES_FILE)
    half = saved(runs, tmp_path, precision="float32")
    floats = full.select_dtypes("float64").columns
    assert list(half.columns) == list(full.columns) and (half[floats].dtypes == np.float32).all()
    assert np.array_equal(half[floats].to_numpy(), full[floats].to_numpy().astype(np.float32), equal_nan=True)
    assert half.drop(columns=floats).equals(full.drop(columns=floats))  # ints and flags as they were


def test_every_nth_step_is_the_full_series_rows_0_n_2n(runs, tmp_path):
    full = pd.read_parquet(runs["default"][0] / rundir.TIMESERIES_FILE)
    thin = saved(runs, tmp_path, every=7)
    assert len(thin) == 43  # ceil(300 / 7)
    assert (
        rundir.saved_timeseries(
            full, OmegaConf.create({"timeseries": True, "precision": "float64", "every": 1})
        )
        is full
    )
    assert thin.equals(full.iloc[::7].reset_index(drop=True))
    assert thin["t"].iloc[1] == pytest.approx(7 * 0.001)


def test_metrics_only_writes_no_time_series_and_the_same_metrics(runs):
    run_dir, record = runs["metrics_only"]
    assert not (run_dir / rundir.TIMESERIES_FILE).exists() and record["timeseries_rows"] is None
    assert (run_dir / rundir.METRICS_FILE).is_file() and (run_dir / rundir.SUMMARY_FILE).is_file()
    reference = runs["default"][1]
    for name, (_, other) in runs.items():  # the metrics come from the full series in memory
        for key in ("peak_axial_force_N", "tracking_rms_pos_m", "steps", "success", "config_hash"):
            assert other.get(key) == reference.get(key), (name, key)


def test_each_saved_run_passes_the_resume_check_and_a_thinned_file_does_not(runs, tmp_path):
    for run_dir, _ in runs.values():
        record = json.loads((run_dir / rundir.METRICS_FILE).read_text())
        assert rundir.artefact_problem(run_dir, record) is None, run_dir
    run_dir, _ = runs["default"]
    record = json.loads((run_dir / rundir.METRICS_FILE).read_text())
    claimed = {**record, "timeseries_rows": 43}
    assert rundir.artefact_problem(run_dir, claimed) == (
        "timeseries.parquet has 300 rows, metrics.json says 43 rows saved"
    )


def test_the_output_settings_are_checked(tmp_path):
    from compliant_docking.config.validate import check

    with pytest.raises(Exception, match="float16"):
        make_cfg("output.precision=float16")
    assert any("output.every" in p for p in check(make_cfg("output.every=0")))
