"""HQP-AC's per-step closed-form path, compiled: :func:`hqp_step` (one call per step) and the
scalar pieces it shares with Python (stiffness scale, preload ramp, manipulability gradient).

From the arm's state, the reference and the wrench: F, s, the preload, F_i, Λ⁻¹ = J M⁻¹ Jᵀ,
its eigendecomposition (floored), Λ^½, Λ, D_r (PD check), F_r, b, level 1's closed form, w,
∇w, a_null, N a_null, the friction feed-forward, both candidates' 21 rows and the check.
Inputs and outputs are numpy records, read and written by field name on both sides: the
law's constants in ``params`` (:func:`params_dtype`), everything the constrained path (ProxQP,
in Python) reads in ``work`` (:func:`work_dtype`), the integral action's parameters and
state in ``integral`` (control/integral.py's record, advanced by its one compiled step), one
row per step of ``rec`` (:data:`STEP_RECORD`). Returns :data:`FAST` (τ =
Z[1, 2n:]), :data:`SLOW` / :data:`SLOW_OK1` (a row violated; level 1's candidate meets its
rows with SLOW_OK1), :data:`MODAL` (Eq. 29's D_r not PD: the caller writes the modal
design into D_r/√s and finishes the step with :func:`hqp_back`) or :data:`NOT_FINITE` (Λ⁻¹
not finite, from a non-finite state: no step; the caller returns a NaN torque, as the numpy
law did, and the loop stops the run as diverged).
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.control.integral import integral_step
from compliant_docking.control.jit import kernel
from compliant_docking.control.kernel_blocks import cholesky, cholesky_solve, friction_feed_forward

FAST, SLOW, SLOW_OK1, MODAL, NOT_FINITE = 0, 1, 2, 3, 4

F8, I8, B1 = np.float64, np.int64, np.bool_
#: the per-step record the controller's time series read
STEP_RECORD = np.dtype([("F", F8), ("s", F8), ("preload", F8), ("w", F8)], align=True)


def params_dtype(n: int) -> np.dtype:
    """The law's constants for an n-joint arm (set once by the controller)."""
    m = 3 * n
    return np.dtype(
        [
            ("deadband", F8), ("K_min_ratio", F8), ("k_alpha", F8), ("threshold", F8),
            ("omega_th", F8), ("k_sa", F8), ("regulariser", F8),
            ("inertia_metric", B1), ("use_force_feedback", B1), ("solve_every_step", B1),
            ("friction", B1), ("friction_mode", I8),  # kernel_blocks.FRICTION_CODES
            ("K0", F8, (6,)), ("P", F8, (6, 6)),  # D_r/√s = Λ^½ ∘ P, P = √K0 + √K0ᵀ
            ("axis", F8, (3,)),  # the docking axis (unit): the preload's direction
            ("T_ji", F8, (2 * n + 1, n)),  # [q, v, 1] → q̈_ji
            ("half", F8, (m,)),  # the rows' half widths
            ("friction_f", F8, (n,)), ("friction_b", F8, (n,)), ("friction_scale", F8, (n,)),
        ],
        align=True,
    )  # fmt: skip


def work_dtype(n: int) -> np.dtype:
    """The kernel's state, results and scratch for an n-joint arm (the controller reads it)."""
    m = 3 * n
    mat6 = (F8, (6, 6))
    return np.dtype(
        [
            ("preload", F8, (4,)),  # value, in contact, step, target (compliance.preload_step)
            ("floor_steps", I8), ("singular_steps", I8), ("fast_steps", I8),
            ("max_cond", F8),  # the largest cond(Λ⁻¹)
            ("F", F8), ("s", F8), ("sqrt_s", F8), ("w", F8),
            ("DK", F8, (12, 6)),  # [D_r; K_r]
            ("z", F8, (12,)), ("JMinv", F8, (6, n)),
            ("lam_inv", *mat6), ("lam", *mat6), ("lam_sqrt", *mat6), ("V", *mat6),
            ("root", F8, (6,)), ("F_r", F8, (6,)), ("b", F8, (6,)),
            ("chol", *mat6), ("chol2", *mat6),  # two Cholesky factors
            ("y", F8, (6,)), ("G", F8, (6, n)), ("grad", F8, (n,)), ("a_null", F8, (n,)), ("Na", F8, (n,)),
            ("T", F8, (m + 1, m)),  # [q̈, q, v, 1] → the rows minus their mid values
            ("Y", F8, (2, m + 1)), ("Z", F8, (2, m)),  # both candidates' [q̈, q, v, 1] and rows
            ("ff", F8, (n,)),  # the friction feed-forward
        ],
        align=True,
    )  # fmt: skip


