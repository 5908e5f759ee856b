"""``robot=fr3``: the model carries what the robot config promises, the per-robot gain
files are part of the composed config, and both controllers dock the default scene.

Docking assertions are the docking gate's (seated within 1 mm, inside the bore's
0.4 mm clearance + 0.1 mm, tilt < 2°) plus the measured steady and peak forces, each
with the reason for its width.
"""

import numpy as np
import pytest

from compliant_docking.run.runner import execute
from compliant_docking.sim import simulate
from tests.helpers import make_cfg


def test_fr3_model_and_limits():
    sim = simulate.prepare(make_cfg("robot=fr3", "task.progress=false"))
    model, ctx = sim.scene.model, sim.controller.ctx
    assert model.nv == 7
    # Menagerie joint friction and damping, which Pinocchio does not model: the
    # controller's feed-forward gets them from MuJoCo
    assert np.allclose(ctx.joint_friction, [1.137, 1.137, 1.137, 1.137, 0.763, 0.44, 0.248])
    assert np.allclose(ctx.joint_damping, 0.21)
    assert sim.controller.friction.active
    assert np.allclose(model.dof_armature, [0.195] * 4 + [0.074] * 3)
    # hardware limits 87/12 N·m, software clip 10 N·m (the seed's max_torque)
    assert np.allclose(model.jnt_actfrcrange[:, 1], [87.0] * 4 + [12.0] * 3)
    assert np.allclose(ctx.torque_limits, 10.0)
    assert np.allclose(model.actuator_ctrlrange, [[-10.0, 10.0]] * 7)
    # the start posture is inside the datasheet ranges
    assert np.all(sim.q0 > sim.scene.arm.q_lower) and np.all(sim.q0 < sim.scene.arm.q_upper)


def test_per_robot_gains_are_in_the_composed_config():
    imp = make_cfg("robot=fr3").controller
    assert (imp.k, imp.d, imp.m, imp.m_rot) == (300.0, 100.0, 2.0, 0.2)
    assert (imp.k_rot, imp.d_rot) == (25.0, 10.0)  # untouched
    lie = make_cfg("robot=fr3", "controller=se3_lie").controller
    assert list(lie.K_diag) == [300.0] * 3 + [25.0] * 3
    assert list(lie.D_diag) == [100.0] * 3 + [10.0] * 3
    assert list(lie.A_diag) == [2.0] * 3 + [0.2] * 3
    # the two files describe the same impedance
    assert list(lie.K_diag) == [imp.k] * 3 + [imp.k_rot] * 3
    assert list(lie.D_diag) == [imp.d] * 3 + [imp.d_rot] * 3
    assert list(lie.A_diag) == [imp.m] * 3 + [imp.m_rot] * 3
    # other robots keep the defaults; the command line still wins
    assert make_cfg("robot=iiwa14").controller.k == 50.0
    assert make_cfg("robot=fr3", "controller.k=200").controller.k == 200.0


#: measured steady axial force [N] per friction feed-forward mode (impedance, se3_lie), with
#: the FR3 gain files (apparent-inertia floor 0.75, integral action 2000 N/(m·s)): the spring
#: k·5 mm = 1.5 N, the integral force frozen at first contact (0.9 N) and what the joints'
#: friction holds. In zero gravity torque_unbiased and torque differ only by C·v (≈ 0 here).
STEADY_FORCE = {"yielding": (3.998, 3.998), "torque_unbiased": (3.986, 3.986), "torque": (3.986, 3.986)}
#: measured peak axial force [N]: the press home, not an impact (first strike 2.0 N); the
#: bounded reference (trajectory.lead_limit) lets the stuck plug go with at most 12 mm of lead
PEAK_FORCE = {"yielding": (7.11, 7.62), "torque_unbiased": (6.93, 7.04), "torque": (6.92, 7.03)}


