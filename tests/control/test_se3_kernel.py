"""``controller=se3_lie``'s compiled step (control/se3_kernel.py) against the numpy evaluations
it replaces, and its twins of numpy pieces other laws use.

Tolerances:
* twins (friction feed-forward, the Cholesky solve) against the numpy/LAPACK pieces: 1e-12
  relative: the same formulas, summed in another order (6×6 with condition ≤ ~1e3: round-off
  ~1e-13 relative);
* the compiled twist step against ``formulation=lambda_space`` (the literal law in numpy, the
  same controller otherwise): 1e-9 relative, the literal-law tolerance of test_se3_lie.py (the
  two evaluate the law by different formulas);
* diagnostics that count steps: equal.
"""

import math

import numpy as np
import pinocchio as pin
import pytest
from omegaconf import OmegaConf

from compliant_docking.config import FrictionComp
from compliant_docking.control import se3_kernel
from compliant_docking.control.se3_lie import SE3LieController
from compliant_docking.control.shaping import ApparentInertiaFloor
from compliant_docking.planning.base import Reference
from compliant_docking.sim import simulate
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
    the floor's refresh: steps 0, 10, 20) give λ̈-space's torques; the integral, the floor and
    the conditioning diagnostics evolve alike."""
    sim = simulate.prepare(make_cfg(*FR3))
    arm = sim.scene.arm
    fast, slow = _pair(sim)
    assert fast._kernel is not None and slow._kernel is None
    modes = []
    step = se3_kernel.step
    monkeypatch.setattr(se3_kernel, "step", lambda mode, *a: modes.append(mode) or step(mode, *a))
    rng = np.random.default_rng(12)
    for k in range(25):
        ref, wrench = _case(arm, rng, rng.uniform(0.0, 1.2))
        tau = fast.compute(0.001 * k, arm, ref, wrench)
        assert close(tau, slow.compute(0.001 * k, arm, ref, wrench), REL), k
        for name in ("lam", "V_tilde", "F_tilde", "Vdot_ref"):
            assert close(getattr(fast, name), getattr(slow, name), REL), (k, name)
    staged = [k for k, m in enumerate(modes) if m == se3_kernel.STAGE]
    assert staged == [0, 10, 20]
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


def test_floor_refresh_twin_matches_the_numpy_floor():
    rng = np.random.default_rng(9)
    W = np.array([2.0, 2.0, 2.0, 0.2, 0.2, 0.2])
    active_seen = set()
    for ratio in (0.05, 0.75, 3.0):
        for _ in range(20):
            B = rng.standard_normal((6, 6)) * np.r_[[0.7] * 3, [3.0] * 3]
            lam_inv = B @ B.T + 0.05 * np.eye(6)
            floor = ApparentInertiaFloor(W, ratio)
            floor.refresh(lam_inv)
            PI, mem = np.zeros((6, 12)), np.zeros(se3_kernel.mem_size(7))
            active = se3_kernel.floor_refresh(lam_inv, floor._w_sqrt, floor._w_isqrt, ratio, PI, mem)
            assert active == (floor.P is not None)
            active_seen.add(active)
            if active:  # P to 1e-12; σ_max = 1/μ_min, μ_min to eps·cond(T) relative (Weyl)
                assert close(PI[:, :6], floor.P, 1e-12)
                cond = np.linalg.cond(lam_inv * np.outer(floor._w_sqrt, floor._w_sqrt))
                rel = 1e-12 + 1e-15 * cond
                assert mem[se3_kernel.FLOOR_MAX_RATIO] == pytest.approx(floor.max_ratio, rel=rel)
    assert active_seen == {False, True}  # both outcomes of the positive-definiteness test