#: contact magnitude above which the preload ramps up [N] (docs/control_laws.md §2)
PRELOAD_CONTACT_N = 1.0
#: contact magnitude below which the contact counts as lost again [N] (hysteresis)
PRELOAD_RELEASE_N = 0.5


# The law's scalar pieces, compiled once: the step kernel calls them, and compliance.py and
# manipulability.py import them for Python's use.
@kernel
def stiffness_scale(F, K_min_ratio, k_alpha):
    """s with K_r = s·K0: s = clip(1 − α, K_min_ratio, 1), α = 1/(1 + exp(−k_alpha F)) (equal
    to the element-wise clip((1 − α)K0, K_min_ratio K0, K0) for K0 ≥ 0); 0.5 at F = 0 and
    non-increasing in F (1 − α = 1/(1 + exp(k_alpha F)))."""
    x = k_alpha * F
    one_minus_alpha = 1.0 / (1.0 + math.exp(x)) if x < 700.0 else 0.0
    return min(max(one_minus_alpha, K_min_ratio), 1.0)


@kernel
def preload_step(state, F):
    """One step of the preload ramp (compliance.PreloadRamp); state = [value, in contact
    (0/1), step, target]. Returns the new value."""
    if F > PRELOAD_CONTACT_N:
        state[1] = 1.0
    elif F < PRELOAD_RELEASE_N:
        state[1] = 0.0
    if state[1] != 0.0:
        state[0] = min(state[0] + state[2], state[3])
    elif state[0] != 0.0:
        state[0] = max(state[0] - state[2], 0.0)
    return state[0]


@kernel
def gradient_over_w(J, G, out):
    """∇w/w into ``out`` for J = [v; ω] (6×n) and G = (J Jᵀ)⁻¹ J (manipulability.py):
    out_i = Σ_{j≤i} v_i·b_j + Σ_{j>i} ω_i·a_j, a_j = v_j × Gv_j + ω_j × Gω_j,
    b_j = Gv_j × ω_j (one pass from the end for the a-sums, one from the start for the b's)."""
    n = J.shape[1]
    ax = ay = az = 0.0
    for i in range(n - 1, -1, -1):
        out[i] = J[3, i] * ax + J[4, i] * ay + J[5, i] * az
        v0, v1, v2, w0, w1, w2 = J[0, i], J[1, i], J[2, i], J[3, i], J[4, i], J[5, i]
        g0, g1, g2, h0, h1, h2 = G[0, i], G[1, i], G[2, i], G[3, i], G[4, i], G[5, i]
        ax += v1 * g2 - v2 * g1 + w1 * h2 - w2 * h1
        ay += v2 * g0 - v0 * g2 + w2 * h0 - w0 * h2
        az += v0 * g1 - v1 * g0 + w0 * h1 - w1 * h0
    bx = by = bz = 0.0
    for i in range(n):
        g0, g1, g2, w0, w1, w2 = G[0, i], G[1, i], G[2, i], J[3, i], J[4, i], J[5, i]
        bx += g1 * w2 - g2 * w1
        by += g2 * w0 - g0 * w2
        bz += g0 * w1 - g1 * w0
        out[i] += J[0, i] * bx + J[1, i] * by + J[2, i] * bz


@kernel
def transposed_product(A, y, out):
    """out = Aᵀy (A: 6×n)."""
    for c in range(A.shape[1]):
        t = 0.0
        for i in range(6):
            t += y[i] * A[i, c]
        out[c] = t