#: se3_lie's torque-following modes dock in the nightly suite (`slow`): the fast suite docks
#: every mode with the impedance law and se3_lie with its default mode (yielding), and
#: tests/control/test_kernel_blocks.py::test_friction_twin_matches_the_numpy_feed_forward
#: proves se3_lie's compiled feed-forward equals the impedance law's in every mode
_SE3_TORQUE_MODES = pytest.mark.slow(reason="same feed-forward as the impedance cells (twin test)")
#: the impedance law's torque-following modes likewise: the fast suite docks the FR3 with the
#: default mode (yielding) and tests/control/test_base.py::test_friction_feedforward_modes and
#: ::test_friction_feedforward_unbiased_mode_ignores_the_bias_torques pin what each mode adds
_IMPEDANCE_TORQUE_MODES = pytest.mark.slow(
    reason="the yielding cell docks the FR3; test_base.py pins each mode's feed-forward"
)
DOCKING_CELLS = [
    ("impedance", "yielding"),
    pytest.param("impedance", "torque_unbiased", marks=_IMPEDANCE_TORQUE_MODES),
    pytest.param("impedance", "torque", marks=_IMPEDANCE_TORQUE_MODES),
    ("se3_lie", "yielding"),
    pytest.param("se3_lie", "torque_unbiased", marks=_SE3_TORQUE_MODES),
    pytest.param("se3_lie", "torque", marks=_SE3_TORQUE_MODES),
]


@pytest.mark.parametrize("controller, friction_comp", DOCKING_CELLS)
def test_fr3_docks_the_default_scene(tmp_path, controller, friction_comp):
    """Both torque-following feed-forward modes seat the plug straight, calmly, and pass the gate.

    Tolerances: the gate's seat (1 mm, the bore's 0.4 mm clearance + 0.1 mm chamfer play,
    2°); the steady force within 0.1 N of the measured value (2.5 %: the friction-bound
    part depends on where the joints stuck); the peak within 15 % (the most
    round-off-sensitive number of a run)."""
    record = execute(
        make_cfg(
            "robot=fr3",
            f"controller={controller}",
            f"controller.friction_comp={friction_comp}",
            "task.progress=false",
        ),
        tmp_path,
        figures=False,
        echo=False,
    )
    assert record["status"] == "ok" and record["error"] is None
    assert record["success"] is True, record["gate_failures"]
    assert record["seat_depth_error_m"] < 1e-3
    assert record["seat_lateral_error_m"] < 0.4e-3 + 1e-4
    assert record["seat_tilt_deg"] < 2.0
    which = 0 if controller == "impedance" else 1
    assert record["steady_axial_force_N"] == pytest.approx(STEADY_FORCE[friction_comp][which], abs=0.1)
    assert record["steady_axial_force_N"] > 300.0 * 0.005  # never below the spring
    assert record["peak_axial_force_N"] == pytest.approx(PEAK_FORCE[friction_comp][which], rel=0.15)
    assert record["steady_contact_events_per_s"] == 0.0  # a calm hold
    assert record["lambda_fallback_steps"] == 0


@pytest.mark.parametrize(
    "controller",
    ["impedance", pytest.param("se3_lie", marks=pytest.mark.slow(reason="the twin test: as DOCKING_CELLS"))],
)
def test_fr3_velocity_mode_lands_on_the_funnel_off_the_axis(tmp_path, controller):
    """Why the FR3's feed-forward follows the command (docs/controllers/friction.md): in
    velocity mode the joints stick while they are at rest (a dead zone), so the heavier
    floored arm lags its reference sideways and lands on the funnel ~5 mm off the axis
    (measured 5.0 mm), striking it at 65-70 N per step (raw). The strike is short: its
    filtered peak (the 50 ms mean the gate judges) is about 7 N, so the funnel guides the
    plug home and the run docks (with the open-loop reference, which keeps pushing while the
    plug sticks on the funnel); the torque modes arrive on the axis instead."""
    record = execute(
        make_cfg(
            "robot=fr3",
            f"controller={controller}",
            "controller.friction_comp=velocity",
            "trajectory.lead_limit=null",
            "task.progress=false",
        ),
        tmp_path,
        figures=False,
        echo=False,
    )
    assert record["first_contact_lateral_offset_m"] > 2e-3  # on the funnel, not the bore
    assert record["first_strike_force_N"] > 50.0  # the raw per-step strike
    assert record["filtered_peak_axial_force_N"] < 0.25 * record["first_strike_force_N"]
    assert record["success"] is True, record["gate_failures"]
