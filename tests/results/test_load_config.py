"""load_runs carries the whole experiment: every leaf of each job's composed config as a
dotted column (single runs, sweeps, nested trees), the drawn misalignment with units, and
configurations that still differ only in what was chosen or overridden."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from omegaconf import OmegaConf

from compliant_docking.results import configuration_keys, load_runs
from compliant_docking.results.load import config_leaves
from compliant_docking.run.rundir import flatten
from tests.helpers import make_cfg


def job(path: Path, *overrides: str, record: dict | None = None, config: bool = True) -> Path:
    """A job directory as Hydra and the runner leave it (without simulating): the composed
    config of ``overrides`` in .hydra/config.yaml, the overrides, a metrics.json."""
    (path / ".hydra").mkdir(parents=True)
    (path / ".hydra" / "overrides.yaml").write_text("".join(f"- {o}\n" for o in overrides))
    cfg = make_cfg(*overrides)
    if config:  # as Hydra writes it: unresolved (target.geometry.plug_radius is ${…})
        (path / ".hydra" / "config.yaml").write_text(OmegaConf.to_yaml(cfg))
    from compliant_docking.sim.misalignment import record_for
    from compliant_docking.sim.settings import sim_settings

    metrics = {
        "status": "ok",
        "error": None,
        "success": True,
        "robot": cfg.robot.name,
        "controller": cfg.controller.name,
        "trajectory": cfg.trajectory.name,
        "peak_axial_force_N": 1.0,
        **record_for(sim_settings(cfg)),
        **(record or {}),
    }
    (path / "metrics.json").write_text(json.dumps(metrics))
    return path


def test_a_single_run_has_every_leaf_of_its_resolved_config(tmp_path):
    run = job(tmp_path / "run", "controller.k=123")
    df = load_runs(run)
    cfg = make_cfg("controller.k=123")
    leaves = config_leaves(run)
    assert len(leaves) > 60 and set(leaves) <= set(df.columns)
    row = df.iloc[0]
    assert row["controller.k"] == 123.0 and row["physics.timestep"] == cfg.physics.timestep
    assert row["target.geometry.radial_clearance"] == cfg.target.geometry.radial_clearance
    assert row["target.geometry.plug_radius"] == cfg.tool.geometry.radius  # the interpolation, resolved
    assert json.loads(row["task.stroke"]) == list(cfg.task.stroke)  # a list: its JSON text
    assert row["controller"] == "impedance" and row["controller.name"] == "impedance"  # no clash
    assert row["overridden"] == "controller.k"
    for unit_key in ("misalignment_x_m", "misalignment_lateral_m", "misalignment_tilt_deg"):
        assert pd.api.types.is_float_dtype(df[unit_key])  # drawn values, unit in the name


def test_a_sweep_has_the_config_of_every_job_and_its_drawn_misalignment(tmp_path):
    sweep = tmp_path / "sweep"
    ranges = ("task.misalignment.x_range=[-0.002,0.002]", "task.misalignment.tilt_deg_range=[0,1]")
    for i, (robot, seed) in enumerate([("iiwa14", 0), ("iiwa14", 1), ("fr3", 0), ("fr3", 1)]):
        job(sweep / f"{i}_robot={robot}", f"robot={robot}", f"task.misalignment.seed={seed}", *ranges)
    df = load_runs(sweep)
    assert list(df["robot.name"]) == ["iiwa14", "iiwa14", "fr3", "fr3"]
    assert df["task.misalignment.x_range"].map(json.loads).tolist() == [[-0.002, 0.002]] * 4
    # the same seed, the same draw, whatever the robot (common random numbers)
    draws = df.set_index(["robot", "task.misalignment.seed"])["misalignment_x_m"]
    assert draws["iiwa14", 0] == draws["fr3", 0] != draws["iiwa14", 1]
    # the robot's gain file changes controller.k and the robot's own leaves, but the
    # configurations differ in the robot only (the seeds repeat them)
    assert df["controller.k"].nunique() == 2 and df["robot.mjcf"].nunique() == 2
    assert configuration_keys(df) == ["robot"]


def test_nested_trees_mix_jobs_with_and_without_a_config(tmp_path):
    job(tmp_path / "runs" / "2025-01-01" / "10-00-00_single", "physics=earth")
    job(tmp_path / "runs" / "multirun" / "2025-01-01" / "11-00-00" / "0_x", "controller=hqp")
    job(tmp_path / "runs" / "old", config=False)  # a run made by runner.execute alone
    df = load_runs(tmp_path / "runs").set_index("job")
    assert df.loc["10-00-00_single", "physics.name"] == "earth"
    assert df.loc["0_x", "controller.K0"].startswith("[")
    assert pd.isna(df.loc["old", "physics.name"]) and df.loc["old", "peak_axial_force_N"] == 1.0


def test_a_config_leaf_named_like_a_metric_gets_a_prefix(tmp_path):
    path = job(tmp_path / "j", record={"figures": "drawn"})  # a made-up metrics key
    df = load_runs(path)
    assert df.iloc[0]["figures"] == "drawn"  # metrics.json keeps its name
    assert "config.figures" in df.columns  # the config's top-level `figures` key


@pytest.mark.parametrize("value", ["${tool.geometry.radius}", "${now:%H}"])
def test_only_interpolations_of_the_config_itself_are_resolved(tmp_path, value):
    path = tmp_path / "j"
    (path / ".hydra").mkdir(parents=True)
    (path / ".hydra" / "config.yaml").write_text(f"tool:\n  geometry:\n    radius: 0.01\na: '{value}'\n")
    expected = 0.01 if value.startswith("${tool") else value  # a resolver stays as written
    assert config_leaves(path)["a"] == expected


def test_a_config_is_flattened_by_one_rule():
    """Every reader's rule (load_runs, MLflow's parameters, sweep and tuning params): each
    leaf under its dotted key, nested and dotted keys alike, lists as values, an empty
    mapping without a leaf, an OmegaConf node as a dict."""
    nested = {"controller": {"k": 1.5, "gains": [1, 2], "extra": {}}, "task.seed": 3}
    expected = {"controller.k": 1.5, "controller.gains": [1, 2], "task.seed": 3}
    assert flatten(nested) == expected
    assert flatten({"controller.k": 1.5, "controller": {"gains": [1, 2]}, "task": {"seed": 3}}) == expected
    assert flatten(OmegaConf.create(nested)) == expected
    assert flatten(None) == {}
