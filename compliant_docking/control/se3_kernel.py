r"""``controller=se3_lie``'s step, compiled: the one implementation of the law's per-step
algebra (:mod:`~.jit`), for general symmetric A, D, K, both formulations.

:func:`step` evaluates, in one call: the body vectors, λ = log6(T̃) with its domain checks,
Ṽ, F̃, V̇_ref − J̇_b v + b·V of the twist formulation (with K (6×6) and G = A⁻¹[I, D]
(6×12) as matrices: with diagonal gains the products add exact zeros, the arithmetic of
the element-wise evaluation), the apparent-inertia floor (P applied every step, refreshed
every ``every`` steps by :func:`~.shaping.refresh_floor`), J_b, J_b M⁻¹, Λ⁻¹ = J_b M⁻¹ J_bᵀ,
the Λ solve by its own 6×6 Cholesky factorization, τ and the friction feed-forward.

Inputs and outputs are named: the constant parameters are one record (:func:`params_dtype`),
the step's state and results another (:func:`state_dtype`), the floor's a third
(:data:`~.shaping.FLOOR_STATE`); numba reads and writes their fields by name, Python
inspects the same buffers (``state["lam"]``). Records rather than named tuples of arrays
or a structref: one buffer per record crosses the Python → machine-code boundary (a named
tuple unboxes every array, every step), scalar fields are writable in place, and numba
caches functions of record types like any other.

What stays in Python, every step or on some steps (:class:`StepKernel`):

* the integral action (:class:`~.integral.PoseIntegral`, its own Python floats): its wrench
  [F_i; M_i] (``update_pose``) is an input of the kernel;
* the steps on which :class:`~.base.TaskInertia` checks the condition number (every
  ``check_every`` steps, every step while above the threshold): the kernel stops once V̇_ref
  is formed (``STAGE``), ``TaskInertia.solve`` (its ``dposv``, ``dpocon`` and fallback) applies
  Λ, and a second kernel (:func:`finish`) forms τ. So the diagnostics
  ``lambda_fallback_steps`` / ``lambda_max_condition`` keep their meaning exactly;
* a step on which the kernel's Cholesky fails (a pivot ≤ 0 or NaN): it returns
  ``NEEDS_SOLVE`` and ``TaskInertia.solve`` takes the step, so dposv decides as on main (it
  fails on the same pivots, then the damped pseudo-inverse follows);
* ``formulation=lambda_space``: every step is staged, and the controller's λ-space finish
  replaces V̇_ref from the kernel's λ, Ṽ, F̃ and base (the shared prelude is this kernel's).

The Cholesky solve (twin of ``dposv``) and the friction feed-forward are the shared blocks
of :mod:`~.kernel_blocks`. log3 and J(w)⁻¹'s coefficients are lie's own functions compiled,
not copies. tests/control/se3_reference.py is the numpy evaluation the kernel is tested
against (tests/control/test_se3_kernel.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from compliant_docking.control.jit import kernel
from compliant_docking.control.kernel_blocks import (
    cholesky,
    cholesky_solve,
    friction_feed_forward,
)
from compliant_docking.control.lie.series import PI_MARGIN, inv_coefficients
from compliant_docking.control.lie.so3 import log3_list
from compliant_docking.control.shaping import FLOOR_STATE, refresh_floor
from compliant_docking.planning.base import Reference

_log3 = kernel(log3_list)
_inv_coefficients = kernel(inv_coefficients)

# return codes of step()
DONE = 0  # τ is in state.tau
NEEDS_SOLVE = 1  # V̇_ref − J̇_b v + b·V is in state.a (d and base too); Λ in Python
OUT_OF_DOMAIN = 2  # ‖λ_rot‖ ≥ π − PI_MARGIN: state.lam[3:] is λ_rot
FLIPPED = 3  # λ_rot flipped through π within one step: state.w_prev the previous λ_rot
# modes
FULL, STAGE = 0, 1

_PI_LIMIT = math.pi - PI_MARGIN
_HALF_PI = 0.5 * math.pi
_HALF_PI_SQ = _HALF_PI * _HALF_PI


def params_dtype(nv: int) -> np.dtype:
    """The law's constant parameters, one record (``nv`` joints)."""
    return np.dtype(
        [
            ("K", "f8", (6, 6)),  # stiffness [N/m | N·m/rad]
            ("G", "f8", (6, 12)),  # A⁻¹[I, D]
            ("F_d", "f8", (6,)),  # desired wrench, desired TCP frame [N | N·m]
            ("null_damping", "f8"),  # b [1/s]
            ("has_F_d", "?"),
            ("force_feedback", "?"),
            ("floor", "?"),  # the apparent-inertia floor is on (its record: FLOOR_STATE)
            ("friction", "?"),  # the friction feed-forward is on
            ("friction_mode", "i8"),  # kernel_blocks.FRICTION_CODES
            ("friction_f", "f8", (nv,)),
            ("friction_b", "f8", (nv,)),
            ("friction_scale", "f8", (nv,)),
        ],
        align=True,
    )


