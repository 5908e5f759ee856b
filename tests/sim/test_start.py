"""The state before the first step (sim.simulate.start_held): the arm at rest at its start
posture, held against gravity, so the first sensor reading is that of a held arm."""

import mujoco
import numpy as np
import pytest

from compliant_docking.sim.sensor import wrench_reader
from compliant_docking.sim.simulate import prepare
from tests.helpers import make_cfg


@pytest.mark.parametrize("robot", ["iiwa14", "fr3"])
def test_first_wrench_under_gravity_is_no_force(robot):
    """Under Earth gravity the first reading (the controller's input at t = 0, row 0 of the
    time series) is that of the arm held at rest: the payload-compensated tool reads zero
    (1e-9 N: round-off of the weight compensation, measured 8e-15 N). Without the holding
    torque the same forward pass leaves the arm in free fall and the sensor reads minus the
    tool's weight (≈ 3.6 N), which the check below shows is what it would catch."""
    sim = prepare(make_cfg(f"robot={robot}", "physics=earth", "task.progress=false"))
    model, data = sim.scene.model, sim.data
    wrench = np.zeros(6)
    read = wrench_reader(sim.scene, data, wrench)
    read()
    assert np.abs(wrench).max() < 1e-9
    assert np.abs(data.qacc).max() < 1e-9  # held: at rest and not accelerating
    data.ctrl[:] = 0.0  # the old start: no torque in the first forward pass
    mujoco.mj_forward(model, data)
    read()
    assert np.linalg.norm(wrench[:3]) > 2.0


def test_zero_gravity_start_is_unchanged():
    """In zero gravity the holding torque is zero: the first pass has no command at all."""
    sim = prepare(make_cfg("physics=space", "task.progress=false"))
    assert not sim.data.ctrl.any() and not sim.data.qacc.any()
