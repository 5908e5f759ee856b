"""HQP-AC's compiled step (control/hqp/kernel.py) against the plain-numpy evaluation of the
law in tests/control/hqp_reference.py, on random states of both arms, and the kernel's
compiled twins against the numpy pieces they copy.

Tolerances: the kernel sums the same products in other orders and takes its
eigendecomposition from LAPACK dsyevd on another triangle than numpy does; at random
postures cond(Λ⁻¹) reaches 1e6 and more, and Λ, Λ^½ and what follows carry ~1e-16·cond
relative round-off (N a_null cancels most of a_null). The bounds (RTOL, COND_RTOL·cond,
relative to each quantity's largest entry) still catch any wrong or dropped term, which
moves a result by ≫ 1e-6 relative.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from compliant_docking.config import FrictionComp
from compliant_docking.control.hqp.compliance import PreloadRamp
from compliant_docking.planning.base import Reference
from compliant_docking.sim.simulate import prepare
from tests.control.hqp_reference import reference_step
from tests.helpers import make_cfg

RTOL = 1e-12  # quantities that do not go through Λ's eigendecomposition
#: per unit of cond(Λ⁻¹) for those that do (Λ, D_r, b and what follows): eigenvectors of a
#: matrix with condition number c carry ~1e-16·c relative round-off (measured: up to
#: 1.4e-14·c on N a_null); about 10× margin
COND_RTOL = 1e-13
CONDITIONED = {"lam", "D", "b", "qdd", "a_null", "Na", "hhat", "Z", "tau"}


def _close(actual, expected, what, cond=0.0, scale=0.0):
    """Within max(RTOL, COND_RTOL·cond(Λ⁻¹)) of the largest entry (module doc), or of
    ``scale`` when larger (N a_null = a_null − …: the size of the terms that cancel)."""
    scale = max(np.abs(expected).max(), scale, 1e-300)
    atol = max(RTOL, COND_RTOL * cond) * scale
    np.testing.assert_allclose(actual, expected, rtol=0, atol=atol, err_msg=what)


def _random_reference(rng, arm) -> Reference:
    ref = Reference()
    ref.pos[:] = arm.pos + rng.normal(scale=0.01, size=3)
    axis = rng.normal(size=3)
    ref.rot[:] = arm.rot @ _rotation(0.05 * axis)
    ref.twist[:] = rng.normal(scale=0.05, size=6)
    ref.accel[:] = rng.normal(scale=0.1, size=6)
    return ref


def _rotation(phi):
    import pinocchio as pin

    return pin.exp3(np.asarray(phi, dtype=float))


def _log3(R):
    import pinocchio as pin

    return pin.log3(R)


def _check_steps(robot: str, *overrides: str, steps: int = 40, seed: int = 0, slow_ok=True) -> dict:
    """``steps`` random states through ctrl.compute; every buffer the constrained path reads
    compared with the reference. Returns how often each branch was taken."""
    sim = prepare(make_cfg("controller=hqp", f"robot={robot}", "task.progress=false", *overrides))
    arm, ctrl = sim.scene.arm, sim.controller
    rng = np.random.default_rng(seed)
    ramp = PreloadRamp(ctrl.preload.target, 1.0, 1.0)  # same target; its step below
    ramp.state[2] = ctrl.preload.state[2]
    seen = {"floored": 0, "modal": 0, "singular": 0, "fast": 0}
    twin = None if ctrl.integral is None else copy.deepcopy(ctrl.integral)
    n = ctrl.n
    for k in range(steps):
        q = rng.uniform(np.maximum(arm.q_lower, -3.0), np.minimum(arm.q_upper, 3.0))
        # small speeds in half the states, so that some steps meet every row
        v = rng.normal(scale=0.3 if k % 2 else 1e-3, size=n)
        arm.update(q, v)
        ref = _random_reference(rng, arm)
        wrench = rng.normal(scale=2.0, size=6) if k % 3 else np.zeros(6)
        integral = (0.0,) * 6
        if twin is not None:  # the integral action the kernel runs, in Python
            rot_err = _log3(ref.rot @ arm.rot.T)
            integral = twin.step(ref.pos - arm.pos, wrench, rot_err)
        F = max(np.linalg.norm(wrench) - ctrl.deadband, 0.0)
        expected = reference_step(ctrl, arm, ref, wrench, ramp.update(F), integral)
        before = ctrl._fast_steps, ctrl.lambda_floor_steps, ctrl.modal_damping_steps, ctrl.singularity_steps
        tau = ctrl.compute(0.0, arm, ref, wrench)
        after = ctrl._fast_steps, ctrl.lambda_floor_steps, ctrl.modal_damping_steps, ctrl.singularity_steps
        fast = bool(expected["within"].all())
        assert [a - b for a, b in zip(after, before)] == [
            fast,
            expected["floored"],
            expected["modal"],
            expected["singular"],
        ]
        seen["fast"] += fast
        for key in ("floored", "modal", "singular"):
            seen[key] += bool(expected[key])
        rec = ctrl._rec[k]
        np.testing.assert_allclose([rec["F"], rec["s"]], [expected["F"], expected["s"]], rtol=1e-12)
        np.testing.assert_allclose(rec["w"], expected["w"], rtol=1e-9)
        for key, actual in (
            ("JMinv", ctrl._JMinv),
            ("lam", ctrl._lam),
            ("D", ctrl._D),
            ("b", ctrl._b),
            ("qdd", ctrl._X[0]),
            ("a_null", ctrl._a_null),
            ("Na", ctrl._Na),
            ("hhat", ctrl._hhat),
        ):
            cond = expected["cond"] if key in CONDITIONED else 0.0
            _close(actual, expected[key], key, cond, np.abs(expected["a_null"]).max() if key == "Na" else 0.0)
        if twin is not None:  # the integral's record, advanced by the kernel and by Python
            assert ctrl.integral.diagnostics() == twin.diagnostics()
            assert ctrl.integral.state == twin.state
            assert ctrl.integral.rot_state == twin.rot_state
        if fast:
            _close(tau, expected["Z"][1, 2 * n :], "tau", expected["cond"])
            _close(ctrl._Z, expected["Z"], "Z", expected["cond"])
    return seen


@pytest.mark.parametrize("robot", ["iiwa14", "fr3"])
@pytest.mark.parametrize("metric", ["inertia", "euclidean"])
def test_kernel_matches_the_reference(robot, metric):
    seen = _check_steps(robot, f"controller.null_space_metric={metric}")
    assert seen["fast"] > 0 and seen["singular"] > 0  # both branches were exercised


@pytest.mark.parametrize("mode", [m.value for m in FrictionComp])
def test_kernel_matches_the_reference_with_preload_integral_and_each_friction_mode(mode):
    _check_steps(
        "fr3",
        f"controller.friction_comp={mode}",
        "controller.preload_force=5",
        "controller.preload_ramp_s=0.01",
        "controller.integral_gain=50",
        "controller.contact_deadband=0.5",
        steps=30,
        seed=1,
    )


def test_kernel_integral_action_lateral_and_clamped():
    """The integral action's other branches: lateral only, and limits of 0.05 N and
    0.002 N·m that clamp after a few steps (its state and diagnostics compared exactly in
    _check_steps)."""
    _check_steps(
        "iiwa14",
        "controller.integral_gain=2000",
        "controller.integral_limit=0.05",
        "controller.integral_rot_gain=500",
        "controller.integral_rot_limit=0.002",
        "controller.integral_lateral_only=true",
        "controller.integral_freeze_force=3",
        steps=30,
        seed=4,
    )


def test_kernel_integral_action_unlatched():
    """The research code's freeze (only while ‖f‖ exceeds the freeze force), the branch the
    default latch skips once it froze."""
    _check_steps(
        "iiwa14",
        "controller.integral_gain=2000",
        "controller.integral_latch=false",
        "controller.integral_rot_gain=100",
        "controller.integral_freeze_force=3",
        steps=30,
        seed=4,
    )


def test_kernel_floor_branch():
    """A condition threshold of 10 floors Λ⁻¹ at every random state."""
    seen = _check_steps("iiwa14", "controller.condition_threshold=10", steps=30, seed=2)
    assert seen["floored"] == 30


def test_kernel_modal_damping_branch():
    """A stiffness spread over 1e6 makes Eq. 29's D_r indefinite at (nearly) every random
    posture: the modal design written back from Python, then the rest of the kernel."""
    seen = _check_steps("iiwa14", "controller.K0=[1e5,1e5,1e5,0.1,0.1,0.1]", steps=20, seed=3)
    assert seen["modal"] > 10


def test_a_non_finite_state_gives_a_non_finite_torque_not_an_exception():
    """As the numpy law did: τ is NaN, and the loop stops the run as diverged with its own
    message (numba's eigh would raise "Array must not contain infs or NaNs" instead)."""
    sim = prepare(make_cfg("robot=fr3", "controller=hqp"))
    arm, ctrl = sim.scene.arm, sim.controller
    ref = Reference()
    sim.planner.sample(0.0, ref)
    q = sim.q0.copy()
    q[2] = np.nan
    arm.update(q, np.zeros(arm.nv))
    tau = ctrl.compute(0.0, arm, ref, np.zeros(6))
    assert tau.shape == (arm.nv,) and np.isnan(tau).all()
    assert ctrl.steps == 1
