"""Closed-loop properties of the impedance controller and the F/T measurement chain."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from compliant_docking.sim.sensor import wrench_reader
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


@pytest.mark.parametrize("physics", ["space", "earth"])
def test_wrench_reader_returns_the_applied_wrench_at_the_tcp(physics):
    """Static: the arm is held by inverse dynamics; the sensor chain recovers the push,
    with the sign of a wrench ON the tool, the moment about the TCP, and the tool's
    weight compensated."""
    sim = prepare(make_cfg(*FREE_SPACE, f"physics={physics}"))
    model, data = sim.scene.model, sim.data
    force, moment = np.array([1.0, -2.0, 3.0]), np.array([0.1, 0.05, -0.2])
    push_at_tcp(sim, force=force, moment=moment)
    model.actuator_ctrlrange[:] = [-1e6, 1e6]
    # torques that hold the arm still against gravity and the push
    pushed = np.zeros(model.nv)
    body = sim.scene.tool_body
    mujoco.mj_applyFT(
        model,
        data,
        data.xfrc_applied[body, :3].copy(),
        data.xfrc_applied[body, 3:].copy(),
        data.xipos[body].copy(),
        body,
        pushed,
    )
    data.ctrl[:] = data.qfrc_bias - pushed
    mujoco.mj_step(model, data)
    assert np.abs(data.qvel).max() < 1e-6
    out = np.zeros(6)
    wrench_reader(sim.scene, data, out)()
    assert np.allclose(out[:3], force, atol=1e-6)
    assert np.allclose(out[3:], moment, atol=1e-6)
