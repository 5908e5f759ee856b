"""The apparent-inertia floor (docs/controllers/impedance.md): what it does to the
delayed force-feedback loop, that it leaves the static compliance alone, and the limit cycle
it removes on a held contact."""

import numpy as np
import pytest

from compliant_docking.control.shaping import ApparentInertiaFloor
from compliant_docking.sim.simulate import prepare
from tests.helpers import FREE_SPACE_HOLD, SHORT_CONTACT, calm, make_cfg, push_at_tcp, steady_contact


def _random_case(seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((6, 6))
    lam = A @ A.T + 0.5 * np.eye(6)  # a task inertia Λ [kg, kg·m²]
    W = np.array([2.0, 2.0, 2.0, 0.2, 0.2, 0.2])  # the FR3's commanded apparent inertia
    return lam, W


def _W_eff_inv(floor, lam):
    """W_eff⁻¹ as a matrix, from apply() (which maps W⁻¹u ↦ W_eff⁻¹u), with J = I so that
    Λ⁻¹ = J M⁻¹ Jᵀ = M⁻¹."""
    Minv = np.linalg.inv(lam)
    W = floor.W_sqrt**2
    columns = []
    for e in np.eye(6):
        floor._step = 0  # refresh on this call
        columns.append(floor.apply(np.eye(6), Minv, e / W))
    return np.column_stack(columns)


def test_the_compiled_refresh_is_the_eigen_decomposition_of_its_definition():
    """P = W^-½ V diag(min(1, μ/ratio)) Vᵀ W^½ with μ, V of W^½Λ⁻¹W^½ (numpy's eigh), None
    where every μ > ratio, on random task inertias: 1e-12 (6×6, condition ≤ ~1e3); the largest
    σ = 1/μ_min to eps·cond relative (Weyl)."""
    rng = np.random.default_rng(9)
    W = np.array([2.0, 2.0, 2.0, 0.2, 0.2, 0.2])
    seen = set()
    for ratio in (0.05, 0.75, 3.0):
        for _ in range(20):
            B = rng.standard_normal((6, 6)) * np.r_[[0.7] * 3, [3.0] * 3]
            lam_inv = B @ B.T + 0.05 * np.eye(6)
            floor = ApparentInertiaFloor(W, ratio)
            floor.refresh(lam_inv)
            mu, V = np.linalg.eigh(lam_inv * np.outer(np.sqrt(W), np.sqrt(W)))
            seen.add(floor.P is not None)
            assert (floor.P is None) == (mu[0] > ratio)
            if floor.P is not None:
                want = (V * np.minimum(mu / ratio, 1.0) / np.sqrt(W)[:, None]) @ (V.T * np.sqrt(W))
                assert np.abs(floor.P - want).max() <= 1e-12 * np.abs(want).max()
                assert floor.max_ratio == pytest.approx(1.0 / mu[0], rel=1e-12 + 1e-15 * mu[-1] / mu[0])
    assert seen == {False, True}  # both outcomes of the positive-definiteness test


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("ratio", [0.5, 0.75, 1.0])
def test_floor_caps_the_delayed_feedback_gain(seed, ratio):
    """Λ W_eff⁻¹ has the eigenvalues min(σ, 1/ratio), σ those of Λ W⁻¹: the feedback gain
    Λ W_eff⁻¹ − I of the one-step-old wrench stays within [−1, 1/ratio − 1], and the
    directions where the arm is light enough keep the commanded inertia exactly."""
    lam, W = _random_case(seed)
    floor = ApparentInertiaFloor(W, ratio)
    W_eff_inv = _W_eff_inv(floor, lam)
    assert np.allclose(W_eff_inv, W_eff_inv.T, atol=1e-12)  # an inertia: symmetric …
    assert np.linalg.eigvalsh(W_eff_inv).min() > 0.0  # … positive definite
    sigma = np.sort(np.linalg.eigvals(lam / W).real)
    assert sigma[-1] > 1.0 / ratio  # the case is one where the floor must act
    got = np.sort(np.linalg.eigvals(lam @ W_eff_inv).real)
    assert np.allclose(got, np.minimum(sigma, 1.0 / ratio), rtol=1e-9)
    # never lighter than commanded: W_eff ⪰ W
    assert np.linalg.eigvalsh(np.linalg.inv(W_eff_inv) - np.diag(W)).min() > -1e-9


def test_floor_leaves_a_heavy_enough_command_untouched():
    """Where W ⪰ ratio·Λ already the input comes back as is (the law of §1, bit for bit)."""
    lam, _ = _random_case(0)
    heavy = np.full(6, 10.0 * np.linalg.eigvalsh(lam).max())
    floor = ApparentInertiaFloor(heavy, 0.6)
    x = np.arange(6.0)
    assert floor.apply(np.eye(6), np.linalg.inv(lam), x) is x
    assert floor.active_steps == 0 and floor.P is None


def test_floor_keeps_the_static_compliance():
    """K and D are untouched: with the floor active a constant push still settles at F/k."""
    sim = prepare(
        make_cfg(
            *FREE_SPACE_HOLD,
            "trajectory.duration=10",
            "controller.m=2",
            "controller.m_rot=0.2",
            "controller.apparent_inertia_floor=0.75",
            "task.progress=false",
        )
    )
    start = sim.scene.arm.tcp_placement(sim.q0)
    force = np.array([2.0, -1.0, 1.5])
    push_at_tcp(sim, force=force)
    sim.run()
    assert sim.controller.inertia_floor.active_steps > 0  # the floor did act
    moved = sim.scene.arm.tcp_placement(sim.data.qpos).translation - start.translation
    expected = force / float(sim.cfg.controller.k)
    # 2 %: the 10 s hold leaves the slowest mode (ζ > 1 at k = 50) within 1 % of rest
    assert np.linalg.norm(moved - expected) < 0.02 * np.linalg.norm(expected)


def test_floor_is_off_without_force_feedback():
    """No force feedback, no delayed-feedback loop: the law stays the specified one."""
    sim = prepare(
        make_cfg(
            *SHORT_CONTACT, "controller.use_force_feedback=false", "controller.apparent_inertia_floor=0.6"
        )
    )
    assert sim.controller.inertia_floor is None


@pytest.mark.parametrize("controller", ["impedance", "se3_lie"])
def test_light_apparent_mass_chatters_without_the_floor_and_not_with_it(controller):
    """The mechanism on a friction-free arm: the iiwa14 (task inertia along the axis
    ≈ 6.8 kg) commanded to 2 kg (Λ/m ≈ 3.4 > 2) bounces on the seat at hundreds of events
    per second under the law as specified; the floor keeps it calm, at k · 5 mm."""
    gains = (
        ("controller.m=2", "controller.m_rot=0.2")
        if controller == "impedance"
        else ("controller.A_diag=[2,2,2,0.2,0.2,0.2]",)
    )
    spec = prepare(
        make_cfg(*SHORT_CONTACT, f"controller={controller}", *gains, "controller.apparent_inertia_floor=null")
    )
    spec.run()
    rate, mean, std = steady_contact(spec)
    assert rate > 50.0 and not calm(rate, mean, std)  # measured ≈ 250 events/s
    floored = prepare(
        make_cfg(*SHORT_CONTACT, f"controller={controller}", *gains, "controller.apparent_inertia_floor=0.6")
    )
    floored.run()
    rate, mean, std = steady_contact(floored)
    assert calm(rate, mean, std) and rate == 0.0
    # pressed home by k · 5 mm (50 N/m); 10 %: the bore's friction holds a little
    assert mean == pytest.approx(50.0 * 0.005, rel=0.1)
