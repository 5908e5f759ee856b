"""Closed-loop statics of the impedance controllers (the F/T chain: tests/sim/test_sensor.py;
transients: tests/control/test_transients.py)."""

import numpy as np
import pinocchio as pin
import pytest

from compliant_docking.sim.simulate import prepare
from tests.helpers import make_cfg, push_at_tcp

FREE_SPACE = ("target=none", "trajectory=hold", "task.init_pos=[0.55,0.0,0.35]", "task.settle_time=0.0")


@pytest.mark.parametrize("physics", ["space", "earth"])
def test_constant_push_settles_at_force_over_stiffness(physics):
    sim = prepare(make_cfg(*FREE_SPACE, "trajectory.duration=10", f"physics={physics}"))
    start = sim.scene.arm.tcp_placement(sim.q0)
    force = np.array([2.0, -1.0, 1.5])
    push_at_tcp(sim, force=force)
    sim.run()
    end = sim.scene.arm.tcp_placement(sim.data.qpos)
    displacement = end.translation - start.translation
    expected = force / float(sim.cfg.controller.k)
    assert np.linalg.norm(displacement - expected) < 0.02 * np.linalg.norm(expected)
    # a force at the TCP produces no rotation
    assert np.linalg.norm(pin.log3(start.rotation.T @ end.rotation)) < 1e-3


@pytest.mark.parametrize("controller", ["impedance", "se3_lie"])
def test_constant_moment_settles_at_moment_over_rotational_stiffness(controller):
    sim = prepare(make_cfg(*FREE_SPACE, "trajectory.duration=4", f"controller={controller}"))
    gains = sim.cfg.controller
    k_rot = float(gains.k_rot) if controller == "impedance" else float(gains.K_diag[3])
    start = sim.scene.arm.tcp_placement(sim.q0)
    moment = np.array([0.3, 0.2, -0.4])
    push_at_tcp(sim, moment=moment)
    sim.run()
    end = sim.scene.arm.tcp_placement(sim.data.qpos)
    rotation = pin.log3(end.rotation @ start.rotation.T)  # world axes
    expected = moment / k_rot
    assert np.linalg.norm(rotation - expected) < 0.03 * np.linalg.norm(expected)
    assert np.linalg.norm(end.translation - start.translation) < 1e-4


def test_without_force_feedback_the_arm_is_stiffer_than_k():
    """Feedback off: the arm's own task inertia replaces the commanded one, so F/k no longer holds.

    This is what makes the push test above able to fail."""
    sim = prepare(make_cfg(*FREE_SPACE, "trajectory.duration=10", "controller.use_force_feedback=false"))
    start = sim.scene.arm.tcp_placement(sim.q0)
    push_at_tcp(sim, force=(2.0, 0.0, 0.0))
    sim.run()
    dx = sim.scene.arm.tcp_placement(sim.data.qpos).translation[0] - start.translation[0]
    assert abs(dx - 2.0 / float(sim.cfg.controller.k)) > 0.1 * 2.0 / float(sim.cfg.controller.k)
