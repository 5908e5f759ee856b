r"""``controller=se3_lie``'s hot step compiled: the twist formulation with diagonal A, D, K
(the config's case) in one numba kernel per control step (:mod:`~.jit`).

The kernel evaluates, in one call, the scalar formulas of :class:`~.se3_lie.SE3LieController`'s
numpy step, in the same order (the results differ by the order of summation in the products
only): the body vectors, λ = log6(T̃) with its domain checks, Ṽ, F̃, V̇_ref − J̇_b v + b·V,
the apparent-inertia floor (P applied every step, refreshed every ``every`` steps), J_b,
J_b M⁻¹, Λ⁻¹ = J_b M⁻¹ J_bᵀ, the Λ solve by its own 6×6 Cholesky factorization, τ and the
friction feed-forward.

What stays in Python, every step or on some steps:

* the integral action (:class:`~.integral.PoseIntegral`, its own Python floats): its wrench
  [F_i; M_i] (``update_pose``) is an input of the kernel;
* the steps on which :class:`~.base.TaskInertia` checks the condition number (every
  ``check_every`` steps, every step while above the threshold): the kernel stops once V̇_ref
  is formed (``STAGE``), ``TaskInertia.solve`` (its ``dposv``, ``dpocon`` and fallback) applies
  Λ, and a second kernel (:func:`finish`) forms τ. So the diagnostics
  ``lambda_fallback_steps`` / ``lambda_max_condition`` keep their meaning exactly;
* a step on which the kernel's Cholesky fails (a pivot ≤ 0 or NaN): it returns
  ``NEEDS_SOLVE`` and ``TaskInertia.solve`` takes the step, so dposv decides as on main (it
  fails on the same pivots, then the damped pseudo-inverse follows).

The Cholesky solve (twin of ``dposv``) and the friction feed-forward are the shared blocks
of :mod:`~.kernel_blocks`. The apparent-inertia floor's refresh is a twin of
``ApparentInertiaFloor.refresh`` (its ``dpotrf`` test by the same Cholesky, its ``dsyevd`` by
numba's ``np.linalg.eigh``, LAPACK's ``dsyevd`` as well; tests/control/test_se3_kernel.py
checks it against the numpy piece). log3 and J(w)⁻¹'s coefficients are lie's own functions
compiled, not copies.
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.control.jit import kernel
from compliant_docking.control.kernel_blocks import (
    cholesky,
    cholesky_solve,
    friction_code,
    friction_feed_forward,
)
from compliant_docking.control.lie.series import PI_MARGIN, inv_coefficients
from compliant_docking.control.lie.so3 import log3_list
from compliant_docking.planning.base import Reference

_log3 = kernel(log3_list)
_inv_coefficients = kernel(inv_coefficients)

# return codes of step()
DONE = 0  # τ is in mem[TAU:]
NEEDS_SOLVE = 1  # V̇_ref − J̇_b v + b·V is in mem[A:A+6] (and [d; base] in mem[Z:Z+12]); Λ in Python
OUT_OF_DOMAIN = 2  # ‖λ_rot‖ ≥ π − PI_MARGIN: mem[LAM+3:LAM+6] is λ_rot
FLIPPED = 3  # λ_rot flipped through π within one step: mem[WPREV:WPREV+3] the previous λ_rot
# modes
FULL, STAGE = 0, 1

# par (constant): gains, flags, friction parameters
K_DIAG, G_INV, G_D, F_D = 0, 6, 12, 18
NULL_DAMPING, HAS_F_D, FORCE_FEEDBACK, FRICTION_ON, FRICTION_MODE = 24, 25, 26, 27, 28
FLOOR, FLOOR_RATIO, W_SQRT, W_ISQRT = 29, 30, 31, 37  # the floor: on, ratio, W^½, W^-½
FRICTION = 43  # f (nv), b (nv), scale (nv)
# mem (state and outputs)
WPREV, MAX_ROT, THETA, FLOOR_ACTIVE, FLOOR_MAX_RATIO = 0, 3, 4, 5, 6
LAM, V_TILDE, F_TILDE, A, A_OFFSET, Z, F_BODY, TAU = 8, 14, 20, 26, 32, 38, 50, 56

_PI_LIMIT = math.pi - PI_MARGIN
_HALF_PI = 0.5 * math.pi
_HALF_PI_SQ = _HALF_PI * _HALF_PI


def par_size(nv: int) -> int:
    return FRICTION + 3 * nv


def mem_size(nv: int) -> int:
    return TAU + nv


@kernel
def floor_refresh(S, w_sqrt, w_isqrt, ratio, PI, mem):
    """Twin of ``ApparentInertiaFloor.refresh`` for Λ⁻¹ = S: P = W_eff⁻¹W into PI[:, :6] and
    True, or False when W ⪰ ratio·Λ already (P None). mem[FLOOR_MAX_RATIO]: the largest σ."""
    T = np.empty((6, 6))  # W^½ Λ⁻¹ W^½, transposed (LAPACK read the upper triangle there)
    U = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            T[j, i] = S[i, j] * (w_sqrt[i] * w_sqrt[j])
            U[j, i] = T[j, i] - ratio if i == j else T[j, i]
    if cholesky(U, np.empty((6, 6))):  # every 1/σ > ratio: nothing to do
        return False
    if not np.all(np.isfinite(T)):  # (dsyevd's failure in numpy: P None)
        return False
    mu, V = np.linalg.eigh(T)
    if mu[0] <= 0.0:
        return False
    mem[FLOOR_MAX_RATIO] = max(mem[FLOOR_MAX_RATIO], 1.0 / mu[0])
    inv_ratio = 1.0 / ratio
    c = np.empty(6)
    for m in range(6):
        c[m] = min(mu[m] * inv_ratio, 1.0)
    for i in range(6):
        for j in range(6):
            s = 0.0
            for m in range(6):
                s += (w_isqrt[i] * V[i, m] * c[m]) * (V[j, m] * w_sqrt[j])
            PI[i, j] = s
    return True


@kernel
def step(mode, k, refresh, Rd, pd, Vd, Ad, R, p, tw, jdv, J, Minv, M, v, h, wrench, Fi,
         par, PI, mem, work, lam_log):
    """One control step of the twist formulation (diagonal gains); see the module docstring.
    ``Fi``: the integral wrench [F_i; M_i] (world axes).

    ``work`` (12×nv) receives J_b (rows 0-5) and J_b M⁻¹ (rows 6-11); ``mem`` the quantities
    of the step and τ; ``lam_log[k]`` λ (when k < its length)."""
    nv = len(v)

    # --- world → TCP (body) axes: x ↦ Rᵀx, as rows x·R
    def body(x0, x1, x2):
        return (x0 * R[0, 0] + x1 * R[1, 0] + x2 * R[2, 0],
                x0 * R[0, 1] + x1 * R[1, 1] + x2 * R[2, 1],
                x0 * R[0, 2] + x1 * R[1, 2] + x2 * R[2, 2])

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
    if par[FORCE_FEEDBACK] != 0.0:
        f0, f1, f2 = body(wrench[0], wrench[1], wrench[2])
        m0, m1, m2 = body(wrench[3], wrench[4], wrench[5])
    else:
        f0 = f1 = f2 = m0 = m1 = m2 = 0.0
    i0, i1, i2 = body(Fi[0], Fi[1], Fi[2])
    i3, i4, i5 = body(Fi[3], Fi[4], Fi[5])

    # --- λ = log6(T̃) = [J(w)⁻¹p̃; w], w = log3(R̃); refused at ‖w‖ ≥ π
    w0, w1, w2, th = _log3(c00, c10, c20, c01, c11, c21, c02, c12, c22)
    mem[THETA] = th
    mem[LAM + 3], mem[LAM + 4], mem[LAM + 5] = w0, w1, w2
    if not th < _PI_LIMIT:
        return OUT_OF_DOMAIN
    if th > _HALF_PI:
        p0, p1, p2 = mem[WPREV], mem[WPREV + 1], mem[WPREV + 2]
        if p0 * w0 + p1 * w1 + p2 * w2 < 0.0 and p0 * p0 + p1 * p1 + p2 * p2 > _HALF_PI_SQ:
            return FLIPPED
    mem[WPREV], mem[WPREV + 1], mem[WPREV + 2] = w0, w1, w2
    if th > mem[MAX_ROT]:
        mem[MAX_ROT] = th
    g, e, dg, de = _inv_coefficients(th)
    wp = w0 * e0 + w1 * e1 + w2 * e2
    l0 = g * e0 - 0.5 * (w1 * e2 - w2 * e1) + e * wp * w0
    l1 = g * e1 - 0.5 * (w2 * e0 - w0 * e2) + e * wp * w1
    l2 = g * e2 - 0.5 * (w0 * e1 - w1 * e0) + e * wp * w2
    mem[LAM], mem[LAM + 1], mem[LAM + 2] = l0, l1, l2
    if k < lam_log.shape[0]:
        for j in range(6):
            lam_log[k, j] = mem[LAM + j]

    # --- Ṽ = Ad(T̃)V_d − V; base = Ad(T̃)V̇_d + ad(Ṽ)V − J̇_b v + b·V (se3_lie.py)
    av0 = dv0 - (dw1 * e2 - dw2 * e1)
    av1 = dv1 - (dw2 * e0 - dw0 * e2)
    av2 = dv2 - (dw0 * e1 - dw1 * e0)
    t0, t1, t2 = av0 - pv0, av1 - pv1, av2 - pv2
    t3, t4, t5 = dw0 - pw0, dw1 - pw1, dw2 - pw2
    bn = par[NULL_DAMPING]
    aa0 = da0 - (dw1 * dv2 - dw2 * dv1) - (db1 * e2 - db2 * e1)
    aa1 = da1 - (dw2 * dv0 - dw0 * dv2) - (db2 * e0 - db0 * e2)
    aa2 = da2 - (dw0 * dv1 - dw1 * dv0) - (db0 * e1 - db1 * e0)
    o0 = ja0 - (pw1 * pv2 - pw2 * pv1) - bn * pv0
    o1 = ja1 - (pw2 * pv0 - pw0 * pv2) - bn * pv1
    o2 = ja2 - (pw0 * pv1 - pw1 * pv0) - bn * pv2
    o3, o4, o5 = jb0 - bn * pw0, jb1 - bn * pw1, jb2 - bn * pw2
    mem[Z + 6] = aa0 + t4 * pv2 - t5 * pv1 + t1 * pw2 - t2 * pw1 - o0
    mem[Z + 7] = aa1 + t5 * pv0 - t3 * pv2 + t2 * pw0 - t0 * pw2 - o1
    mem[Z + 8] = aa2 + t3 * pv1 - t4 * pv0 + t0 * pw1 - t1 * pw0 - o2
    mem[Z + 9] = db0 + t4 * pw2 - t5 * pw1 - o3
    mem[Z + 10] = db1 + t5 * pw0 - t3 * pw2 - o4
    mem[Z + 11] = db2 + t3 * pw1 - t4 * pw0 - o5
    mem[A_OFFSET], mem[A_OFFSET + 1], mem[A_OFFSET + 2] = o0, o1, o2
    mem[A_OFFSET + 3], mem[A_OFFSET + 4], mem[A_OFFSET + 5] = o3, o4, o5
    mem[V_TILDE], mem[V_TILDE + 1], mem[V_TILDE + 2] = t0, t1, t2
    mem[V_TILDE + 3], mem[V_TILDE + 4], mem[V_TILDE + 5] = t3, t4, t5

    # --- F̃ = Ad(T̃)⁻ᵀF_d − F_body − [RᵀF_i; RᵀM_i]
    if par[HAS_F_D] != 0.0:
        g0, g1, g2 = par[F_D], par[F_D + 1], par[F_D + 2]
        n0, n1, n2 = par[F_D + 3], par[F_D + 4], par[F_D + 5]
        r0 = c00 * g0 + c10 * g1 + c20 * g2
        r1 = c01 * g0 + c11 * g1 + c21 * g2
        r2 = c02 * g0 + c12 * g1 + c22 * g2
        mem[F_TILDE] = r0 - f0
        mem[F_TILDE + 1] = r1 - f1
        mem[F_TILDE + 2] = r2 - f2
        mem[F_TILDE + 3] = e1 * r2 - e2 * r1 + c00 * n0 + c10 * n1 + c20 * n2 - m0
        mem[F_TILDE + 4] = e2 * r0 - e0 * r2 + c01 * n0 + c11 * n1 + c21 * n2 - m1
        mem[F_TILDE + 5] = e0 * r1 - e1 * r0 + c02 * n0 + c12 * n1 + c22 * n2 - m2
    else:
        mem[F_TILDE], mem[F_TILDE + 1], mem[F_TILDE + 2] = -f0, -f1, -f2
        mem[F_TILDE + 3], mem[F_TILDE + 4], mem[F_TILDE + 5] = -m0, -m1, -m2
    mem[F_TILDE] -= i0
    mem[F_TILDE + 1] -= i1
    mem[F_TILDE + 2] -= i2
    mem[F_TILDE + 3] -= i3
    mem[F_TILDE + 4] -= i4
    mem[F_TILDE + 5] -= i5
    mem[F_BODY], mem[F_BODY + 1], mem[F_BODY + 2] = f0, f1, f2
    mem[F_BODY + 3], mem[F_BODY + 4], mem[F_BODY + 5] = m0, m1, m2

    # --- r = F̃ − dexp⁻ᵀKλ (se3_lie.py's closed form)
    y0, y1, y2 = par[K_DIAG] * l0, par[K_DIAG + 1] * l1, par[K_DIAG + 2] * l2
    y3, y4, y5 = par[K_DIAG + 3] * w0, par[K_DIAG + 4] * w1, par[K_DIAG + 5] * w2
    s = w0 * l0 + w1 * l1 + w2 * l2
    wy = w0 * y0 + w1 * y1 + w2 * y2
    ly = l0 * y0 + l1 * y1 + l2 * y2
    wz = w0 * y3 + w1 * y4 + w2 * y5
    ewy = e * wy
    ewz = e * wz
    qs = dg * s
    qw = e * ly + de * s * wy
    r = (mem[F_TILDE] - (g * y0 + 0.5 * (w1 * y2 - w2 * y1) + ewy * w0),
         mem[F_TILDE + 1] - (g * y1 + 0.5 * (w2 * y0 - w0 * y2) + ewy * w1),
         mem[F_TILDE + 2] - (g * y2 + 0.5 * (w0 * y1 - w1 * y0) + ewy * w2),
         mem[F_TILDE + 3] - (qs * y0 + 0.5 * (l1 * y2 - l2 * y1) + ewy * l0 + qw * w0
                             + g * y3 + 0.5 * (w1 * y5 - w2 * y4) + ewz * w0),
         mem[F_TILDE + 4] - (qs * y1 + 0.5 * (l2 * y0 - l0 * y2) + ewy * l1 + qw * w1
                             + g * y4 + 0.5 * (w2 * y3 - w0 * y5) + ewz * w1),
         mem[F_TILDE + 5] - (qs * y2 + 0.5 * (l0 * y1 - l1 * y0) + ewy * l2 + qw * w2
                             + g * y5 + 0.5 * (w0 * y4 - w1 * y3) + ewz * w2))
    vt = (t0, t1, t2, t3, t4, t5)
    # --- a = base − G·[r; −Ṽ], G = [diag(1/a), diag(d/a)]; [d; base] kept for the floor
    for j in range(6):
        mem[Z + j] = par[G_D + j] * vt[j] - par[G_INV + j] * r[j]
        mem[A + j] = mem[Z + 6 + j] - par[G_INV + j] * r[j] + par[G_D + j] * vt[j]

    # --- J_b = diag(Rᵀ, Rᵀ)·J and J_b M⁻¹
    for c in range(nv):
        for i in range(3):
            work[i, c] = R[0, i] * J[0, c] + R[1, i] * J[1, c] + R[2, i] * J[2, c]
            work[3 + i, c] = R[0, i] * J[3, c] + R[1, i] * J[4, c] + R[2, i] * J[5, c]
    for i in range(6):
        for c in range(nv):
            s = 0.0
            for m in range(nv):
                s += work[i, m] * Minv[m, c]
            work[6 + i, c] = s
    S = np.empty((6, 6))  # Λ⁻¹ = J_b M⁻¹ J_bᵀ
    for i in range(6):
        for j in range(6):
            s = 0.0
            for m in range(nv):
                s += work[6 + i, m] * work[j, m]
            S[i, j] = s
    if par[FLOOR] != 0.0:  # A⁻¹(…) → A_eff⁻¹(…): a = [P, I]·[d; base] while P is not None
        if refresh:
            active = floor_refresh(S, par[W_SQRT:W_SQRT + 6], par[W_ISQRT:W_ISQRT + 6],
                                   par[FLOOR_RATIO], PI, mem)
            mem[FLOOR_ACTIVE] = 1.0 if active else 0.0
        if mem[FLOOR_ACTIVE] != 0.0:
            for j in range(6):
                s = 0.0
                for m in range(12):
                    s += PI[j, m] * mem[Z + m]
                mem[A + j] = s
    if mode == STAGE:
        return NEEDS_SOLVE

    # --- Λ(V̇_ref − J̇_b v + bV) by Cholesky of Λ⁻¹
    L = np.empty((6, 6))
    x = np.empty(6)
    if not cholesky(S, L):
        return NEEDS_SOLVE
    x[:] = mem[A:A + 6]
    cholesky_solve(L, x)
    finish(x, M, v, h, par, mem, work)
    return DONE


@kernel
def finish(x, M, v, h, par, mem, work):
    """τ = J_bᵀ(x − F_body) + h − b·M v (+ friction feed-forward) into mem[TAU:], x = Λ(…)."""
    nv = len(v)
    bn = par[NULL_DAMPING]
    if par[FORCE_FEEDBACK] != 0.0:
        for i in range(6):
            x[i] -= mem[F_BODY + i]
    tau = mem[TAU:TAU + nv]
    for c in range(nv):
        s = 0.0
        for i in range(6):
            s += x[i] * work[i, c]
        mv = 0.0
        for m in range(nv):
            mv += M[c, m] * v[m]
        tau[c] = s + h[c] - bn * mv
    if par[FRICTION_ON] != 0.0:
        ff = np.empty(nv)
        friction_feed_forward(tau, v, h, par[FRICTION:FRICTION + nv], par[FRICTION + nv:FRICTION + 2 * nv],
                              par[FRICTION + 2 * nv:FRICTION + 3 * nv], int(par[FRICTION_MODE]), ff)
        for c in range(nv):
            tau[c] += ff[c]


class TwistKernel:
    """The per-step driver of :func:`step` for one :class:`~.se3_lie.SE3LieController`
    (twist formulation, diagonal gains): buffers, the integral action, the choice of full or
    staged step, TaskInertia on the staged ones, the floor's and TaskInertia's counters."""

    def __init__(self, ctrl, K_diag, G_diag):
        nv = ctrl.arm.nv
        fr, floor = ctrl.friction, ctrl.inertia_floor
        par = np.zeros(par_size(nv))
        par[K_DIAG:K_DIAG + 6] = K_diag
        par[G_INV:G_D + 6] = G_diag  # [1/a; d/a]
        par[F_D:F_D + 6] = ctrl.desired_wrench
        par[NULL_DAMPING] = ctrl.null_damping
        par[HAS_F_D] = float(bool(np.any(ctrl.desired_wrench)))
        par[FORCE_FEEDBACK] = float(ctrl.use_force_feedback)
        par[FRICTION_ON] = float(fr.active)
        par[FRICTION_MODE] = friction_code(fr.mode)
        par[FRICTION:] = np.concatenate([fr.f, fr.b, fr._scale])
        if floor is not None:
            par[FLOOR], par[FLOOR_RATIO] = 1.0, floor.ratio
            par[W_SQRT:W_SQRT + 6], par[W_ISQRT:W_ISQRT + 6] = floor._w_sqrt, floor._w_isqrt
        self.par = par
        self.mem = np.zeros(mem_size(nv))
        self.work = np.zeros((12, nv))
        self.Jb, self.JbMinv = self.work[:6], self.work[6:]
        self.ctrl, self.floor, self.ti, self.integral = ctrl, floor, ctrl.task_inertia, ctrl.integral
        self.PI = floor.P_and_I if floor is not None else np.zeros((6, 12))
        self._err = np.zeros(3)
        self._no_force = (0.0,) * 6
        self._warm_up(ctrl.arm)

    def _warm_up(self, arm) -> None:
        """Load (or compile) the kernels for this step's argument types now, on throwaway
        buffers, so that neither the loop's timing nor its first step pays for it."""
        ref = Reference()
        ref.rot[:] = arm.rot
        mem, work, PI = self.mem.copy(), self.work.copy(), self.PI.copy()
        for mode in (FULL, STAGE):
            step(mode, 0, False, ref.rot, ref.pos, ref.twist, ref.accel, arm.rot, arm.pos,
                 arm.twist, arm.Jdot_v, arm.J, arm.Minv, arm.M, arm.v, arm.h, np.zeros(6),
                 self._no_force, self.par, PI, mem, work, np.zeros((0, 6)))
        finish(np.zeros(6), arm.M, arm.v, arm.h, self.par, mem, work)

    def __call__(self, t, arm, ref, wrench) -> np.ndarray:
        ctrl, floor, ti, mem = self.ctrl, self.floor, self.ti, self.mem
        integral = self.integral
        if integral is None:
            F_i = self._no_force
        else:
            np.subtract(ref.pos, arm.pos, out=self._err)
            F_i = integral.update_pose(self._err, wrench, ref.rot, arm.rot_T)
        # steps with TaskInertia's condition-number check end in numpy (staged); the floor's
        # refresh runs in the kernel; the counters of both objects are advanced here
        staged = ti.due()
        refresh = floor is not None and floor.due()
        k = ctrl._k
        ctrl._k = k + 1
        status = step(STAGE if staged else FULL, k, refresh, ref.rot, ref.pos, ref.twist,
                      ref.accel, arm.rot, arm.pos, arm.twist, arm.Jdot_v, arm.J, arm.Minv,
                      arm.M, arm.v, arm.h, wrench, F_i, self.par, self.PI, mem, self.work,
                      ctrl._lam_log)
        if status > NEEDS_SOLVE:
            ctrl.raise_out_of_domain(t, mem[LAM + 3:LAM + 6].tolist(), mem[THETA],
                                     mem[WPREV:WPREV + 3].tolist(), status == FLIPPED)
        if floor is not None:  # ApparentInertiaFloor.current's bookkeeping
            if refresh:
                floor.refreshed_elsewhere(bool(mem[FLOOR_ACTIVE]), float(mem[FLOOR_MAX_RATIO]))
            floor.count_step()
        if status == DONE:
            ti.count_unchecked()
        else:  # TaskInertia.solve: its check (staged), or its fallback (the Cholesky failed)
            finish(ti.solve(self.Jb, self.JbMinv, mem[A:A + 6].copy()), arm.M, arm.v, arm.h,
                   self.par, mem, self.work)
        return mem[TAU:].copy()
