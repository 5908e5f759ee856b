"""``controller=se3_lie``: the law against a literal transcription of docs/control_laws.md §3,
the world → body conversions by finite differences, and closed-loop physics.

Tolerances:
* the controller against the literal law (numpy, Pinocchio and lie's dexp, explicit inverses): 1e-9
  relative (both evaluate the same formulas; the literal one forms inverses);
* central finite differences with step 1e-6 s: truncation ~1e-12 and round-off
  ~1e-10, so 1e-6 relative (a missing ω×ṗ term is an O(1) relative error);
* push tests: the settled displacement is F/k within 2 % (force) and M/k_rot within
  3 % (moment), the impedance controller's own tolerances;
* large-error convergence: position < 0.5 mm, rotation < 0.01° after 8 s.
"""

import json
import math

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from hydra.errors import ConfigCompositionException
from hydra.utils import instantiate
from omegaconf import OmegaConf

from compliant_docking.config import FrictionComp
from compliant_docking.control import lie
from compliant_docking.control.se3_lie import SE3LieController
from compliant_docking.planning.base import Reference
from compliant_docking.run.runner import execute
from compliant_docking.sim import simulate
from tests.helpers import make_cfg, push_at_tcp

FREE_SPACE = (
    "controller=se3_lie",
    "target=none",
    "trajectory=hold",
    "task.init_pos=[0.55,0.0,0.35]",
    "task.settle_time=0.0",
    "task.progress=false",
)
REL = 1e-9


def blockdiag(R):
    out = np.zeros((6, 6))
    out[:3, :3] = out[3:, 3:] = R
    return out


def random_spd(rng, scale):
    B = rng.standard_normal((6, 6))
    return np.diag(scale) + 0.2 * (B @ B.T) * np.sqrt(np.outer(scale, scale)) / 6


def controller(sim, **kwargs):
    """A controller on sim's arm with the gains of conf/controller/se3_lie.yaml, some
    overridden (friction feed-forward irrelevant: iiwa14 has none), under the law of §3
    (no apparent-inertia floor: these tests compare against the spec)."""
    assert not sim.controller.friction.active
    params = OmegaConf.to_container(sim.cfg.controller, resolve=True)
    params.pop("_target_")
    params["friction_comp"] = FrictionComp.torque
    params["apparent_inertia_floor"] = None
    return SE3LieController(sim.controller.ctx, **{**params, **kwargs})


def literal_law(arm, ref, wrench, A, D, K, b, F_d):
    """docs/control_laws.md §3 transcribed with dense numpy, Pinocchio's SE(3) helpers and lie's dexp
    (explicit inverses)."""
    R, p = arm.rot.copy(), arm.pos.copy()
    Rd, pd = ref.rot, ref.pos
    Tt = pin.SE3(R, p).actInv(pin.SE3(Rd, pd))  # T⁻¹T_d
    lam = pin.log6(Tt).vector
    V = blockdiag(R.T) @ arm.twist
    V_d = blockdiag(Rd.T) @ ref.twist
    vd, wd = ref.twist[:3], ref.twist[3:]
    Vdot_d = np.r_[Rd.T @ (ref.accel[:3] - np.cross(wd, vd)), Rd.T @ ref.accel[3:]]
    F_body = blockdiag(R.T) @ wrench
    Ad = Tt.action
    V_tilde = Ad @ V_d - V
    lam_dot = lie.dexp_inv(lam) @ V_tilde
    F_tilde = Tt.dualAction @ F_d - F_body
    X, Xi, Xd = lie.dexp_all(lam, lam_dot)
    gamma = X.T @ F_tilde
    Xinv, Ainv = np.linalg.inv(X), np.linalg.inv(A)
    K_V = Xinv @ (Ainv @ D @ X + Xd)
    K_P = Xinv @ Ainv @ Xinv.T @ K
    K_F = Xinv @ Ainv @ Xinv.T
    lam_ddot = -K_V @ lam_dot - K_P @ lam + K_F @ gamma
    Vdot_ref = Ad @ Vdot_d - X @ lam_ddot + pin.Motion(V_tilde).action @ V - Xd @ lam_dot
    # redundancy resolution
    w, v = arm.twist[3:], arm.twist[:3]
    Jb = blockdiag(R.T) @ arm.J
    Jdot_b_v = np.r_[R.T @ (arm.Jdot_v[:3] - np.cross(w, v)), R.T @ arm.Jdot_v[3:]]
    Lam = np.linalg.inv(Jb @ arm.Minv @ Jb.T)
    Jbar = arm.Minv @ Jb.T @ Lam
    N = np.eye(arm.nv) - Jbar @ Jb
    qdd = Jbar @ (Vdot_ref - Jdot_b_v) + N @ (-b * arm.v)
    tau = arm.M @ qdd + arm.h - Jb.T @ F_body
    return dict(
        lam=lam,
        V_tilde=V_tilde,
        F_tilde=F_tilde,
        lam_dot=lam_dot,
        gamma=gamma,
        lam_ddot_ref=lam_ddot,
        Vdot_ref=Vdot_ref,
        tau=tau,
        gains=(K_V, K_P, K_F),
    )


