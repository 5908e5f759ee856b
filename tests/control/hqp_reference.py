"""A plain-numpy evaluation of HQP-AC's per-step closed-form path (docs/control_laws.md §2),
written from the law (numpy.linalg, no LAPACK shortcuts, no compiled code): the reference
the compiled step kernel (control/hqp/kernel.py) is checked against.

It reads the controller's parameters only (gains, limits, the friction feed-forward
object of control/base.py) and evaluates the law from the arm's state.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from compliant_docking.control.hqp.compliance import modal_damping, stiffness_scale
from compliant_docking.control.hqp.manipulability import manipulability_gradient


def reference_step(ctrl, arm, ref, wrench, preload: float, integral_wrench=(0.0,) * 6) -> dict:
    """The law's quantities at this step for the HQPController ``ctrl`` (its parameters),
    ``preload`` the ramp's value of this step, ``integral_wrench`` [F_i; M_i] of this step."""
    J, M, Minv, q, v, h = arm.J, arm.M, arm.Minv, arm.q, arm.v, arm.h
    F = max(np.linalg.norm(wrench) - ctrl.deadband, 0.0) if ctrl.use_force_feedback else 0.0
    s = stiffness_scale(F, ctrl.min_stiffness_ratio, ctrl.sigmoid_gain)
    K_r = s * ctrl.K0
    lam_inv = J @ Minv @ J.T
    eigval, V = np.linalg.eigh(lam_inv)
    cond = eigval[-1] / eigval[0] if eigval[0] > 0.0 else np.inf
    floored = eigval[0] * ctrl.threshold < eigval[-1]
    if floored:
        eigval = np.maximum(eigval, max(eigval[-1], 1e-300) / ctrl.threshold)
    lam = (V / eigval) @ V.T
    lam_sqrt = (V / np.sqrt(eigval)) @ V.T
    k_sqrt = np.sqrt(K_r)
    D = lam_sqrt * k_sqrt[None, :] + k_sqrt[:, None] * lam_sqrt  # Eq. 29
    modal = np.linalg.eigvalsh(D)[0] <= 0.0
    if modal:
        D = modal_damping(lam_sqrt, (V * np.sqrt(eigval)) @ V.T, K_r)
    e = np.concatenate([arm.pos - ref.pos, pin.log3(arm.rot @ ref.rot.T)])
    F_r = -D @ (arm.twist - ref.twist) - K_r * e
    F_r[:3] += np.asarray(integral_wrench[:3]) + preload * ctrl.axis
    F_r[3:] += np.asarray(integral_wrench[3:])
    b = ref.accel - arm.Jdot_v + lam_inv @ F_r
    JJ = J @ J.T + 1e-8 * np.eye(6)
    w = math.sqrt(np.linalg.det(JJ))
    if ctrl._inertia_metric:
        qdd = Minv @ J.T @ np.linalg.solve(lam_inv + 1e-8 * np.eye(6), b)
    else:
        qdd = J.T @ np.linalg.solve(JJ, b)
    a_null = ctrl.posture_stiffness * (ctrl.q_home - q) - ctrl.posture_damping * v
    singular = w < ctrl.manipulability_threshold and ctrl.singularity_weight > 0.0
    if singular:
        d = manipulability_gradient(J, np.linalg.solve(JJ, J), 1.0)
        if ctrl._inertia_metric:
            d = Minv @ d
        if np.linalg.norm(d) > 0.0:
            omega = ctrl.manipulability_threshold
            a_null = a_null + ctrl.singularity_weight * (omega - w) / omega * d / np.linalg.norm(d)
    Na = a_null - Minv @ J.T @ lam @ J @ a_null
    dt_p, q_mid = ctrl.dt_p, 0.5 * (ctrl.q_min + ctrl.q_max)

    def rows(x, hhat):
        return np.concatenate([v + dt_p * x, q + dt_p * v + 0.5 * dt_p**2 * x - q_mid, M @ x + hhat])

    hhat = h.copy()
    if ctrl.friction.active:
        hhat = hhat + ctrl.friction(M @ (qdd + Na) + h, v, h)
    Z = np.array([rows(qdd, hhat), rows(qdd + Na, hhat)])
    return {
        "F": F,
        "s": s,
        "w": w,
        "JMinv": J @ Minv,
        "lam": lam,
        "D": D,
        "b": b,
        "qdd": qdd,
        "a_null": a_null,
        "Na": Na,
        "hhat": hhat,
        "Z": Z,
        "within": np.abs(Z) <= ctrl._half,
        "floored": floored,
        "cond": cond,  # of Λ⁻¹ before the floor (its eigenvectors carry the round-off)
        "modal": modal,
        "singular": singular,
    }
