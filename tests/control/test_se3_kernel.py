"""``controller=se3_lie``'s compiled step (control/se3_kernel.py) against the numpy reference
(tests/control/se3_reference.py) and against its own λ-space finish.

Tolerances:
* the kernel against the numpy reference: 1e-10 relative: the same formulas, products summed
  in another order and Λ applied by another solve (condition ≤ ~1e4: round-off ~1e-12);
* the twist formulation against ``formulation=lambda_space`` (the literal law's λ-space route
  on the kernel's prelude): 1e-9 relative, the literal-law tolerance of test_se3_lie.py (the
  two evaluate the law by different formulas);
* diagnostics that count steps: equal.
"""

import copy
import math

import numpy as np
import pinocchio as pin
import pytest
from omegaconf import OmegaConf

from compliant_docking.config import FrictionComp
from compliant_docking.control import se3_kernel
from compliant_docking.control.se3_lie import SE3LieController
from compliant_docking.planning.base import Reference
from compliant_docking.sim import simulate
from tests.control.se3_reference import floor_P, reference_step
from tests.control.test_se3_lie import random_case, random_spd
from tests.helpers import make_cfg

FR3 = ("robot=fr3", "controller=se3_lie", "task.progress=false")
REL = 1e-9


def close(a, b, rel):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) <= rel * max(1.0, np.max(np.abs(b)))


def _pair(sim):
    """The FR3's se3_lie (floor, integral action on position and orientation, friction yielding) as configured, twice:
    twist (compiled step) and lambda_space (numpy)."""
    params = OmegaConf.to_container(sim.cfg.controller, resolve=True)
    params.pop("_target_")
    assert params["apparent_inertia_floor"] and params["integral_gain"] and params["integral_rot_gain"]
    assert params["friction_comp"] == FrictionComp.yielding and sim.controller.friction.active
    make = lambda form: SE3LieController(sim.controller.ctx, **{**params, "formulation": form})  # noqa: E731
    return make("twist"), make("lambda_space")


def _case(arm, rng, angle, axis=None):
    q = arm.q_lower + (arm.q_upper - arm.q_lower) * rng.uniform(0.3, 0.7, arm.nv)
    arm.update(q, rng.uniform(-0.5, 0.5, arm.nv))
    axis = rng.standard_normal(3) if axis is None else axis
    ref = Reference()
    ref.rot[:] = arm.rot @ pin.exp3(angle * axis / np.linalg.norm(axis))
    ref.pos[:] = arm.pos + rng.uniform(-0.02, 0.02, 3)
    ref.twist[:] = rng.uniform(-0.3, 0.3, 6)
    ref.accel[:] = rng.uniform(-1.0, 1.0, 6)
    wrench = rng.uniform(-3.0, 3.0, 6)
    wrench[:3] *= rng.uniform() < 0.5  # the integral freezes above its force: both branches
    return ref, wrench


def test_compiled_step_matches_lambda_space_on_the_fr3(monkeypatch):
    """25 steps on random states: full compiled steps and the staged ones (TaskInertia's check,
    the floor's refresh: steps 0, 10, 20) give the torques of the λ-space finish (every step
    staged); the integral, the floor and the conditioning diagnostics evolve alike."""
    sim = simulate.prepare(make_cfg(*FR3))
    arm = sim.scene.arm
    fast, slow = _pair(sim)
    assert fast._kernel.lambda_finish is None and slow._kernel.lambda_finish is not None
    modes = []
    step = se3_kernel.step
    monkeypatch.setattr(se3_kernel, "step", lambda mode, *a: modes.append(mode) or step(mode, *a))
    rng = np.random.default_rng(12)
    for k in range(25):
        ref, wrench = _case(arm, rng, rng.uniform(0.0, 1.2))
        tau = fast.compute(0.001 * k, arm, ref, wrench)
        assert close(tau, slow.compute(0.001 * k, arm, ref, wrench), REL), k
        assert slow.lam_ddot_ref is not None  # the λ-space finish ran
        for name in ("lam", "V_tilde", "F_tilde", "Vdot_ref"):
            assert close(getattr(fast, name), getattr(slow, name), REL), (k, name)
    staged = [k for k, m in enumerate(modes[0::2]) if m == se3_kernel.STAGE]  # the twist's calls
    assert staged == [0, 10, 20] and set(modes[1::2]) == {se3_kernel.STAGE}
    assert fast.inertia_floor.active_steps == slow.inertia_floor.active_steps > 0
    assert fast.integral.state == pytest.approx(slow.integral.state, rel=1e-12)
    assert fast.integral.rot_state == pytest.approx(slow.integral.rot_state, rel=1e-12)
    assert fast.integral.torque == pytest.approx(slow.integral.torque, rel=1e-12)
    assert any(fast.integral.torque)  # the orientation part integrated before it latched
    assert fast.task_inertia._step == slow.task_inertia._step == 25
    d_fast, d_slow = fast.diagnostics(), slow.diagnostics()
    assert d_fast.keys() == d_slow.keys()
    for key in d_fast:
        assert d_fast[key] == pytest.approx(d_slow[key], rel=1e-9), key
    assert close(fast.timeseries()["se3_lambda"], slow.timeseries()["se3_lambda"], REL)