def random_case(arm, rng, angle):
    """A random state of the arm, a reference rotated by ``angle`` from the TCP, a wrench."""
    q = arm.q_lower + (arm.q_upper - arm.q_lower) * rng.uniform(0.2, 0.8, arm.nv)
    v = rng.uniform(-1.0, 1.0, arm.nv)
    arm.update(q, v)
    axis = rng.standard_normal(3)
    ref = Reference()
    ref.rot[:] = arm.rot @ pin.exp3(angle * axis / np.linalg.norm(axis))
    ref.pos[:] = arm.pos + rng.uniform(-0.1, 0.1, 3)
    ref.twist[:] = rng.uniform(-0.5, 0.5, 6)
    ref.accel[:] = rng.uniform(-2.0, 2.0, 6)
    return ref, rng.uniform(-5.0, 5.0, 6)


def close(a, b, rel=REL):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) <= rel * max(1.0, np.max(np.abs(b)))


# --------------------------------------------------------------------------- the law
@pytest.mark.parametrize("formulation", ["twist", "lambda_space"])
@pytest.mark.parametrize("gains", ["diagonal", "general"])
def test_controller_matches_the_literal_law(formulation, gains):
    sim = simulate.prepare(make_cfg(*FREE_SPACE))
    arm = sim.scene.arm
    rng = np.random.default_rng(11)
    if gains == "diagonal":
        A = np.diag([10.0, 8.0, 12.0, 1.0, 0.8, 1.2])
        D = np.diag([80.0, 70.0, 90.0, 10.0, 9.0, 11.0])
        K = np.diag([50.0, 40.0, 60.0, 25.0, 20.0, 30.0])
    else:
        A = random_spd(rng, [10.0, 10.0, 10.0, 1.0, 1.0, 1.0])
        D = random_spd(rng, [80.0, 80.0, 80.0, 10.0, 10.0, 10.0])
        K = random_spd(rng, [50.0, 50.0, 50.0, 25.0, 25.0, 25.0])
    F_d = np.array([1.0, -2.0, 0.5, 0.1, 0.05, -0.2])
    b = 7.0
    for angle in (0.0, 1e-3, 0.05, 0.3, 1.0, 2.0, 3.0):  # Taylor and closed-form branches
        # a fresh controller per case: unrelated references are not a continuous motion
        ctrl = controller(sim, A=A, D=D, K=K, null_damping=b, desired_wrench=F_d, formulation=formulation)
        ref, wrench = random_case(arm, rng, angle)
        tau = ctrl.compute(0.0, arm, ref, wrench)
        lit = literal_law(arm, ref, wrench, A, D, K, b, F_d)
        assert close(tau, lit["tau"]), angle
        for name in ("lam", "V_tilde", "F_tilde", "Vdot_ref"):
            assert close(getattr(ctrl, name), lit[name]), (angle, name)
        if formulation == "lambda_space":
            for name in ("lam_dot", "gamma", "lam_ddot_ref"):
                assert close(getattr(ctrl, name), lit[name]), (angle, name)
            for ours, theirs in zip(ctrl.lambda_gains(ctrl.lam, ctrl.lam_dot), lit["gains"]):
                assert close(ours, theirs)


