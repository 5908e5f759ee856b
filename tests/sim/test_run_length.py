"""The run length under a bounded reference (sim/simulate.py, docs/planners.md): every step
the reference holds the planner extends the run by one step, so the settle time after the
planner's end is the configured one; never held, the run is the planned one; the extension
is capped by ``task.max_hold``."""

import numpy as np
import pytest

from compliant_docking.run.runner import execute
from compliant_docking.sim.simulate import prepare
from tests.helpers import make_cfg

SETTLE = ("task.settle_time=0.1", "task.press_duration=0.1", "task.progress=false")
SHORT = ("trajectory.duration=0.2", *SETTLE)


def test_a_held_reference_extends_the_run_by_exactly_the_held_steps():
    # a 0.18 m stroke in 0.6 s against a 5 mm bound: the plug lags, the reference holds
    # (about 1.9 s) and the plug docks
    sim = prepare(
        make_cfg("trajectory.duration=0.6", *SETTLE, "trajectory.lead_limit=0.005", "task.max_hold=3.0")
    )
    sim.run()
    held = sim.lead.held_steps
    assert 0 < held < sim.extra_steps  # held, not capped
    assert sim.planned_steps == round(0.7 / sim.scene.model.opt.timestep)
    assert sim.steps_done == sim.telemetry.count == sim.planned_steps + held
    # the planner's time at the last step is the planned run's last step: the planned motion
    # ended settle_time before the run's end, as configured
    assert sim.lead.index == sim.planned_steps - 1
    assert sim.finished and not sim.extension_capped


def test_a_reference_never_held_keeps_the_planned_length():
    sim = prepare(make_cfg(*SHORT, "trajectory.lead_limit=10.0"))  # a bound no plug reaches
    sim.run()
    assert sim.lead.held_steps == 0
    assert sim.steps_done == sim.telemetry.count == sim.planned_steps
    open_loop = prepare(make_cfg(*SHORT, "trajectory.lead_limit=null"))
    assert open_loop.extra_steps == 0 and open_loop.n_steps == sim.planned_steps


def test_the_extension_is_capped_by_max_hold(tmp_path):
    # a 0.18 m stroke in 0.2 s against a 10 µm bound: held far longer than 20 ms
    cfg = make_cfg(*SHORT, "trajectory.lead_limit=1e-5", "task.max_hold=0.02")
    record = execute(cfg, tmp_path, figures=False, echo=False)
    dt = 0.001
    assert record["reference_held_steps"] * dt > 0.02  # held longer than the cap
    assert record["run_extended_s"] == pytest.approx(0.02)
    assert record["run_extension_capped"] is True
    assert record["steps"] == round(0.32 / dt)
    assert "task.max_hold" in record["run_notes"]


def test_max_hold_must_not_be_negative():
    with pytest.raises(Exception, match="max_hold"):
        prepare(make_cfg(*SHORT, "task.max_hold=-1.0"))


def test_a_fixed_run_length_is_not_extended():
    sim = prepare(make_cfg(*SHORT, "trajectory.lead_limit=1e-5", "task.duration=0.3"))
    sim.run()
    assert sim.lead.held_steps > 0 and sim.extra_steps == 0 and not sim.extension_capped
    assert sim.steps_done == round(0.3 / sim.scene.model.opt.timestep)
    assert np.isclose(sim.duration, 0.3)


@pytest.mark.slow
def test_a_comparison_draw_held_for_seconds_docks(tmp_path):
    """An FR3 comparison draw whose reference is held 3.5 s: before the extension the plug
    seated 0.8 s before the end of the planned run and the steady window saw it arrive."""
    cfg = make_cfg(
        "robot=fr3",
        "controller=impedance",
        "trajectory=quintic",
        "task.misalignment.seed=4",
        "+experiment=controller_comparison",
        "task.progress=false",
    )
    record = execute(cfg, tmp_path, figures=False, echo=False)
    dt = cfg.physics.timestep
    assert record["reference_held_steps"] * dt > 3.0 and not record["run_extension_capped"]
    assert record["run_extended_s"] == pytest.approx(record["reference_held_steps"] * dt)
    assert record["steps"] == round(18.0 / dt) + record["reference_held_steps"]
    assert record["success"] is True and record["steady_contact_events_per_s"] == 0.0
