"""Shared controller pieces: task-space inertia with its fallback, friction feed-forward."""

import numpy as np
import pytest

from compliant_docking.config import FrictionComp
from compliant_docking.control.base import FrictionFeedForward, TaskInertia


def test_task_inertia_solves_exactly_when_well_conditioned():
    rng = np.random.default_rng(0)
    J = rng.standard_normal((6, 7))
    A = rng.standard_normal((7, 7))
    Minv = np.linalg.inv(A @ A.T + 7 * np.eye(7))
    rhs = rng.standard_normal(6)
    inertia = TaskInertia(1e8)
    for _ in range(12):  # across the conditioning checks
        x = inertia.solve(J, J @ Minv, rhs)
        assert np.allclose((J @ Minv @ J.T) @ x, rhs, atol=1e-10)
    assert inertia.fallback_steps == 0
    assert 1.0 < inertia.max_condition < 1e8


def test_task_inertia_falls_back_at_a_singularity():
    rng = np.random.default_rng(1)
    J = rng.standard_normal((6, 7))
    J[5] = J[4]  # two identical task rows: J M⁻¹ Jᵀ is singular
    Minv = np.eye(7)
    inertia = TaskInertia(1e6)
    x = inertia.solve(J, J @ Minv, np.ones(6))
    assert np.all(np.isfinite(x))
    assert inertia.fallback_steps == 1
    # the damped inverse caps the condition number at the threshold
    damped = inertia.damped(J @ Minv @ J.T)
    eig = np.linalg.eigvalsh(damped)
    assert eig.max() / eig.min() <= 1.0001e6


def test_friction_feedforward_modes():
    f = np.array([1.0, 0.0, 0.5])
    b = np.array([0.2, 0.0, 0.1])
    v = np.array([0.3, 1.0, -0.02])
    tau = np.array([-4.0, 2.0, 0.1])
    torque = FrictionFeedForward(f, b, FrictionComp.torque)(tau, v)
    assert np.allclose(torque, f * np.tanh(2 * tau / np.where(f > 0, f, 1)) + b * v)
    assert torque[1] == 0.0  # a joint without friction gets nothing
    velocity = FrictionFeedForward(f, b, FrictionComp.velocity)(tau, v)
    assert np.allclose(velocity, f * np.tanh(v / 0.01) + b * v)
    assert not FrictionFeedForward(np.zeros(3), np.zeros(3), FrictionComp.torque).active


def test_friction_feedforward_unbiased_mode_ignores_the_bias_torques():
    """``torque_unbiased``: the torque mode on τ_pre − h, h the step's bias torques. A
    gravity-holding command (τ_pre = h) gets no friction push; the motion part does."""
    f = np.array([1.0, 0.0, 0.5])
    b = np.array([0.2, 0.0, 0.1])
    v = np.array([0.3, 1.0, -0.02])
    h = np.array([-30.0, 5.0, 17.0])  # e.g. gravity on loaded joints
    ff = FrictionFeedForward(f, b, FrictionComp.torque_unbiased)
    assert np.allclose(ff(h.copy(), v, h), b * v)  # holding torque only: damping term only
    tau = h + np.array([0.3, -1.0, -0.2])
    expected = f * np.tanh(2 * (tau - h) / np.where(f > 0, f, 1)) + b * v
    assert np.allclose(ff(tau, v, h), expected)
    # with h = 0 (zero gravity, at rest) it is the torque mode
    assert np.allclose(ff(tau, v, np.zeros(3)), FrictionFeedForward(f, b, FrictionComp.torque)(tau, v))
    with pytest.raises(ValueError, match="torque_unbiased"):
        ff(tau, v)


def test_friction_feedforward_yielding_never_pushes_against_the_motion():
    """``yielding``: torque_unbiased on a joint at rest or moving with it; on a joint moving
    against it, scaled by 1 − |v|/0.02 rad/s and off from 0.02 rad/s on. So beyond the
    damping term b·v it never opposes a motion faster than 0.02 rad/s (a joint the contact
    drives against the command, e.g. the plug pushed sideways by the funnel)."""
    f = np.array([1.0, 1.0, 1.0, 1.0, 0.0])
    b = np.array([0.2, 0.2, 0.2, 0.2, 0.0])
    h = np.array([-30.0, 5.0, 17.0, 0.0, 1.0])
    tau = h + np.array([0.3, 0.3, -0.2, 0.4, 2.0])  # the command beyond h: + + − +
    v = np.array([0.0, 0.05, 0.05, -0.01, 1.0])  # at rest, with, against, half-speed against
    ff = FrictionFeedForward(f, b, FrictionComp.yielding)
    unbiased = np.tanh(2 * (tau - h) / np.where(f > 0, f, 1))
    expected = f * unbiased * np.array([1.0, 1.0, 0.0, 0.5, 1.0]) + b * v
    assert np.allclose(ff(tau.copy(), v, h), expected)
    rng = np.random.default_rng(3)
    for _ in range(200):  # random commands and speeds: (ff − b·v)·v ≥ 0 wherever |v| ≥ 0.02
        v = rng.standard_normal(5) * 0.05
        moved = ff(h + rng.standard_normal(5), v, h) - b * v
        fast = np.abs(v) >= FrictionFeedForward.YIELD_SPEED
        assert np.all(moved[fast] * v[fast] >= 0.0)
