"""The wrist force/torque chain (compliant_docking/sim/sensor.py): what MuJoCo's sensor
reports, turned into the wrench ON the tool at the TCP in world axes, the tool's weight
removed."""

import math

import mujoco
import numpy as np
import pytest

from compliant_docking.sim.sensor import wrench_reader
from compliant_docking.sim.simulate import prepare
from tests.helpers import FREE_SPACE_HOLD, make_cfg, push_at_tcp

#: plug pointing straight down (the default), and tilted 50° from it about the world y axis:
#: then the tool's weight has a moment about the TCP (its centre of mass is 30 mm up the
#: plug axis): 0.3 kg · 9.81 m/s² · 0.03 m · sin 50° = 0.068 N·m
TILTS = {"vertical": None, "tilted 50°": 50.0}


def _quat_wxyz(tilt_deg: float) -> str:
    """The TCP orientation Ry(180° − tilt): the plug axis (TCP z) 'tilt' degrees off straight down."""
    half = math.radians(180.0 - tilt_deg) / 2.0
    return f"task.init_quat=[{math.cos(half)},0.0,{math.sin(half)},0.0]"


def _held_still(sim, force, moment):
    """Push the tool and hold the arm still with inverse dynamics (gravity and push), then
    read the sensor chain after one step."""
    model, data = sim.scene.model, sim.data
    push_at_tcp(sim, force=force, moment=moment)
    model.actuator_ctrlrange[:] = [-1e6, 1e6]
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
    assert np.abs(data.qvel).max() < 1e-6  # static: no inertial forces in the reading
    out = np.zeros(6)
    wrench_reader(sim.scene, data, out)()
    return out


@pytest.mark.parametrize("tilt", TILTS.values(), ids=TILTS.keys())
@pytest.mark.parametrize("physics", ["space", "earth"])
def test_wrench_reader_returns_the_applied_wrench_at_the_tcp(physics, tilt):
    """The push comes back with the sign of a wrench ON the tool, the moment about the TCP
    and the tool's weight (force and moment) compensated; 1e-6: the static hold's residual."""
    tilted = () if tilt is None else (_quat_wxyz(tilt),)
    sim = prepare(make_cfg(*FREE_SPACE_HOLD, f"physics={physics}", *tilted))
    if tilt is not None:  # the start pose really is tilted
        axis = sim.scene.arm.tcp_placement(sim.q0).rotation[:, 2]
        assert math.degrees(math.acos(-axis[2])) == pytest.approx(tilt, abs=1e-6)
    force, moment = np.array([1.0, -2.0, 3.0]), np.array([0.1, 0.05, -0.2])
    out = _held_still(sim, force, moment)
    assert np.allclose(out[:3], force, atol=1e-6)
    assert np.allclose(out[3:], moment, atol=1e-6)


def test_the_tilted_case_measures_the_weight_moment():
    """Without the payload compensation the tilted reading is off by the weight's moment
    about the TCP, m·g·|c − tcp|·sin(tilt) = 0.068 N·m, and its force m·g: so the test
    above would catch a wrong sign or a dropped term."""
    sim = prepare(make_cfg(*FREE_SPACE_HOLD, "physics=earth", _quat_wxyz(50.0)))
    tool = sim.scene.arm.tool
    out = _held_still(sim, np.zeros(3), np.zeros(3))
    assert np.allclose(out, 0.0, atol=1e-6)
    # the raw chain, without compensation: −(sensor reading) at the TCP, world axes
    data, scene = sim.data, sim.scene
    raw = data.sensordata[scene.force_adr : scene.force_adr + 6]
    site_rot = data.site_xmat[scene.sensor_site].reshape(3, 3)
    r = -(tool.sensor.actInv(tool.tcp)).translation  # TCP → sensor, sensor axes
    f_site, m_site = -raw[:3], -(raw[3:] + np.cross(r, raw[:3]))
    weight = tool.mass * scene.gravity
    lever = np.linalg.norm(tool.com - tool.tcp.translation)
    expected_moment = tool.mass * 9.81 * lever * math.sin(math.radians(50.0))
    assert expected_moment > 0.06  # 0.068 N·m: the chamfer puts the centre of mass 30.2 mm up
    np.testing.assert_allclose(site_rot @ f_site, weight, atol=1e-6)
    assert np.linalg.norm(site_rot @ m_site) == pytest.approx(expected_moment, rel=1e-6)