@kernel
def hqp_step(J, M, Minv, h, q, v, Jdot_v, twist, pos, ref_twist, ref_pos, ref_accel, rot_err, wrench, params, work, integral, rec, k):  # fmt: skip
    """One control step's closed-form path (module doc); ``rot_err`` = log3(R_d Rᵀ);
    ``params``, ``work``, ``integral``: one-element record arrays (module doc)."""
    n = J.shape[1]
    par, ws = params[0], work[0]
    JMinv, lam_inv, lam, lam_sqrt, V, root = ws.JMinv, ws.lam_inv, ws.lam, ws.lam_sqrt, ws.V, ws.root
    DK, L, K0, P = ws.DK, ws.chol, par.K0, par.P

    # contact magnitude F, stiffness K_r = s·K0, preload p
    F = 0.0
    if par.use_force_feedback:
        ww = 0.0
        for i in range(6):
            ww += wrench[i] * wrench[i]
        F = max(math.sqrt(ww) - par.deadband, 0.0)
    s = stiffness_scale(F, par.K_min_ratio, par.k_alpha)
    ws.F, ws.s, ws.sqrt_s = F, s, math.sqrt(s)
    for i in range(6):
        DK[6 + i, i] = s * K0[i]
    preload_step(ws.preload, F)
    it = integral[0]
    if it.on:  # F_i, M_i from x_d − x, e_R (docs/controllers/integral.md)
        e0, e1, e2 = ref_pos[0] - pos[0], ref_pos[1] - pos[1], ref_pos[2] - pos[2]
        integral_step(it, e0, e1, e2, wrench, rot_err)

    # Λ⁻¹ = J M⁻¹ Jᵀ (symmetric by construction), its eigendecomposition and floor
    for i in range(6):
        for c in range(n):
            t = 0.0
            for j in range(n):
                t += J[i, j] * Minv[j, c]
            JMinv[i, c] = t
    for i in range(6):
        for j in range(i, 6):
            t = 0.0
            for c in range(n):
                t += JMinv[i, c] * J[j, c]
            lam_inv[i, j] = t
            lam_inv[j, i] = t
    if not np.all(np.isfinite(lam_inv)):  # a non-finite state: no step (eigh would raise)
        return NOT_FINITE
    eigval, vectors = np.linalg.eigh(lam_inv)
    V[:, :] = vectors
    top, low = eigval[5], eigval[0]
    if low * ws.max_cond < top:  # a new largest condition number
        ws.max_cond = top / low if low > 0.0 else math.inf
    if low * par.threshold < top:  # also when low ≤ 0: lift to λ_max/threshold
        ws.floor_steps += 1
        floor = max(top, 1e-300) / par.threshold
        for i in range(6):
            eigval[i] = max(eigval[i], floor)
    for i in range(6):
        root[i] = np.sqrt(eigval[i])
    # Λ^½ = Vs Vᵀ, Λ = Vs Vsᵀ with Vs = V diag(λ^-½); D_r/√s = Λ^½ ∘ P
    Vs = ws.chol2  # scratch (the back half uses it for a factor)
    for i in range(6):
        for c in range(6):
            Vs[i, c] = V[i, c] / root[c]
    for i in range(6):
        for j in range(i, 6):
            t = 0.0
            u = 0.0
            for c in range(6):
                t += Vs[i, c] * V[j, c]
                u += Vs[i, c] * Vs[j, c]
            lam_sqrt[i, j] = t
            lam_sqrt[j, i] = t
            lam[i, j] = u
            lam[j, i] = u
            DK[i, j] = t * P[i, j]
            DK[j, i] = t * P[j, i]
    if not cholesky(DK[:6], L):
        return MODAL
    return hqp_back(J, M, Minv, h, q, v, Jdot_v, twist, pos, ref_twist, ref_pos, ref_accel, rot_err, params, work, integral, rec, k)  # fmt: skip


