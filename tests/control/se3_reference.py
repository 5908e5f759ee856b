"""A numpy evaluation of ``controller=se3_lie``'s twist step (docs/control_laws.md §3, the
reduced form of docs/controllers/se3_lie.md), the reference the compiled kernel
(control/se3_kernel.py) is checked against, as tests/control/hqp_reference.py is for HQP.

It is the numpy twist step the package ran for general gains before the kernel took every
case, written with vectors and matrices instead of the kernel's scalars: the world vectors
turned to TCP axes, λ = log6(T̃) by Pinocchio, the cross products by ``numpy.cross``,
dexp⁻ᵀKλ by lie's closed-form dexp⁻¹ as a matrix, G = A⁻¹[I, D] as a matrix, Λ by
``numpy.linalg.solve`` and the apparent-inertia floor's P by ``numpy.linalg.eigh`` (no LAPACK
shortcuts, no compiled code). It reads the controller's parameters only and keeps no state:
the domain checks at π and the diagnostics are tested on the controller itself.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from compliant_docking.control import lie


def floor_P(ctrl, lam_inv):
    """The floor's P = W_eff⁻¹W for Λ⁻¹ (None when W ⪰ ratio·Λ already or no floor)."""
    floor = ctrl.inertia_floor
    if floor is None:
        return None
    w_sqrt = np.sqrt(np.diag(ctrl.A))
    mu, V = np.linalg.eigh(lam_inv * np.outer(w_sqrt, w_sqrt))  # μ = 1/σ
    if mu[0] > floor.ratio:
        return None
    c = np.minimum(mu / floor.ratio, 1.0)
    return (V * c / w_sqrt[:, None]) @ (V.T * w_sqrt)


def reference_step(ctrl, arm, ref, wrench, integral_wrench=(0.0,) * 6, P="compute") -> dict:
    """The law's quantities at this step for the SE3LieController ``ctrl`` (its parameters):
    λ, Ṽ, F̃, base, V̇_ref and τ. ``integral_wrench``: [F_i; M_i] of this step (world axes);
    ``P``: the floor's P to apply (None: off), or computed from this step's Λ⁻¹."""
    Rt = arm.rot_T
    # --- world → TCP (body) axes
    e = Rt @ (ref.pos - arm.pos)  # p̃ = Rᵀ(p_d − p)
    R_err = Rt @ ref.rot  # R̃ = RᵀR_d
    v, w = Rt @ arm.twist[:3], Rt @ arm.twist[3:]  # body twist V = [v; w]
    ja, jb = Rt @ arm.Jdot_v[:3], Rt @ arm.Jdot_v[3:]
    dv, dw = Rt @ ref.twist[:3], Rt @ ref.twist[3:]
    da, db = Rt @ ref.accel[:3], Rt @ ref.accel[3:]
    F_body = np.zeros(6)
    if ctrl.use_force_feedback:
        F_body = np.concatenate([Rt @ wrench[:3], Rt @ wrench[3:]])
    F_i = np.asarray(integral_wrench, dtype=float)
    F_i = np.concatenate([Rt @ F_i[:3], Rt @ F_i[3:]])

    # --- λ = log6(T̃), T̃ = T⁻¹T_d = (R̃, p̃)
    lam = pin.log6(pin.SE3(R_err, e)).vector
    # --- Ṽ = Ad(T̃)V_d − V, Ad(T̃)V_d = [Rᵀṗ_d − (Rᵀω_d) × p̃; Rᵀω_d]
    tv, tw = dv - np.cross(dw, e) - v, dw - w
    V_tilde = np.concatenate([tv, tw])
    # --- base = Ad(T̃)V̇_d + ad(Ṽ)V − J̇_b v + b·V, with
    #     Ad(T̃)V̇_d = [Rᵀp̈_d − (Rᵀω_d) × (Rᵀṗ_d) − (Rᵀα_d) × p̃; Rᵀα_d],
    #     ad(Ṽ)V = [w̃ × v + ṽ × w; w̃ × w], J̇_b v = [Rᵀa − (Rᵀω) × (Rᵀṗ); Rᵀα]
    b = ctrl.null_damping
    offset = np.concatenate([ja - np.cross(w, v) - b * v, jb - b * w])  # J̇_b v − b·V
    Ad_Vd_dot = np.concatenate([da - np.cross(dw, dv) - np.cross(db, e), db])
    ad_V = np.concatenate([np.cross(tw, v) + np.cross(tv, w), np.cross(tw, w)])
    base = Ad_Vd_dot + ad_V - offset
    # --- F̃ = Ad(T̃)⁻ᵀF_d − F_body − [RᵀF_i; RᵀM_i], Ad(T̃)⁻ᵀ[f; m] = [R̃f; p̃ × R̃f + R̃m]
    F_d = np.asarray(ctrl.desired_wrench, dtype=float)
    f_d = R_err @ F_d[:3]
    F_tilde = np.concatenate([f_d, np.cross(e, f_d) + R_err @ F_d[3:]]) - F_body - F_i
    # --- a = V̇_ref − J̇_b v + b·V = base − A⁻¹(F̃ − D·Ṽ − dexp⁻ᵀKλ) = base − G·[r; −Ṽ]
    r = F_tilde - lie.dexp_inv(lam).T @ (ctrl.K @ lam)
    a = base - ctrl.G @ np.concatenate([r, -V_tilde])

    # --- J_b, Λ⁻¹ and the floor: a = base + P(a − base)
    Jb = np.vstack([Rt @ arm.J[:3], Rt @ arm.J[3:]])
    lam_inv = Jb @ arm.Minv @ Jb.T
    if isinstance(P, str):
        P = floor_P(ctrl, lam_inv)
    if P is not None:
        a = base + P @ (a - base)
    # --- τ = J_bᵀ[Λ(V̇_ref − J̇_b v + bV) − F_body] − b·M v + h (+ friction feed-forward)
    force = np.linalg.solve(lam_inv, a) - F_body
    tau = Jb.T @ force + arm.h - b * arm.M @ arm.v
    if ctrl.friction.active:
        tau += ctrl.friction(tau, arm.v, arm.h)
    return {
        "lam": lam,
        "V_tilde": V_tilde,
        "F_tilde": F_tilde,
        "base": base,
        "Vdot_ref": a + offset,
        "tau": tau,
        "P": P,
    }
