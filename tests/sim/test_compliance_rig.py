"""The arm-free compliance rig (compliant_docking.sim.compliance_rig): where it starts, what
its support does, what its drives do, and the sign of the forces it records."""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from compliant_docking.config.store import default_interface
from compliant_docking.sim.compliance_rig import (
    Push,
    Ramp,
    Support,
    critically_damp,
    interface_rig,
    plug_contacts,
    plug_tilt,
    push_insertion,
    ramp_insertion,
    tip_height,
)

PLUG, SOCKET, CONTACT = default_interface()


def rig(height=0.0, *, drive=None, offset=0.002, tilt_deg=2.0, twist=False):
    support = Support(300.0, 0.0, 25.0, 0.0, compliance_height=height, twist=twist)
    return interface_rig(
        replace(PLUG), replace(SOCKET), replace(CONTACT), support=support, drive=drive or Ramp(0.005),
        offset=offset, tilt_deg=tilt_deg,
    )  # fmt: skip


def _centre(r, height: float) -> np.ndarray:
    """The compliance centre in the world: on the plug's axis, ``height`` above the tip."""
    tip = r.data.site_xpos[r.tcp_site]
    axis = tip - r.data.site_xpos[r.mount_site]
    return tip - height * axis / np.linalg.norm(axis)


@pytest.mark.parametrize("height", [0.0, 0.1, PLUG.length])
def test_rest_pose_is_the_starting_pose(height):
    r = rig(height)
    tip = r.data.site_xpos[r.tcp_site]
    np.testing.assert_allclose(tip, [0.002, 0.0, SOCKET.mouth_height + 0.002], atol=1e-12)
    assert plug_tilt(r) == pytest.approx(math.radians(2.0), abs=1e-12)
    assert tip_height(r) == pytest.approx(SOCKET.mouth_height + 0.002, abs=1e-12)
    # the tilt leans the tip towards -x: the mounting face is on the +x side of the tip
    assert r.data.site_xpos[r.mount_site][0] > tip[0]
    np.testing.assert_allclose(r.data.qpos, 0.0)
    assert r.model.nu == 1 and r.model.njnt == 5  # slides x, y, z (the drive), hinges x, y


@pytest.mark.parametrize("height", [0.0, 0.1, 0.2, PLUG.length])
def test_the_hinges_pass_through_the_compliance_centre(height):
    """A force through the compliance centre loads only the slides (it translates the plug),
    a moment only the hinges (it turns the plug about that point): Whitney's support."""
    r = rig(height)
    m, d = r.model, r.data
    body = m.body("tool_dock").id
    centre = _centre(r, height)
    force = np.array([0.7, -0.4, 0.0])
    qfrc = np.zeros(m.nv)
    mujoco.mj_applyFT(m, d, force, np.zeros(3), centre, body, qfrc)
    np.testing.assert_allclose(qfrc[list(r.angular_dofs)], 0.0, atol=1e-12)
    np.testing.assert_allclose(qfrc[list(r.lateral_dofs)], force[:2], atol=1e-12)
    torque = np.array([0.03, -0.05, 0.0])
    qfrc[:] = 0.0
    mujoco.mj_applyFT(m, d, np.zeros(3), torque, centre, body, qfrc)
    np.testing.assert_allclose(qfrc[list(r.lateral_dofs)], 0.0, atol=1e-12)
    np.testing.assert_allclose(qfrc[list(r.angular_dofs)], torque[:2], atol=1e-12)
    # and the springs are those of the support
    np.testing.assert_allclose(m.jnt_stiffness[[m.dof_jntid[i] for i in r.lateral_dofs]], 300.0)
    np.testing.assert_allclose(m.jnt_stiffness[[m.dof_jntid[i] for i in r.angular_dofs]], 25.0)


def test_critical_damping_of_each_joint():
    r = rig(0.1)
    critically_damp(r, 0.5)
    full = np.zeros((r.model.nv, r.model.nv))
    mujoco.mj_fullM(r.model, r.data, full)
    for dof, k in ((r.lateral_dofs[0], 300.0), (r.angular_dofs[1], 25.0)):
        assert r.model.dof_damping[dof] == pytest.approx(2 * 0.5 * math.sqrt(k * full[dof, dof]), rel=1e-12)
    assert r.model.dof_damping[r.drive_dof] == 0.0


def test_ramp_follows_the_speed_in_free_space_and_records_no_force():
    r = rig(0.0, offset=0.0, tilt_deg=0.0)
    critically_damp(r)
    start = tip_height(r)
    trace = ramp_insertion(r, end_height=start - 0.004)
    assert trace.stopped == "depth"
    steady = trace.time > 0.1
    speed = -np.diff(trace.tip_height[steady]) / np.diff(trace.time[steady])
    np.testing.assert_allclose(speed, 0.005, rtol=1e-6)
    np.testing.assert_array_equal(trace.force, 0.0)
    assert len(trace.contacts) == 0
    assert np.abs(trace.servo_force[steady]).max() < 1e-3  # only the plug's (absent) drag


def test_contact_force_is_the_force_on_the_plug():
    """Pushed onto the seat with 5 N, the plug feels +5 N along +z from the socket, and every
    recorded normal points into the plug (up, on the floor)."""
    support = Support(100.0, 10.0, 0.5, 0.02, compliance_height=PLUG.length)
    r = interface_rig(
        replace(PLUG), replace(SOCKET), replace(CONTACT), support=support, drive=Push(5.0, 0.05)
    )
    result = push_insertion(r, dwell=0.3)
    assert result.seated
    contacts = plug_contacts(r)
    total = sum(force for *_, force in contacts)
    assert total[2] == pytest.approx(5.0, rel=1e-3)
    for plug_geom, socket_geom, _, normal, _, _ in contacts:
        assert plug_geom in r.plug_geoms and socket_geom not in r.plug_geoms
        assert r.model.geom(socket_geom).name == "target_floor"
        assert normal[2] > 0.999


def test_each_run_needs_its_drive():
    with pytest.raises(ValueError, match="drive=Push"):
        push_insertion(rig(0.0))
    with pytest.raises(ValueError, match="drive=Ramp"):
        ramp_insertion(rig(0.0, drive=Push(5.0, 0.05)), end_height=0.0)
