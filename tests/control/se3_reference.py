"""A numpy evaluation of ``controller=se3_lie``'s twist step (docs/control_laws.md §3, the
reduced form of docs/controllers/se3_lie.md), the reference the compiled kernel
(control/se3_kernel.py) is checked against, as tests/control/hqp_reference.py is for HQP.

It is the numpy step the package ran before the kernel took every case: the world vectors
turned to TCP axes by one product, λ by lie's log3 and J(w)⁻¹ coefficients on Python
floats, dexp⁻ᵀKλ in closed form, G = A⁻¹[I, D] as a matrix; Λ by ``numpy.linalg.solve``
and the apparent-inertia floor's P by ``numpy.linalg.eigh`` (no LAPACK shortcuts, no
compiled code). It reads the controller's parameters only and keeps no state: the domain
checks at π and the diagnostics are tested on the controller itself.
"""

from __future__ import annotations

import numpy as np

from compliant_docking.control.lie import inv_coefficients, log3_list


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
    # --- world → TCP (body) axes: one product for every vector
    W = np.zeros((16, 3))
    W[0:3] = ref.rot.T
    W[3] = ref.pos - arm.pos
    W[4:6] = arm.twist.reshape(2, 3)
    W[6:8] = arm.Jdot_v.reshape(2, 3)
    W[8:10] = ref.twist.reshape(2, 3)
    W[10:12] = ref.accel.reshape(2, 3)
    if ctrl.use_force_feedback:
        W[12:14] = np.asarray(wrench, dtype=float).reshape(2, 3)
    W[14:16] = np.asarray(integral_wrench, dtype=float).reshape(2, 3)
    rows = W.dot(arm.rot).tolist()
    F_i = rows.pop(14) + rows.pop(14)
    (
        (c00, c01, c02),
        (c10, c11, c12),
        (c20, c21, c22),
        (e0, e1, e2),
        (pv0, pv1, pv2),
        (pw0, pw1, pw2),
        (ja0, ja1, ja2),
        (jb0, jb1, jb2),
        (dv0, dv1, dv2),
        (dw0, dw1, dw2),
        (da0, da1, da2),
        (db0, db1, db2),
        (f0, f1, f2),
        (m0, m1, m2),
    ) = rows
    # R̃ = RᵀR_d has columns (c00, c01, c02), (c10, …), (c20, …); p̃ = Rᵀ(p_d − p) = e

    # --- λ = log6(T̃) = [J(w)⁻¹p̃; w], w = log3(R̃)
    w0, w1, w2, th = log3_list(c00, c10, c20, c01, c11, c21, c02, c12, c22)
    g, e, dg, de = inv_coefficients(th)  # J(w)⁻¹'s coefficients g, e and g1, e1
    wp = w0 * e0 + w1 * e1 + w2 * e2
    l0 = g * e0 - 0.5 * (w1 * e2 - w2 * e1) + e * wp * w0
    l1 = g * e1 - 0.5 * (w2 * e0 - w0 * e2) + e * wp * w1
    l2 = g * e2 - 0.5 * (w0 * e1 - w1 * e0) + e * wp * w2
    lam = np.array([l0, l1, l2, w0, w1, w2])

    # --- Ad(T̃)V_d = [Rᵀṗ_d − (Rᵀω_d) × p̃; Rᵀω_d]; Ṽ = Ad(T̃)V_d − V
    av0 = dv0 - (dw1 * e2 - dw2 * e1)
    av1 = dv1 - (dw2 * e0 - dw0 * e2)
    av2 = dv2 - (dw0 * e1 - dw1 * e0)
    t0, t1, t2 = av0 - pv0, av1 - pv1, av2 - pv2
    t3, t4, t5 = dw0 - pw0, dw1 - pw1, dw2 - pw2
    # --- base = Ad(T̃)V̇_d + ad(Ṽ)V − J̇_b v + b·V, with ad(Ṽ)V = [w̃×v + ṽ×w; w̃×w],
    #     Ad(T̃)V̇_d = [Rᵀp̈_d − (Rᵀω_d) × (Rᵀṗ_d) − (Rᵀα_d) × p̃; Rᵀα_d]
    #     and J̇_b v = [Rᵀa − (Rᵀω)×(Rᵀṗ); Rᵀα]
    bn = ctrl.null_damping
    aa0 = da0 - (dw1 * dv2 - dw2 * dv1) - (db1 * e2 - db2 * e1)
    aa1 = da1 - (dw2 * dv0 - dw0 * dv2) - (db2 * e0 - db0 * e2)
    aa2 = da2 - (dw0 * dv1 - dw1 * dv0) - (db0 * e1 - db1 * e0)
    o0 = ja0 - (pw1 * pv2 - pw2 * pv1) - bn * pv0  # J̇_b v − b·V
    o1 = ja1 - (pw2 * pv0 - pw0 * pv2) - bn * pv1
    o2 = ja2 - (pw0 * pv1 - pw1 * pv0) - bn * pv2
    o3, o4, o5 = jb0 - bn * pw0, jb1 - bn * pw1, jb2 - bn * pw2
    base = np.array(
        [
            aa0 + t4 * pv2 - t5 * pv1 + t1 * pw2 - t2 * pw1 - o0,
            aa1 + t5 * pv0 - t3 * pv2 + t2 * pw0 - t0 * pw2 - o1,
            aa2 + t3 * pv1 - t4 * pv0 + t0 * pw1 - t1 * pw0 - o2,
            db0 + t4 * pw2 - t5 * pw1 - o3,
            db1 + t5 * pw0 - t3 * pw2 - o4,
            db2 + t3 * pw1 - t4 * pw0 - o5,
        ]
    )

    # --- F̃ = Ad(T̃)⁻ᵀF_d − F_body − [RᵀF_i; RᵀM_i], Ad(T̃)⁻ᵀ[f; m] = [R̃f; p̃ × R̃f + R̃m]
    g0, g1, g2, n0, n1, n2 = np.asarray(ctrl.desired_wrench, dtype=float).tolist()
    r0 = c00 * g0 + c10 * g1 + c20 * g2
    r1 = c01 * g0 + c11 * g1 + c21 * g2
    r2 = c02 * g0 + c12 * g1 + c22 * g2
    F_tilde = (
        np.array(
            [
                r0 - f0,
                r1 - f1,
                r2 - f2,
                e1 * r2 - e2 * r1 + c00 * n0 + c10 * n1 + c20 * n2 - m0,
                e2 * r0 - e0 * r2 + c01 * n0 + c11 * n1 + c21 * n2 - m1,
                e0 * r1 - e1 * r0 + c02 * n0 + c12 * n1 + c22 * n2 - m2,
            ]
        )
        - F_i
    )
    V_tilde = np.array([t0, t1, t2, t3, t4, t5])

    # --- r = F̃ − dexp⁻ᵀKλ: dexp⁻ᵀy = [J⁻ᵀy_v; Qiᵀy_v + J⁻ᵀy_w] with J⁻ᵀy = g y + ½ w×y
    # + e w(w·y) and Qiᵀy = g1 s y + ½ λ_v×y + e(λ_v(w·y) + w(λ_v·y)) + e1 s w(w·y), s = w·λ_v
    y0, y1, y2, y3, y4, y5 = ctrl.K.dot(lam).tolist()
    s = w0 * l0 + w1 * l1 + w2 * l2
    wy = w0 * y0 + w1 * y1 + w2 * y2
    ly = l0 * y0 + l1 * y1 + l2 * y2
    wz = w0 * y3 + w1 * y4 + w2 * y5
    ewy, ewz = e * wy, e * wz
    qs = dg * s
    qw = e * ly + de * s * wy
    r = F_tilde - np.array(
        [
            g * y0 + 0.5 * (w1 * y2 - w2 * y1) + ewy * w0,
            g * y1 + 0.5 * (w2 * y0 - w0 * y2) + ewy * w1,
            g * y2 + 0.5 * (w0 * y1 - w1 * y0) + ewy * w2,
            qs * y0
            + 0.5 * (l1 * y2 - l2 * y1)
            + ewy * l0
            + qw * w0
            + g * y3
            + 0.5 * (w1 * y5 - w2 * y4)
            + ewz * w0,
            qs * y1
            + 0.5 * (l2 * y0 - l0 * y2)
            + ewy * l1
            + qw * w1
            + g * y4
            + 0.5 * (w2 * y3 - w0 * y5)
            + ewz * w1,
            qs * y2
            + 0.5 * (l0 * y1 - l1 * y0)
            + ewy * l2
            + qw * w2
            + g * y5
            + 0.5 * (w0 * y4 - w1 * y3)
            + ewz * w2,
        ]
    )
    # --- a = V̇_ref − J̇_b v + b·V = base − A⁻¹(r − D·Ṽ) = base − G·[r; −Ṽ]
    a = base - ctrl.G.dot(np.concatenate([r, -V_tilde]))

    # --- J_b, Λ⁻¹ and the floor: a = base + P(a − base)
    Jb = np.vstack([arm.rot_T @ arm.J[:3], arm.rot_T @ arm.J[3:]])
    lam_inv = Jb @ arm.Minv @ Jb.T
    if isinstance(P, str):
        P = floor_P(ctrl, lam_inv)
    if P is not None:
        a = base + P.dot(a - base)
    # --- τ = J_bᵀ[Λ(V̇_ref − J̇_b v + bV) − F_body] − b·M v + h (+ friction feed-forward)
    force = np.linalg.solve(lam_inv, a)
    if ctrl.use_force_feedback:
        force -= np.array([f0, f1, f2, m0, m1, m2])
    tau = force.dot(Jb) + arm.h - bn * arm.M.dot(arm.v)
    if ctrl.friction.active:
        tau += ctrl.friction(tau, arm.v, arm.h)
    return {
        "lam": lam,
        "V_tilde": V_tilde,
        "F_tilde": F_tilde,
        "base": base,
        "Vdot_ref": a + np.array([o0, o1, o2, o3, o4, o5]),
        "tau": tau,
        "P": P,
    }