def state_dtype(nv: int) -> np.dtype:
    """The step's state and results, one record (``nv`` joints)."""
    return np.dtype(
        [
            ("w_prev", "f8", (3,)),  # λ_rot of the previous step [rad]
            ("max_rot", "f8"),  # the largest ‖λ_rot‖ seen [rad]
            ("theta", "f8"),  # ‖λ_rot‖ of this step [rad]
            ("lam", "f8", (6,)),  # λ [m | rad]
            ("V_tilde", "f8", (6,)),  # Ṽ (body axes)
            ("F_tilde", "f8", (6,)),  # F̃ (body axes)
            ("a", "f8", (6,)),  # V̇_ref − J̇_b v + b·V
            ("a_offset", "f8", (6,)),  # J̇_b v − b·V (V̇_ref = a + a_offset)
            ("d", "f8", (6,)),  # −A⁻¹(F̃ − D·Ṽ − dexp⁻ᵀKλ): a = base + d (floor: base + P·d)
            ("base", "f8", (6,)),  # Ad(T̃)V̇_d + ad(Ṽ)V − J̇_b v + b·V
            ("F_body", "f8", (6,)),  # the measured wrench in TCP axes (0 without force feedback)
            ("Jb", "f8", (6, nv)),  # J_b = diag(Rᵀ, Rᵀ)·J
            ("JbMinv", "f8", (6, nv)),  # J_b M⁻¹
            ("tau", "f8", (nv,)),  # the torque command
        ],
        align=True,
    )


