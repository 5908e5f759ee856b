"""Pinocchio's arm + tool model agrees with MuJoCo's simulation of the same scene."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from compliant_docking.sim.scene import build_scene
from compliant_docking.sim.settings import sim_settings
from tests.helpers import make_cfg


@pytest.mark.parametrize("robot", ["iiwa14", "fr3"])
@pytest.mark.parametrize("physics", ["space", "earth"])
def test_mass_matrix_and_bias_match_mujoco(robot, physics):
    scene = build_scene(sim_settings(make_cfg(f"robot={robot}", f"physics={physics}")))
    model, arm = scene.model, scene.arm
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    M_mj = np.zeros((model.nv, model.nv))
    lo, hi = arm.q_lower, arm.q_upper
    for _ in range(10):
        q = lo + (hi - lo) * rng.uniform(0.05, 0.95, size=model.nv)
        v = rng.uniform(-1.5, 1.5, size=model.nv)
        data.qpos[:], data.qvel[:] = q, v
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, M_mj)
        arm.update(q, v)
        # the same model in two libraries: equal to round-off (entries up to ~10 kg·m², N·m)
        assert np.max(np.abs(arm.M - M_mj)) < 1e-9
        assert np.max(np.abs(arm.h - data.qfrc_bias)) < 1e-9
        # the TCP in Pinocchio is the tool's tcp site in MuJoCo (positions ~1 m: round-off)
        assert np.allclose(arm.pos, data.site_xpos[scene.tcp_site], atol=1e-12)
        assert np.allclose(arm.rot, data.site_xmat[scene.tcp_site].reshape(3, 3), atol=1e-12)


def test_jdot_v_matches_finite_difference():
    scene = build_scene(sim_settings(make_cfg()))
    arm = scene.arm
    rng = np.random.default_rng(3)
    q = arm.q_lower + (arm.q_upper - arm.q_lower) * rng.uniform(0.2, 0.8, size=arm.nv)
    v = rng.uniform(-1, 1, size=arm.nv)
    h = 1e-6
    J = []
    for s in (-1, 1):
        arm.update(pin.integrate(arm.model, q, s * h * v), v)
        J.append(arm.J.copy())
    arm.update(q, v)
    fd = (J[1] - J[0]) @ v / (2 * h)
    # central differences with h = 1e-6: truncation ~h² = 1e-12, round-off ~eps/h = 2e-10;
    # 1e-6 leaves room, while a missing or wrong term of J̇v (order |v|² ≈ 1) fails
    assert np.allclose(arm.Jdot_v, fd, atol=1e-6)
    assert np.allclose(arm.twist, arm.J @ v, atol=1e-12)