def test_lambda_space_quantities_are_consistent():
    """Ṽ = dexp λ̇ and, for the commanded motion, d/dt Ṽ = dexp λ̈_ref + ḋexp λ̇ equals
    Ad(T̃)V̇_d + ad(Ṽ)V − V̇_ref (the kinematic identity the law inverts)."""
    sim = simulate.prepare(make_cfg(*FREE_SPACE))
    arm = sim.scene.arm
    rng = np.random.default_rng(5)
    for angle in (0.02, 0.7, 2.5):
        ctrl = controller(sim, formulation="lambda_space")
        ref, wrench = random_case(arm, rng, angle)
        ctrl.compute(0.0, arm, ref, wrench)
        X, Xd = ctrl.dexp, ctrl.dexp_dot
        assert close(X @ ctrl.lam_dot, ctrl.V_tilde, 1e-12)
        R, Rd = arm.rot, ref.rot
        Tt = pin.SE3(R, arm.pos).actInv(pin.SE3(Rd, ref.pos))
        vd, wd = ref.twist[:3], ref.twist[3:]
        Vdot_d = np.r_[Rd.T @ (ref.accel[:3] - np.cross(wd, vd)), Rd.T @ ref.accel[3:]]
        V = blockdiag(R.T) @ arm.twist
        lhs = X @ ctrl.lam_ddot_ref + Xd @ ctrl.lam_dot
        rhs = (
            Tt.action @ Vdot_d + pin.Motion(np.asarray(ctrl.V_tilde, dtype=float)).action @ V - ctrl.Vdot_ref
        )
        assert close(lhs, rhs, 1e-10)
        # … and it is the impedance A·dṼ/dt + D·Ṽ + dexp⁻ᵀKλ = F̃ (default diagonal gains)
        A, D, K = ctrl.A, ctrl.D, ctrl.K
        residual = A @ lhs + D @ ctrl.V_tilde + np.linalg.solve(X.T, K @ ctrl.lam) - ctrl.F_tilde
        assert np.max(np.abs(residual)) < 1e-9 * max(1.0, np.max(np.abs(ctrl.F_tilde)))


# --------------------------------------------------------------------------- frames
def _tcp_motion(arm, q0, v0, a0, t):
    """TCP pose, world twist and classical acceleration along q(t) = q0 + v0 t + a0 t²/2."""
    model, data = arm.model, arm.model.createData()
    q = pin.integrate(model, q0, v0 * t + 0.5 * a0 * t * t)
    v = v0 + a0 * t
    pin.forwardKinematics(model, data, q, v, a0)
    pin.updateFramePlacements(model, data)
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    pose = data.oMf[arm.tcp_frame]
    twist = pin.getFrameVelocity(model, data, arm.tcp_frame, lwa).vector
    accel = pin.getFrameClassicalAcceleration(model, data, arm.tcp_frame, lwa).vector
    return q, v, pose.rotation.copy(), pose.translation.copy(), twist, accel


