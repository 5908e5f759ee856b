"""The controller's model against the plant (compliant_docking/sim/model_error.py) and the
plant's contact draws (compliant_docking/sim/dynamics.py): the static offset a payload error
gives under impedance, the draws' reproducibility, and their record in metrics.json."""

import numpy as np
import pytest

from compliant_docking.results import load_runs
from compliant_docking.run.runner import execute
from compliant_docking.sim import dynamics, model_error
from compliant_docking.sim.geometry.collision import SOCKET_BIT
from compliant_docking.sim.settings import sim_settings
from compliant_docking.sim.simulate import prepare
from tests.helpers import FREE_SPACE_HOLD, make_cfg

#: the arm held in free space under gravity by a stiff, critically damped impedance
#: (k = 400 N/m, m = 10 kg, d = 2√(mk)): settled to 1e-7 m within 2 s
HELD = (*FREE_SPACE_HOLD, "physics=earth", "controller.k=400", "controller.d=126.49", "task.duration=2.0")


@pytest.mark.parametrize("scale", [0.5, 1.5])
def test_a_payload_error_sags_by_its_weight_over_the_stiffness(scale):
    """The controller believes the tool weighs scale × its mass: gravity compensation misses
    Δm·g, which the F/T sensor (payload-compensated with the believed mass) reads as a push,
    and the impedance law settles a push F at F/k: the TCP sits Δm·g/k below (above) the
    reference, Δm = (1 − scale)·m, and does not move sideways."""
    cfg = make_cfg(*HELD, f"model_error.tool_mass_scale={scale}")
    sim = prepare(cfg)
    assert sim.arm is not None and sim.arm.tool.mass == pytest.approx(scale * sim.scene.arm.tool.mass)
    sim.run()
    last = sim.telemetry.count - 1
    offset = sim.scene.arm.tcp_placement(sim.telemetry.q[last]).translation - sim.reference.pos[last]
    delta_m = (1.0 - scale) * sim.scene.arm.tool.mass
    predicted = delta_m * -9.81 / 400.0
    assert abs(predicted) > 3e-3  # a visible sag
    assert offset[2] == pytest.approx(predicted, rel=1e-3)
    assert np.abs(offset[:2]).max() < 1e-6


def test_the_exact_model_is_the_plant_s():
    """model_error=none: the controller steps the plant's own Pinocchio arm (no second model)."""
    sim = prepare(make_cfg(*FREE_SPACE_HOLD))
    assert sim.arm is None and sim.sensing is None


def test_model_error_draws_are_reproducible_and_independent():
    """Same seed, same draw; a quantity's draw does not depend on which others are drawn
    (its own stream), lies in its range, and another seed draws another value."""
    cfg = make_cfg(
        "model_error.tool_mass_scale_range=[0.8,1.2]",
        "model_error.friction_scale_range=[0.5,1.5]",
        "model_error.tool_com_offset_m_range=[-0.005,0.005]",
        "task.misalignment.seed=11",
    )
    first, again = (
        model_error.draw(sim_settings(cfg).model_error),
        model_error.draw(sim_settings(cfg).model_error),
    )
    assert first == again and first.seed == 11
    assert 0.8 <= first.tool_mass_scale <= 1.2 and 0.5 <= first.friction_scale <= 1.5
    assert max(abs(c) for c in first.tool_com_offset) <= 0.005 and first.link_mass_scale == 1.0
    alone = make_cfg("model_error.tool_mass_scale_range=[0.8,1.2]", "task.misalignment.seed=11")
    assert model_error.draw(sim_settings(alone).model_error).tool_mass_scale == first.tool_mass_scale
    cfg.model_error.seed = 12
    assert model_error.draw(sim_settings(cfg).model_error).tool_mass_scale != first.tool_mass_scale


def test_contact_draws_are_written_on_the_plug_and_socket_geoms():
    """dynamics=randomised: the drawn friction, solref and solimp width are the model's on
    every plug and socket collision geom, the same for the same seed."""
    cfg = make_cfg("dynamics=randomised", "task.misalignment.seed=4")
    draw = dynamics.draw(sim_settings(cfg).dynamics)
    assert draw == dynamics.draw(sim_settings(cfg).dynamics) and not draw.is_nominal
    model = prepare(cfg).scene.model
    colliding = np.flatnonzero((model.geom_contype == SOCKET_BIT) | (model.geom_conaffinity == SOCKET_BIT))
    assert len(colliding) > 10
    np.testing.assert_array_equal(model.geom_friction[colliding, 0], draw.friction)
    np.testing.assert_array_equal(
        model.geom_solref[colliding], [[draw.timeconst, draw.dampratio]] * len(colliding)
    )
    np.testing.assert_array_equal(model.geom_solimp[colliding, 2], draw.width)


def test_the_drawn_errors_are_columns_of_load_runs(tmp_path):
    """metrics.json records the realised model error, sensor and contact draw, so load_runs
    has them as columns (the robustness preset's analysis reads them)."""
    cfg = make_cfg(
        *FREE_SPACE_HOLD,
        "task.duration=0.02",
        "task.progress=false",
        "model_error.tool_mass_scale_range=[0.8,1.2]",
        "sensor=wrist_ft",
        "task.misalignment.seed=3",
    )
    execute(cfg, tmp_path / "run", figures=False, echo=False)
    row = load_runs(tmp_path / "run").iloc[0]
    drawn = model_error.draw(sim_settings(cfg).model_error)
    assert row["model_error_tool_mass_scale"] == drawn.tool_mass_scale
    assert row["model_error_tool_mass_kg"] == pytest.approx(0.3 * (drawn.tool_mass_scale - 1.0))
    assert row["model_error_seed"] == 3
    assert row["sensor_delay_steps"] == 1 and row["sensor_force_bias_N"] > 0.0