@kernel
def step(mode, k, refresh, Rd, pd, Vd, Ad, R, p, tw, jdv, J, Minv, M, v, h, wrench, Fi,
         params, floor, state, lam_log):
    """One control step (see the module docstring). ``params``, ``state``, ``floor``: one-record
    arrays of :func:`params_dtype`, :func:`state_dtype` and :data:`~.shaping.FLOOR_STATE`;
    ``Fi``: the integral wrench [F_i; M_i] (world axes); ``lam_log[k]`` receives λ (when
    k < its length). Returns :data:`DONE` (τ in ``state.tau``) or another code."""
    par, st = params[0], state[0]
    nv = len(v)

    # --- world → TCP (body) axes: x ↦ Rᵀx, as rows x·R
    def body(x0, x1, x2):
        return (x0 * R[0, 0] + x1 * R[1, 0] + x2 * R[2, 0],
                x0 * R[0, 1] + x1 * R[1, 1] + x2 * R[2, 1],
                x0 * R[0, 2] + x1 * R[1, 2] + x2 * R[2, 2])

    # R̃ = RᵀR_d has columns (c00, c01, c02), (c10, …), (c20, …); p̃ = Rᵀ(p_d − p) = e
    c00, c01, c02 = body(Rd[0, 0], Rd[1, 0], Rd[2, 0])
    c10, c11, c12 = body(Rd[0, 1], Rd[1, 1], Rd[2, 1])
    c20, c21, c22 = body(Rd[0, 2], Rd[1, 2], Rd[2, 2])
    e0, e1, e2 = body(pd[0] - p[0], pd[1] - p[1], pd[2] - p[2])
    pv0, pv1, pv2 = body(tw[0], tw[1], tw[2])
    pw0, pw1, pw2 = body(tw[3], tw[4], tw[5])
    ja0, ja1, ja2 = body(jdv[0], jdv[1], jdv[2])
    jb0, jb1, jb2 = body(jdv[3], jdv[4], jdv[5])
    dv0, dv1, dv2 = body(Vd[0], Vd[1], Vd[2])
    dw0, dw1, dw2 = body(Vd[3], Vd[4], Vd[5])
    da0, da1, da2 = body(Ad[0], Ad[1], Ad[2])
    db0, db1, db2 = body(Ad[3], Ad[4], Ad[5])
    if par.force_feedback:
        f0, f1, f2 = body(wrench[0], wrench[1], wrench[2])
        m0, m1, m2 = body(wrench[3], wrench[4], wrench[5])
    else:
        f0 = f1 = f2 = m0 = m1 = m2 = 0.0
    i0, i1, i2 = body(Fi[0], Fi[1], Fi[2])
    i3, i4, i5 = body(Fi[3], Fi[4], Fi[5])

    # --- λ = log6(T̃) = [J(w)⁻¹p̃; w], w = log3(R̃); refused at ‖w‖ ≥ π
    lam = st.lam
    w0, w1, w2, th = _log3(c00, c10, c20, c01, c11, c21, c02, c12, c22)
    st.theta = th
    lam[3], lam[4], lam[5] = w0, w1, w2
    if not th < _PI_LIMIT:
        return OUT_OF_DOMAIN
    w_prev = st.w_prev
    if th > _HALF_PI:  # a step through π shows as a flip of λ_rot (log3 stays ≤ π)
        p0, p1, p2 = w_prev[0], w_prev[1], w_prev[2]
        if p0 * w0 + p1 * w1 + p2 * w2 < 0.0 and p0 * p0 + p1 * p1 + p2 * p2 > _HALF_PI_SQ:
            return FLIPPED
    w_prev[0], w_prev[1], w_prev[2] = w0, w1, w2
    if th > st.max_rot:
        st.max_rot = th
    g, e, dg, de = _inv_coefficients(th)  # J(w)⁻¹'s coefficients g, e and g1, e1
    wp = w0 * e0 + w1 * e1 + w2 * e2
    l0 = g * e0 - 0.5 * (w1 * e2 - w2 * e1) + e * wp * w0
    l1 = g * e1 - 0.5 * (w2 * e0 - w0 * e2) + e * wp * w1
    l2 = g * e2 - 0.5 * (w0 * e1 - w1 * e0) + e * wp * w2
    lam[0], lam[1], lam[2] = l0, l1, l2
    if k < lam_log.shape[0]:
        for j in range(6):
            lam_log[k, j] = lam[j]

    # --- Ad(T̃)V_d and Ad(T̃)V̇_d: the reference twist and its derivative carried to the
    # TCP, in its axes: Ad(T̃)V_d = [Rᵀṗ_d − (Rᵀω_d) × p̃; Rᵀω_d],
    # Ad(T̃)V̇_d = [Rᵀp̈_d − (Rᵀω_d) × (Rᵀṗ_d) − (Rᵀα_d) × p̃; Rᵀα_d]
    av0 = dv0 - (dw1 * e2 - dw2 * e1)
    av1 = dv1 - (dw2 * e0 - dw0 * e2)
    av2 = dv2 - (dw0 * e1 - dw1 * e0)
    # --- Ṽ = Ad(T̃)V_d − V
    t0, t1, t2 = av0 - pv0, av1 - pv1, av2 - pv2
    t3, t4, t5 = dw0 - pw0, dw1 - pw1, dw2 - pw2
    # --- base = Ad(T̃)V̇_d + ad(Ṽ)V − J̇_b v + b·V, with ad(Ṽ)V = [w̃×v + ṽ×w; w̃×w]
    #     and J̇_b v = [Rᵀa − (Rᵀω)×(Rᵀṗ); Rᵀα]
    bn = par.null_damping
    aa0 = da0 - (dw1 * dv2 - dw2 * dv1) - (db1 * e2 - db2 * e1)
    aa1 = da1 - (dw2 * dv0 - dw0 * dv2) - (db2 * e0 - db0 * e2)
    aa2 = da2 - (dw0 * dv1 - dw1 * dv0) - (db0 * e1 - db1 * e0)
    o0 = ja0 - (pw1 * pv2 - pw2 * pv1) - bn * pv0  # J̇_b v − b·V
    o1 = ja1 - (pw2 * pv0 - pw0 * pv2) - bn * pv1
    o2 = ja2 - (pw0 * pv1 - pw1 * pv0) - bn * pv2
    o3, o4, o5 = jb0 - bn * pw0, jb1 - bn * pw1, jb2 - bn * pw2
    base, a_offset, V_tilde = st.base, st.a_offset, st.V_tilde
    base[0] = aa0 + t4 * pv2 - t5 * pv1 + t1 * pw2 - t2 * pw1 - o0
    base[1] = aa1 + t5 * pv0 - t3 * pv2 + t2 * pw0 - t0 * pw2 - o1
    base[2] = aa2 + t3 * pv1 - t4 * pv0 + t0 * pw1 - t1 * pw0 - o2
    base[3] = db0 + t4 * pw2 - t5 * pw1 - o3
    base[4] = db1 + t5 * pw0 - t3 * pw2 - o4
    base[5] = db2 + t3 * pw1 - t4 * pw0 - o5
    a_offset[0], a_offset[1], a_offset[2] = o0, o1, o2
    a_offset[3], a_offset[4], a_offset[5] = o3, o4, o5
    V_tilde[0], V_tilde[1], V_tilde[2] = t0, t1, t2
    V_tilde[3], V_tilde[4], V_tilde[5] = t3, t4, t5

    # --- F̃ = Ad(T̃)⁻ᵀF_d − F_body − [RᵀF_i; RᵀM_i], Ad(T̃)⁻ᵀ[f; m] = [R̃f; p̃ × R̃f + R̃m]
    F_tilde, F_body = st.F_tilde, st.F_body
    if par.has_F_d:
        F_d = par.F_d
        g0, g1, g2 = F_d[0], F_d[1], F_d[2]
        n0, n1, n2 = F_d[3], F_d[4], F_d[5]
        r0 = c00 * g0 + c10 * g1 + c20 * g2
        r1 = c01 * g0 + c11 * g1 + c21 * g2
        r2 = c02 * g0 + c12 * g1 + c22 * g2
        F_tilde[0] = r0 - f0
        F_tilde[1] = r1 - f1
        F_tilde[2] = r2 - f2
        F_tilde[3] = e1 * r2 - e2 * r1 + c00 * n0 + c10 * n1 + c20 * n2 - m0
        F_tilde[4] = e2 * r0 - e0 * r2 + c01 * n0 + c11 * n1 + c21 * n2 - m1
        F_tilde[5] = e0 * r1 - e1 * r0 + c02 * n0 + c12 * n1 + c22 * n2 - m2
    else:
        F_tilde[0], F_tilde[1], F_tilde[2] = -f0, -f1, -f2
        F_tilde[3], F_tilde[4], F_tilde[5] = -m0, -m1, -m2
    F_tilde[0] -= i0
    F_tilde[1] -= i1
    F_tilde[2] -= i2
    F_tilde[3] -= i3
    F_tilde[4] -= i4
    F_tilde[5] -= i5
    F_body[0], F_body[1], F_body[2] = f0, f1, f2
    F_body[3], F_body[4], F_body[5] = m0, m1, m2

    # --- r = F̃ − dexp⁻ᵀKλ, y = Kλ: dexp⁻ᵀy = [J⁻ᵀy_v; Qiᵀy_v + J⁻ᵀy_w] with
    # J⁻ᵀy = g y + ½ w×y + e w(w·y) and Qiᵀy = g1 s y + ½ λ_v×y + e(λ_v(w·y) + w(λ_v·y))
    # + e1 s w(w·y), s = w·λ_v
    K = par.K
    y = np.empty(6)
    for i in range(6):
        acc = 0.0
        for j in range(6):
            acc += K[i, j] * lam[j]
        y[i] = acc
    y0, y1, y2, y3, y4, y5 = y[0], y[1], y[2], y[3], y[4], y[5]
    s = w0 * l0 + w1 * l1 + w2 * l2
    wy = w0 * y0 + w1 * y1 + w2 * y2
    ly = l0 * y0 + l1 * y1 + l2 * y2
    wz = w0 * y3 + w1 * y4 + w2 * y5
    ewy = e * wy
    ewz = e * wz
    qs = dg * s  # g1 s
    qw = e * ly + de * s * wy  # e λ_v·y + e1 s w·y
    r = (F_tilde[0] - (g * y0 + 0.5 * (w1 * y2 - w2 * y1) + ewy * w0),
         F_tilde[1] - (g * y1 + 0.5 * (w2 * y0 - w0 * y2) + ewy * w1),
         F_tilde[2] - (g * y2 + 0.5 * (w0 * y1 - w1 * y0) + ewy * w2),
         F_tilde[3] - (qs * y0 + 0.5 * (l1 * y2 - l2 * y1) + ewy * l0 + qw * w0
                       + g * y3 + 0.5 * (w1 * y5 - w2 * y4) + ewz * w0),
         F_tilde[4] - (qs * y1 + 0.5 * (l2 * y0 - l0 * y2) + ewy * l1 + qw * w1
                       + g * y4 + 0.5 * (w2 * y3 - w0 * y5) + ewz * w1),
         F_tilde[5] - (qs * y2 + 0.5 * (l0 * y1 - l1 * y0) + ewy * l2 + qw * w2
                       + g * y5 + 0.5 * (w0 * y4 - w1 * y3) + ewz * w2))
    # --- a = V̇_ref − J̇_b v + b·V = base − G·[r; −Ṽ] = base + d, d = G[:, 6:]Ṽ − G[:, :6]r
    G, d, a = par.G, st.d, st.a
    for j in range(6):
        u = 0.0
        for m in range(6):
            u += G[j, m] * r[m]
        w = 0.0
        for m in range(6):
            w += G[j, 6 + m] * V_tilde[m]
        d[j] = w - u
        a[j] = base[j] - u + w

    # --- J_b = diag(Rᵀ, Rᵀ)·J and J_b M⁻¹
    Jb, JbMinv = st.Jb, st.JbMinv
    for c in range(nv):
        for i in range(3):
            Jb[i, c] = R[0, i] * J[0, c] + R[1, i] * J[1, c] + R[2, i] * J[2, c]
            Jb[3 + i, c] = R[0, i] * J[3, c] + R[1, i] * J[4, c] + R[2, i] * J[5, c]
    for i in range(6):
        for c in range(nv):
            acc = 0.0
            for m in range(nv):
                acc += Jb[i, m] * Minv[m, c]
            JbMinv[i, c] = acc
    S = np.empty((6, 6))  # Λ⁻¹ = J_b M⁻¹ J_bᵀ
    for i in range(6):
        for j in range(6):
            acc = 0.0
            for m in range(nv):
                acc += JbMinv[i, m] * Jb[j, m]
            S[i, j] = acc
    if par.floor:  # A⁻¹(…) → A_eff⁻¹(…): a = [P, I]·[d; base] while P is in force
        if refresh:
            refresh_floor(S, floor)
        fl = floor[0]
        if fl.active:
            PI = fl.P_and_I
            for j in range(6):
                acc = 0.0
                for m in range(6):
                    acc += PI[j, m] * d[m]
                for m in range(6):
                    acc += PI[j, 6 + m] * base[m]
                a[j] = acc
    if mode == STAGE:
        return NEEDS_SOLVE

    # --- Λ(V̇_ref − J̇_b v + bV) by Cholesky of Λ⁻¹
    L = np.empty((6, 6))
    if not cholesky(S, L):
        return NEEDS_SOLVE
    x = a.copy()
    cholesky_solve(L, x)
    finish(x, M, v, h, params, state)
    return DONE