@pytest.mark.parametrize("formulation", ["twist", "lambda_space"])
def test_body_accelerations_by_finite_differences(formulation):
    """The reference is the arm's own motion (so T̃ = I, Ṽ = 0): the controller must ask
    for V̇_ref = V̇_d, the derivative of the body twist (checked by central differences
    of [Rᵀṗ; Rᵀω]), and its torque must produce the reference's classical acceleration."""
    sim = simulate.prepare(make_cfg(*FREE_SPACE))
    arm = sim.scene.arm
    ctrl = controller(sim, formulation=formulation)
    rng = np.random.default_rng(2)
    for _ in range(3):
        q0 = arm.q_lower + (arm.q_upper - arm.q_lower) * rng.uniform(0.2, 0.8, arm.nv)
        v0, a0 = rng.uniform(-1.0, 1.0, arm.nv), rng.uniform(-3.0, 3.0, arm.nv)
        t, h = 0.3, 1e-6

        def body_twist(s):
            *_, R, _, twist, _ = _tcp_motion(arm, q0, v0, a0, s)
            return blockdiag(R.T) @ twist

        fd = (body_twist(t + h) - body_twist(t - h)) / (2 * h)
        q, v, R, p, twist, accel = _tcp_motion(arm, q0, v0, a0, t)
        ref = Reference()
        ref.rot[:], ref.pos[:], ref.twist[:], ref.accel[:] = R, p, twist, accel
        arm.update(q, v)
        tau = ctrl.compute(0.0, arm, ref, np.zeros(6))
        assert np.max(np.abs(ctrl.lam)) < 1e-12 and np.max(np.abs(ctrl.V_tilde)) < 1e-12
        assert close(ctrl.Vdot_ref, fd, 1e-6)
        # the classical acceleration of the TCP under the commanded torque
        qdd = np.linalg.solve(arm.M, tau - arm.h)
        assert close(arm.J @ qdd + arm.Jdot_v, accel, 1e-9)
        # and J̇_b v (zero joint acceleration) by finite differences of J_b(q) v
        fd0 = (
            blockdiag(_tcp_motion(arm, q0, v, 0 * a0, t + h)[2].T) @ _tcp_motion(arm, q0, v, 0 * a0, t + h)[4]
            - blockdiag(_tcp_motion(arm, q0, v, 0 * a0, t - h)[2].T)
            @ _tcp_motion(arm, q0, v, 0 * a0, t - h)[4]
        ) / (2 * h)
        q1 = pin.integrate(arm.model, q0, v * t)
        arm.update(q1, v)
        w, lin = arm.twist[3:], arm.twist[:3]
        Jdot_b_v = np.r_[arm.rot.T @ (arm.Jdot_v[:3] - np.cross(w, lin)), arm.rot.T @ arm.Jdot_v[3:]]
        assert close(Jdot_b_v, fd0, 1e-6)


# --------------------------------------------------------------------------- closed loop
def test_constant_push_settles_at_force_over_stiffness():
    """Anisotropic K (TCP axes): the displacement is R diag(1/k) Rᵀ F."""
    k = np.array([40.0, 60.0, 80.0])
    sim = simulate.prepare(
        make_cfg(*FREE_SPACE, "trajectory.duration=10", f"controller.K_diag=[{k[0]},{k[1]},{k[2]},25,25,25]")
    )
    start = sim.scene.arm.tcp_placement(sim.q0)
    force = np.array([2.0, -1.0, 1.5])
    push_at_tcp(sim, force=force)
    sim.run()
    end = sim.scene.arm.tcp_placement(sim.data.qpos)
    R = start.rotation
    expected = R @ ((R.T @ force) / k)
    displacement = end.translation - start.translation
    assert np.linalg.norm(displacement - expected) < 0.02 * np.linalg.norm(expected)
    assert np.linalg.norm(pin.log3(start.rotation.T @ end.rotation)) < 1e-3


def test_without_force_feedback_the_push_test_fails():
    """Feedback off: the arm's own inertia replaces A, F/k no longer holds (the push
    test above can fail)."""
    sim = simulate.prepare(
        make_cfg(*FREE_SPACE, "trajectory.duration=10", "controller.use_force_feedback=false")
    )
    start = sim.scene.arm.tcp_placement(sim.q0)
    push_at_tcp(sim, force=(2.0, 0.0, 0.0))
    sim.run()
    dx = sim.scene.arm.tcp_placement(sim.data.qpos).translation[0] - start.translation[0]
    assert abs(dx - 2.0 / 50.0) > 0.1 * 2.0 / 50.0


def _rotated_start(sim, axis, degrees, offset=(0.0, 0.0, 0.0)):
    """Start the arm at the reference pose rotated by ``degrees`` about ``axis`` (TCP
    frame) and shifted by ``offset`` (world) [m]."""
    ref = sim.waypoints.start
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    start = pin.SE3(
        ref.rotation @ pin.exp3(math.radians(degrees) * axis), ref.translation + np.asarray(offset, float)
    )
    q = sim.scene.arm.solve_ik(start, sim.q0)
    sim.data.qpos[:] = q
    sim.data.qvel[:] = 0.0
    mujoco.mj_forward(sim.scene.model, sim.data)
    return q