def test_singular_task_inertia_takes_the_fallback_as_in_numpy():
    """A Jacobian with a zero row (Λ⁻¹ singular) on a step without a conditioning check: the
    kernel's Cholesky fails and TaskInertia's damped pseudo-inverse takes the step, as in numpy."""
    sim = simulate.prepare(make_cfg(*FR3))
    arm = sim.scene.arm
    fast, slow = _pair(sim)
    rng = np.random.default_rng(3)
    for k in range(3):
        ref, wrench = _case(arm, rng, 0.3)
        if k == 2:  # step 2, no check due: the TCP's axes the world's, J's last row zero, so
            # J_b's last row and Λ⁻¹'s last row and column are exactly zero (a zero pivot)
            # the rotation column-major, as pinocchio gives it: the compiled step's own signature
            # (a C-ordered one would compile a second signature, for this test alone)
            arm.rot = np.eye(3, order="F")
            arm.rot_T = arm.rot.T
            arm.J = arm.J.copy()
            arm.J[5] = 0.0
        assert close(fast.compute(0.0, arm, ref, wrench), slow.compute(0.0, arm, ref, wrench), REL)
    assert fast.task_inertia.fallback_steps == slow.task_inertia.fallback_steps == 1
    assert math.isinf(fast.diagnostics()["lambda_max_condition"])


def test_domain_errors_keep_their_messages():
    sim = simulate.prepare(make_cfg(*FR3))
    arm = sim.scene.arm
    fast, _ = _pair(sim)
    rng = np.random.default_rng(1)
    axis = np.array([0.3, -1.0, 0.5])
    for _ in range(2):  # steps 0 (staged) and 1 (full): 2 rad about +axis
        fast.compute(0.0, arm, *_case(arm, rng, 2.0, axis))
    with pytest.raises(ValueError, match=r"se3_lie at t = 0\.250 s: .*flipped from 2 rad"):
        fast.compute(0.25, arm, *_case(arm, rng, 2.0, -axis))
    with pytest.raises(ValueError, match=r"se3_lie at t = 0\.500 s: .*π"):
        fast.compute(0.5, arm, *_case(arm, rng, math.pi, axis))


@pytest.mark.parametrize("gains", ["diagonal", "general"])
def test_kernel_matches_the_numpy_reference(gains):
    """The compiled step against the numpy twist step (tests/control/se3_reference.py) on
    random states, orientation errors in both coefficient branches and a desired wrench:
    the FR3's friction feed-forward and integral action (position and orientation); diagonal
    gains with the apparent-inertia floor, and general symmetric A, D, K (no floor: it needs a
    diagonal A)."""
    sim = simulate.prepare(make_cfg(*FR3))  # the FR3: joint friction, a feed-forward
    arm = sim.scene.arm
    rng = np.random.default_rng(5)
    F_d = np.array([1.0, -2.0, 0.5, 0.1, 0.05, -0.2])
    params = OmegaConf.to_container(sim.cfg.controller, resolve=True)
    params.pop("_target_")
    if gains == "diagonal":  # light enough for the floor to act on some states
        A, D, K = np.diag([2.0, 2.5, 3.0, 0.2, 0.25, 0.3]), np.diag([40.0, 50.0, 60.0, 4.0, 5.0, 6.0]), None
        extra = {"apparent_inertia_floor": 0.75, "friction_comp": FrictionComp.torque_unbiased}
    else:
        A = random_spd(rng, [10.0, 10.0, 10.0, 1.0, 1.0, 1.0])
        D = random_spd(rng, [80.0, 80.0, 80.0, 10.0, 10.0, 10.0])
        K = random_spd(rng, [50.0, 50.0, 50.0, 25.0, 25.0, 25.0])
        extra = {"apparent_inertia_floor": None}
    kwargs = {**params, **extra, "A": A, "D": D, "desired_wrench": F_d, "null_damping": 7.0}
    if K is not None:
        kwargs["K"] = K
    ctrl = SE3LieController(sim.controller.ctx, **kwargs)
    active, compared = [], 0
    for k in range(24):
        ref, wrench = random_case(arm, rng, (0.0, 1e-3, 0.3, 2.0)[k % 4])
        wrench *= 0.1  # below the integral's freeze force (1 N): it integrates every step
        # the integral wrench [F_i; M_i] of this step, from a copy of the integral action
        F_i = copy.deepcopy(ctrl.integral).update_pose(ref.pos - arm.pos, wrench, ref.rot, arm.rot_T)
        tau = ctrl.compute(0.0, arm, ref, wrench)
        floor = ctrl.inertia_floor
        P = None if floor is None else floor.P
        want = reference_step(ctrl, arm, ref, wrench, F_i, P=P)
        for name in ("lam", "V_tilde", "F_tilde", "Vdot_ref"):
            assert close(getattr(ctrl, name), want[name], 1e-10), (k, name)
        if np.linalg.cond(want_lam_inv(ctrl, arm)) < 1e6:  # a random posture may be near-singular
            compared += 1
            assert close(tau, want["tau"], 1e-10), k
        if floor is not None and k % floor.every == 0:  # refreshed here: the numpy P
            want_P = floor_P(ctrl, want_lam_inv(ctrl, arm))
            assert (P is None) == (want_P is None), k
            if P is not None:
                assert close(P, want_P, 1e-10), k
            active.append(P is not None)
    assert compared >= 16
    assert np.all(ctrl.integral.state) and np.all(ctrl.integral.torque)  # the integral acted
    if gains == "diagonal":
        assert ctrl.friction.active and True in active  # the floor acted on a refresh
    assert not np.any(ctrl.K - np.diag(np.diag(ctrl.K))) == (gains == "diagonal")


def want_lam_inv(ctrl, arm):
    Jb = np.vstack([arm.rot_T @ arm.J[:3], arm.rot_T @ arm.J[3:]])
    return Jb @ arm.Minv @ Jb.T
