"""Integral action on the position error (docs/controllers/integral.md): the state's freeze,
clamp and lateral projection, and a constant disturbance removed by every controller."""

import numpy as np
import pytest

from compliant_docking.control.integral import PoseIntegral
from compliant_docking.sim.simulate import prepare
from tests.helpers import FREE_SPACE_HOLD, make_cfg, push_at_tcp

AXIS = np.array([0.0, 0.0, -1.0])
FREE = np.zeros(6)


def test_position_integral_lateral_freeze_and_clamp():
    pi = PoseIntegral(100.0, 2.0, AXIS, 0.001, lateral_only=True, freeze_force=1.0, latch=False)
    for _ in range(1000):  # 1 s of a 1 mm error along x and 5 mm along the axis
        force = np.array(pi.update(np.array([0.001, 0.0, -0.005]), FREE))
    assert np.allclose(force, [100.0 * 0.001 * 1.0, 0.0, 0.0])  # ki ∫e dt, axis ignored
    # in contact (‖f‖ > 1 N) it holds its value
    pressed = np.array([0.0, 0.0, 3.0, 0.0, 0.0, 0.0])
    assert np.allclose(pi.update(np.array([0.05, 0.0, 0.0]), pressed), force)
    assert pi.frozen_steps == 1
    # clamped at 2 N without winding up: the state is scaled back with the force
    for _ in range(100_000):
        force = np.array(pi.update(np.array([0.01, 0.0, 0.0]), FREE))
    assert np.linalg.norm(force) == pytest.approx(2.0)
    force = pi.update(np.array([-0.01, 0.0, 0.0]), FREE)  # a reversed error acts at once
    assert np.linalg.norm(force) < 2.0
    every_axis = PoseIntegral(100.0, 2.0, AXIS, 0.001, lateral_only=False, freeze_force=1.0, latch=False)
    assert every_axis.update(np.array([0.0, 0.0, -0.005]), FREE)[2] == pytest.approx(-0.0005)
    assert every_axis.diagnostics()["integral_final_force_N"] == pytest.approx(0.0005)


def test_latched_integral_cannot_wind_up_in_a_fall():
    """A scripted force history: free space with a 1 mm offset (the integral learns it), a
    contact (5 N: frozen), then the contact lost with a 10 mm error, as when a plug stuck on
    the chamfer falls towards the seat. Latched, the integral keeps the value it had at the
    contact; the research code's freeze winds it up to the clamp in the fall."""
    contact = np.array([0.0, 0.0, 5.0, 0.0, 0.0, 0.0])
    history = [(np.array([0.001, 0.0, 0.0]), FREE)] * 200  # 0.2 s free, 1 mm off
    history += [(np.array([0.001, 0.0, 0.0]), contact)] * 10  # first contact
    history += [(np.array([0.0, 0.0, -0.010]), FREE)] * 500  # the fall: 10 mm behind, no force
    forces = {}
    for latch in (True, False):
        pi = PoseIntegral(2000.0, 10.0, AXIS, 0.001, lateral_only=False, freeze_force=1.0, latch=latch)
        trace = [np.array(pi.update(e, w)) for e, w in history]
        forces[latch] = trace
    at_contact = forces[True][200]
    assert np.allclose(at_contact, [2000.0 * 0.001 * 0.2, 0.0, 0.0])  # ki · 1 mm · 0.2 s = 0.4 N
    assert all(np.array_equal(f, at_contact) for f in forces[True][200:])
    assert np.linalg.norm(forces[False][-1]) == pytest.approx(10.0)  # wound up to the clamp


def test_position_integral_rejects_meaningless_settings():
    with pytest.raises(ValueError, match="integral_gain"):
        PoseIntegral(0.0, 2.0, AXIS, 0.001, lateral_only=False, freeze_force=1.0, latch=False)
    with pytest.raises(ValueError, match="integral_freeze_force"):
        PoseIntegral(10.0, 2.0, AXIS, 0.001, lateral_only=False, freeze_force=-1.0, latch=False)


def test_integral_gain_zero_means_no_integral():
    sim = prepare(
        make_cfg(
            "target=none",
            "trajectory=hold",
            "task.init_pos=[0.55,0.0,0.35]",
            "controller.integral_gain=0",
            "task.progress=false",
        )
    )
    assert sim.controller.integral is None
    assert "integral_final_force_N" not in sim.controller.diagnostics()


@pytest.mark.parametrize("controller", ["impedance", "se3_lie", "hqp"])
def test_integral_action_removes_a_constant_disturbance(controller):
    """A constant 2.5 N push in free space (iiwa14, no friction): without integral action
    the TCP settles at F/K; with integral_gain = 100 N/(m·s) on every axis the offset
    decays. For the impedance laws (m = 10, d = 80, k = 50) the slowest poles of
    m s³ + d s² + k s + ki are −0.24 ± 1.13j s⁻¹: after 15 s the envelope is 2.6 % of the
    initial offset, hence the 5 % bound; HQP (K_r ≥ 90 N/m, heavier damping) is faster."""
    force = np.array([2.0, -1.0, 1.5])
    moved = {}
    for ki in (0.0, 100.0):
        sim = prepare(
            make_cfg(
                *FREE_SPACE_HOLD,
                "trajectory.duration=15",
                f"controller={controller}",
                f"controller.integral_gain={ki}",
                "controller.integral_lateral_only=false",
                "controller.integral_freeze_force=100",
                "task.progress=false",
            )
        )
        start = sim.scene.arm.tcp_placement(sim.q0).translation
        push_at_tcp(sim, force=force)
        sim.run()
        moved[ki] = sim.scene.arm.tcp_placement(sim.data.qpos).translation - start
    without = np.linalg.norm(moved[0.0])
    assert without > 0.005  # the push moves the compliant TCP by F/K: 5-56 mm
    assert np.linalg.norm(moved[100.0]) < 0.05 * without