# the lambda_space cell is nightly (`slow`); fast proof: the twist cell of this test and
# tests/control/test_se3_lie.py::test_formulations_give_the_same_run (both formulations
# give the same run, to 1e-7, from a 120° error)
@pytest.mark.parametrize("formulation", ["twist", pytest.param("lambda_space", marks=pytest.mark.slow)])
def test_converges_from_a_160_degree_orientation_error(formulation):
    sim = simulate.prepare(
        make_cfg(*FREE_SPACE, "trajectory.duration=8", f"controller.formulation={formulation}")
    )
    # the plug axis itself tilts by 52°, and the tool starts 4.7 cm away
    _rotated_start(sim, [1.0, 0.0, 2.0], 160.0, offset=[-0.03, 0.03, 0.02])
    sim.run()
    ref = sim.waypoints.start
    end = sim.scene.arm.tcp_placement(sim.data.qpos)
    assert math.degrees(sim.controller.max_rotation_error) > 159.9
    lam = sim.controller.timeseries()["se3_lambda"]
    angle = np.degrees(np.linalg.norm(lam[:, 3:], axis=1))
    assert angle[0] > 159.9 and angle[2000] < 1.0  # below 1° after 2 s
    assert np.linalg.norm(end.translation - ref.translation) < 0.5e-3
    assert math.degrees(np.linalg.norm(pin.log3(end.rotation.T @ ref.rotation))) < 0.01
    assert sim.telemetry.contacts[: sim.telemetry.count].max() == 0
    # the record of λ is the pose error: its end matches the final pose
    assert np.linalg.norm(lam[-1]) < 1e-3


def test_formulations_give_the_same_run():
    finals = []
    for formulation in ("twist", "lambda_space"):
        sim = simulate.prepare(
            make_cfg(*FREE_SPACE, "trajectory.duration=1.5", f"controller.formulation={formulation}")
        )
        _rotated_start(sim, [0.3, -1.0, 1.0], 120.0)
        push_at_tcp(sim, force=(1.0, 0.5, -0.5), moment=(0.05, 0.0, 0.1))
        sim.run()
        finals.append(sim.telemetry.state[: sim.telemetry.count].copy())
    assert np.max(np.abs(finals[0] - finals[1])) < 1e-7


def test_orientation_error_reaching_pi_fails_the_run(tmp_path, monkeypatch):
    """Start 170° from the reference about the tool axis, spinning away from it with no
    rotational stiffness: |λ_rot| reaches π and the run fails with the clear message."""
    base = simulate.prepare(make_cfg(*FREE_SPACE))
    r0 = base.waypoints.start.rotation  # plug down, roll of ik_guess (joint 7 near 0)
    # reference rolled by −90° so that +170° stays inside joint 7's range
    quat = pin.Quaternion(r0 @ pin.exp3(np.array([0.0, 0.0, -math.pi / 2])))
    init_quat = f"[{quat.w},{quat.x},{quat.y},{quat.z}]"
    real_prepare = simulate.prepare

    def prepare_rotated(cfg, settings=None):
        sim = real_prepare(cfg, settings)
        # joint 7 turns the tool about its own axis (through the TCP): 170° away from the
        # reference, and spinning further away
        sim.data.qpos[6] += math.radians(170.0)
        sim.data.qvel[6] = 2.0
        mujoco.mj_forward(sim.scene.model, sim.data)
        start = sim.scene.arm.tcp_placement(sim.data.qpos)
        ref = sim.waypoints.start
        assert np.linalg.norm(start.translation - ref.translation) < 1e-9
        angle = np.linalg.norm(pin.log3(start.rotation.T @ ref.rotation))
        assert angle == pytest.approx(math.radians(170.0), abs=1e-9)
        return sim

    monkeypatch.setattr(simulate, "prepare", prepare_rotated)
    record = execute(
        make_cfg(
            *FREE_SPACE,
            f"task.init_quat={init_quat}",
            "controller.K_diag=[50,50,50,0,0,0]",
            "controller.D_diag=[80,80,80,0.5,0.5,0.5]",
        ),
        tmp_path,
        echo=False,
        figures=False,
    )
    assert record["status"] == "failed" and record["success"] is False
    assert "π" in record["error"] and "se3_lie at t =" in record["error"]
    t_fail = float(record["error"].split("t = ")[1].split(" s")[0])
    assert 0.02 < t_fail < 0.5  # it got there by moving (10° at ~2 rad/s)
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["status"] == "failed" and "π" in saved["error"]