@kernel
def hqp_back(J, M, Minv, h, q, v, Jdot_v, twist, pos, ref_twist, ref_pos, ref_accel, rot_err, params, work, integral, rec, k):  # fmt: skip
    """The step after Λ and D_r/√s (called by :func:`hqp_step`; after :data:`MODAL`, by the
    controller once D_r/√s holds the modal design)."""
    n = J.shape[1]
    m = 3 * n
    par, ws, it = params[0], work[0], integral[0]
    DK, z, JMinv, lam_inv, lam = ws.DK, ws.z, ws.JMinv, ws.lam_inv, ws.lam
    F_r, b, y, L, L2, G = ws.F_r, ws.b, ws.y, ws.chol, ws.chol2, ws.G
    grad, a_null, Na, T, Y, Z, ff = ws.grad, ws.a_null, ws.Na, ws.T, ws.Y, ws.Z, ws.ff
    T_ji, half, axis = par.T_ji, par.half, par.axis
    preload = ws.preload[0]
    reg = par.regulariser

    for i in range(6):
        for j in range(6):
            DK[i, j] *= ws.sqrt_s
    # F_r = [D_r; K_r]ᵀ [ν_d − ν; x_d − x; log3(R_d Rᵀ)] + [F_i; M_i] + p·[axis; 0]
    for i in range(6):
        z[i] = ref_twist[i] - twist[i]
    for i in range(3):
        z[6 + i] = ref_pos[i] - pos[i]
        z[9 + i] = rot_err[i]
    for j in range(6):
        t = 0.0
        for i in range(12):
            t += z[i] * DK[i, j]
        F_r[j] = t
    F_i, M_i = it.force, it.torque
    for i in range(3):  # F_i, M_i (0 when off) and the preload along the axis
        F_r[i] += F_i[i] + preload * axis[i]
    if it.rot_gain != 0.0:
        for i in range(3):
            F_r[3 + i] += M_i[i]
    # b = Λ⁻¹F_r + ν̇_d − J̇v
    for i in range(6):
        t = 0.0
        for j in range(6):
            t += lam_inv[i, j] * F_r[j]
        b[i] = t + ref_accel[i] - Jdot_v[i]

    # level 1's closed form (min-norm least squares) and w = √det(J Jᵀ + εI)
    JJ = L2  # J Jᵀ + εI (lower triangle), then (inertia metric) Λ⁻¹ + εI
    for i in range(6):
        for j in range(i + 1):
            t = 0.0
            for c in range(n):
                t += J[i, c] * J[j, c]
            JJ[i, j] = t
        JJ[i, i] += reg
    chol_ok = cholesky(JJ, L)
    X0, X1 = Y[0, :n], Y[1, :n]
    w = 0.0
    if chol_ok:
        w = 1.0
        for i in range(6):
            w *= L[i, i]
        y[:] = b
        if par.inertia_metric:  # M⁻¹Jᵀ(J M⁻¹Jᵀ + εI)⁻¹ b: min ‖Jq̈ − b‖² + ε q̈ᵀMq̈
            for i in range(6):
                for j in range(i + 1):
                    JJ[i, j] = lam_inv[i, j]
                JJ[i, i] += reg
            cholesky(JJ, L2)  # Λ⁻¹ + εI is PD whenever J Jᵀ + εI is
            cholesky_solve(L2, y)
            transposed_product(JMinv, y, X0)  # q̈ = (J M⁻¹)ᵀy
        else:
            cholesky_solve(L, y)
            transposed_product(J, y, X0)  # q̈ = Jᵀy
    else:  # J Jᵀ + εI is PD for every finite J (a non-finite one returned above)
        X0[:] = np.nan
    for c in range(n):
        Y[0, n + c] = Y[1, n + c] = q[c]
        Y[0, 2 * n + c] = Y[1, 2 * n + c] = v[c]
    Y[0, m] = Y[1, m] = 1.0

    # level 2's target a_null = k_ji q̈_ji (+ k_sa q̈_sa below ω_th)
    for c in range(n):
        t = 0.0
        for i in range(2 * n):
            t += Y[0, n + i] * T_ji[i, c]
        a_null[c] = t + T_ji[2 * n, c]
    omega = par.omega_th
    if w < omega and chol_ok and par.k_sa > 0.0:
        ws.singular_steps += 1
        for i in range(6):
            for c in range(n):
                G[i, c] = J[i, c]
        for c in range(n):  # G = (J Jᵀ + εI)⁻¹ J, column by column
            cholesky_solve(L, G[:, c])
        gradient_over_w(J, G, grad)
        direction = ff  # scratch until the friction feed-forward
        if par.inertia_metric:
            for i in range(n):
                t = 0.0
                for j in range(n):
                    t += Minv[i, j] * grad[j]
                direction[i] = t
        else:
            direction[:] = grad
        norm = 0.0
        for i in range(n):
            norm += direction[i] * direction[i]
        norm = math.sqrt(norm)
        if norm > 0.0:
            gain = par.k_sa * (omega - w) / (omega * norm)
            for i in range(n):
                a_null[i] += gain * direction[i]
    # N a_null = a_null − M⁻¹JᵀΛ J a_null; the final candidate q̈ + N a_null
    Ja = F_r  # scratch: F_r is not needed any more
    for i in range(6):
        t = 0.0
        for c in range(n):
            t += J[i, c] * a_null[c]
        y[i] = t
    for i in range(6):
        t = 0.0
        for j in range(6):
            t += lam[i, j] * y[j]
        Ja[i] = t
    for c in range(n):
        t = 0.0
        for i in range(6):
            t += Ja[i] * JMinv[i, c]
        Na[c] = a_null[c] - t
        X1[c] = X0[c] + Na[c]

    # both candidates against every row: Z = [q̈, q, v, 1]·T (T's M block and ĥ row here)
    for i in range(n):
        for j in range(n):
            T[i, 2 * n + j] = M[i, j]
        T[m, 2 * n + i] = h[i]
    for r in range(2):
        for c in range(m):
            t = 0.0
            for i in range(m + 1):
                t += Y[r, i] * T[i, c]
            Z[r, c] = t
    if par.friction:  # ĥ = h + the feed-forward of the final candidate's τ_pre
        f, fb, scale = par.friction_f, par.friction_b, par.friction_scale
        friction_feed_forward(Z[1, 2 * n :], v, h, f, fb, scale, par.friction_mode, ff)
        for i in range(n):
            Z[0, 2 * n + i] += ff[i]
            Z[1, 2 * n + i] += ff[i]
            T[m, 2 * n + i] += ff[i]
    ok0 = True
    ok1 = True
    for c in range(m):
        if not abs(Z[0, c]) <= half[c]:
            ok0 = False
        if not abs(Z[1, c]) <= half[c]:
            ok1 = False
    if k < rec.shape[0]:
        row = rec[k]
        row.F, row.s, row.preload, row.w = ws.F, ws.s, preload, w
    ws.w = w
    if ok0 and ok1 and not par.solve_every_step:
        ws.fast_steps += 1
        return FAST
    return SLOW_OK1 if ok0 else SLOW