@kernel
def finish(x, M, v, h, params, state):
    """τ = J_bᵀ(x − F_body) + h − b·M v (+ friction feed-forward) into ``state.tau``, x = Λ(…)."""
    par, st = params[0], state[0]
    nv = len(v)
    bn = par.null_damping
    if par.force_feedback:
        for i in range(6):
            x[i] -= st.F_body[i]
    tau, Jb = st.tau, st.Jb
    for c in range(nv):
        s = 0.0
        for i in range(6):
            s += x[i] * Jb[i, c]
        mv = 0.0
        for m in range(nv):
            mv += M[c, m] * v[m]
        tau[c] = s + h[c] - bn * mv
    if par.friction:
        ff = np.empty(nv)
        friction_feed_forward(tau, v, h, par.friction_f, par.friction_b, par.friction_scale,
                              par.friction_mode, ff)
        for c in range(nv):
            tau[c] += ff[c]


#: the λ-space finish of ``formulation=lambda_space``: (λ, Ṽ, F̃, base) ↦ V̇_ref − J̇_b v + b·V
LambdaFinish = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


class StepKernel:
    """The per-step driver of :func:`step` for one :class:`~.se3_lie.SE3LieController`:
    the records, the integral action, the choice of full or staged step, TaskInertia on the
    staged ones, the floor's and TaskInertia's counters. ``lambda_finish`` (the λ-space
    formulation) replaces V̇_ref on every (then staged) step."""

    def __init__(self, ctrl, n_steps: int, lambda_finish: LambdaFinish | None = None):
        nv = ctrl.arm.nv
        fr, floor = ctrl.friction, ctrl.inertia_floor
        self.params = np.zeros(1, params_dtype(nv))
        par = self.params[0]
        par["K"], par["G"], par["F_d"] = ctrl.K, ctrl.G, ctrl.desired_wrench
        par["null_damping"] = ctrl.null_damping
        par["has_F_d"] = bool(np.any(ctrl.desired_wrench))
        par["force_feedback"] = ctrl.use_force_feedback
        par["floor"] = floor is not None
        par["friction"], par["friction_mode"] = fr.active, fr.code
        par["friction_f"], par["friction_b"], par["friction_scale"] = fr.f, fr.b, fr.scale
        self.state = np.zeros(1, state_dtype(nv))
        st = self.state[0]
        self.Jb, self.JbMinv, self.a, self.tau = st["Jb"], st["JbMinv"], st["a"], st["tau"]
        self.floor_state = floor.state if floor is not None else np.zeros(1, FLOOR_STATE)
        self.ctrl, self.floor, self.ti, self.integral = ctrl, floor, ctrl.task_inertia, ctrl.integral
        self.lambda_finish = lambda_finish
        self._lam_log = np.zeros((max(n_steps, 0), 6))  # λ of every step, the run's time series
        self._k = 0  # steps taken
        self._err = np.zeros(3)
        self._no_force = (0.0,) * 6
        self._warm_up(ctrl.arm)

    def field(self, name: str) -> np.ndarray:
        """A copy of the state's field ``name`` (the last step's value)."""
        return self.state[name][0].copy()

    def lam_log(self) -> np.ndarray:
        """λ of the steps taken so far (rows of the run's length at most)."""
        return self._lam_log[: min(self._k, len(self._lam_log))]

    def _warm_up(self, arm) -> None:
        """Load (or compile) the kernels for this step's argument types now, on throwaway
        records, so that neither the loop's timing nor its first step pays for it."""
        ref = Reference()
        ref.rot[:] = arm.rot
        state, floor = self.state.copy(), self.floor_state.copy()
        for mode in (FULL, STAGE):
            step(mode, 0, False, ref.rot, ref.pos, ref.twist, ref.accel, arm.rot, arm.pos,
                 arm.twist, arm.Jdot_v, arm.J, arm.Minv, arm.M, arm.v, arm.h, np.zeros(6),
                 self._no_force, self.params, floor, state, np.zeros((0, 6)))
        finish(np.zeros(6), arm.M, arm.v, arm.h, self.params, state)

    def __call__(self, t, arm, ref, wrench) -> np.ndarray:
        floor, ti, state = self.floor, self.ti, self.state
        integral = self.integral
        if integral is None:
            F_i = self._no_force
        else:
            np.subtract(ref.pos, arm.pos, out=self._err)
            F_i = integral.update_pose(self._err, wrench, ref.rot, arm.rot_T)
        # steps with TaskInertia's condition-number check end in numpy (staged), and every
        # λ-space step; the floor's refresh runs in the kernel; the counters of both objects
        # are advanced here
        staged = ti.due() or self.lambda_finish is not None
        refresh = floor is not None and floor.due()
        k = self._k
        self._k = k + 1
        status = step(STAGE if staged else FULL, k, refresh, ref.rot, ref.pos, ref.twist,
                      ref.accel, arm.rot, arm.pos, arm.twist, arm.Jdot_v, arm.J, arm.Minv,
                      arm.M, arm.v, arm.h, wrench, F_i, self.params, self.floor_state, state,
                      self._lam_log)
        if status > NEEDS_SOLVE:
            st = state[0]
            self.ctrl.raise_out_of_domain(t, st["lam"][3:].tolist(), float(st["theta"]),
                                     st["w_prev"].tolist(), status == FLIPPED)
        if floor is not None:  # ApparentInertiaFloor.current's bookkeeping
            if refresh:
                floor.take_refresh()
            floor.count_step()
        if status == DONE:
            ti.count_unchecked()
            return self.tau.copy()
        a = self.a
        if self.lambda_finish is not None:  # V̇_ref by the λ-space route, the floor's P on it
            st = state[0]
            base = st["base"]
            a[:] = self.lambda_finish(st["lam"].copy(), st["V_tilde"].copy(), st["F_tilde"].copy(),
                                      base.copy())
            if floor is not None and floor.P is not None:
                a[:] = base + floor.P.dot(a - base)
        # TaskInertia.solve: its check (staged), or its fallback (the Cholesky failed)
        finish(ti.solve(self.Jb, self.JbMinv, a.copy()), arm.M, arm.v, arm.h, self.params, state)
        return self.tau.copy()