def test_orientation_error_of_pi_is_refused():
    sim = simulate.prepare(make_cfg(*FREE_SPACE))
    arm = sim.scene.arm
    ref, wrench = random_case(arm, np.random.default_rng(3), math.pi)
    with pytest.raises(ValueError, match="π"):
        controller(sim).compute(0.25, arm, ref, wrench)
    ref, wrench = random_case(arm, np.random.default_rng(3), math.pi - 1e-3)
    assert np.all(np.isfinite(controller(sim).compute(0.25, arm, ref, wrench)))  # just below: fine


def test_docks_the_default_scene(tmp_path):
    record = execute(
        make_cfg("controller=se3_lie", "task.progress=false"), tmp_path, figures=False, echo=False
    )
    assert record["status"] == "ok" and record["error"] is None
    assert record["success"] is True, record["gate_failures"]
    assert record["seat_depth_error_m"] < 1e-3
    assert record["seat_lateral_error_m"] < 0.4e-3 + 1e-4
    assert 1.0 < record["peak_axial_force_N"] < 50.0
    assert record["steady_axial_force_N"] == pytest.approx(50.0 * 0.005, rel=0.1)  # k · overshoot
    assert record["lambda_fallback_steps"] == 0
    assert 0.0 <= record["se3_max_rotation_error_rad"] < 0.01
    import pandas as pd

    ts = pd.read_parquet(tmp_path / "timeseries.parquet")
    assert {f"se3_lambda_{i}" for i in range(1, 7)} <= set(ts.columns)


# --------------------------------------------------------------------------- config
def test_config_composes_with_the_seed_defaults():
    cfg = make_cfg("controller=se3_lie")
    c = cfg.controller
    assert c._target_ == "compliant_docking.control.se3_lie.SE3LieController"
    assert list(c.A_diag) == [10.0, 10.0, 10.0, 1.0, 1.0, 1.0]
    assert list(c.D_diag) == [80.0, 80.0, 80.0, 10.0, 10.0, 10.0]
    assert list(c.K_diag) == [50.0, 50.0, 50.0, 25.0, 25.0, 25.0]
    assert c.null_damping == 10.0 and c.condition_threshold == 1e8
    assert c.use_force_feedback is True and c.formulation.value == "twist"
    with pytest.raises(ConfigCompositionException):
        make_cfg("controller=se3_lie", "controller.formulation=exact")
    with pytest.raises(ConfigCompositionException):
        make_cfg("controller=se3_lie", "controller.stiffnes=3")


@pytest.mark.parametrize(
    "override, message",
    [
        ("controller.A_diag=[10,10,10,1,1,0]", r"controller.A_diag\[5\] must be a finite number > 0"),
        ("controller.K_diag=[50,50,-1,25,25,25]", r"controller.K_diag\[2\] must be a finite number >= 0"),
        ("controller.D_diag=[80,80,80]", "controller.D_diag must have 6 values; got 3"),
        ("controller.null_damping=-1", "controller.null_damping must be a finite number >= 0"),
        ("controller.condition_threshold=0.5", "controller.condition_threshold must be a finite number > 1"),
    ],
)
def test_bad_gains_are_refused_with_a_message(override, message):
    with pytest.raises(ValueError, match=message):
        simulate.prepare(make_cfg(*FREE_SPACE, override))


def test_instantiates_from_the_config_alone():
    sim = simulate.prepare(make_cfg(*FREE_SPACE))
    ctrl = instantiate(make_cfg("controller=se3_lie").controller, _partial_=True, _convert_="all")(
        context=sim.controller.ctx
    )
    assert isinstance(ctrl, SE3LieController)
    assert np.allclose(ctrl.K, np.diag([50.0, 50.0, 50.0, 25.0, 25.0, 25.0]))
