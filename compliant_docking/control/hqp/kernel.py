"""HQP-AC's per-step closed-form path, compiled: :func:`hqp_step` (one call per step) and the
scalar pieces it shares with Python (stiffness scale, preload ramp, manipulability gradient).

From the arm's state, the reference and the wrench: F, s, the preload, F_i, Λ⁻¹ = J M⁻¹ Jᵀ,
its eigendecomposition (floored), Λ^½, Λ, D_r (PD check), F_r, b, level 1's closed form, w,
∇w, a_null, N a_null, the friction feed-forward, both candidates' 21 rows and the check.
Everything the constrained path (ProxQP, in Python) reads goes to the flat workspace ``ws``
(views: :func:`layout`); constants are in the flat ``cst``. Returns :data:`FAST` (τ =
Z[1, 2n:]), :data:`SLOW` / :data:`SLOW_OK1` (a row violated; level 1's candidate meets its
rows with SLOW_OK1), :data:`MODAL` (Eq. 29's D_r not PD: the caller writes the modal
design into D_r/√s and finishes the step with :func:`hqp_back`) or :data:`NOT_FINITE` (Λ⁻¹
not finite, from a non-finite state: no step; the caller returns a NaN torque, as the numpy
law did, and the loop stops the run as diverged).
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.control.jit import kernel
from compliant_docking.control.kernel_blocks import cholesky, cholesky_solve, friction_feed_forward

FAST, SLOW, SLOW_OK1, MODAL, NOT_FINITE = 0, 1, 2, 3, 4

# scalar parameters at the head of ``cst``
P_DEADBAND, P_KMIN, P_KALPHA, P_THRESH, P_OMEGA, P_KSA = 0, 1, 2, 3, 4, 5
P_INERTIA, P_USE_FF, P_FRICTION, P_FRICTION_MODE, P_EVERY, P_INTEGRAL, P_REG = 6, 7, 8, 9, 10, 11, 12
P_I_GAIN, P_I_LIMIT, P_I_DT, P_I_FREEZE_SQ, P_I_LATERAL, P_I_LATCH = 13, 14, 15, 16, 17, 18  # integral
P_I_ROT_GAIN, P_I_ROT_LIMIT = 19, 20  # the integral's orientation part
N_PAR = 21
# scalar state and results at the head of ``ws``
W_PRELOAD = 0  # 4 floats: value, in contact, step, target (compliance.preload_step)
W_FLOOR, W_MAX_COND, W_SINGULAR, W_FAST = 4, 5, 6, 7  # counters and the largest cond(Λ⁻¹)
W_F, W_S, W_W, W_SQRT_S, W_INTEGRAL = 8, 9, 10, 11, 12  # F, s, w, √s, F_i (3)
W_I_STATE, W_I_FROZEN, W_I_MAX = 15, 18, 19  # the integral's ∫P e dt (3), frozen steps, max ‖F_i‖
W_I_LATCHED = 20  # 1 once the latched integral froze for good
W_I_TORQUE, W_I_ROT_STATE, W_I_ROT_MAX = 21, 24, 27  # M_i (3), ∫e_R dt (3), max ‖M_i‖
N_SCALARS = 28
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


# Fields of ``cst`` (C_*) and ``ws`` (W_* arrays) in order; ``off[field]`` is where one starts.
C_K0, C_P, C_AXIS, C_TJI, C_HALF, C_FRICTION_F, C_FRICTION_B, C_FRICTION_SCALE = range(8)
W_DK, W_Z, W_JMINV, W_LAM_INV, W_LAM, W_LAM_SQRT, W_V, W_ROOT, W_FR, W_B = range(8, 18)
W_CHOL, W_CHOL2, W_Y, W_G, W_GRAD, W_A_NULL, W_NA, W_T, W_Y_ROWS, W_Z_ROWS, W_FF = range(18, 29)
N_FIELDS = 29


def layout(n: int) -> tuple[np.ndarray, int, int]:
    """(off, size of cst, size of ws) for an n-joint arm: off (int64) has each field's start.

    cst: K0 (6), P (6×6), axis (3), T_ji ((2n+1)×n), half (3n), friction f, b, scale (n each);
    ws: [D_r; K_r] (12×6), z (12), J M⁻¹ (6×n), Λ⁻¹, Λ, Λ^½, V (6×6 each), λ^½, F_r, b (6),
    two Cholesky factors (6×6), y (6), G (6×n), ∇w/w, a_null, N a_null (n each),
    T ((3n+1)×3n), Y (2×(3n+1)), Z (2×3n), friction feed-forward (n).
    """
    m = 3 * n
    cst_sizes = (6, 36, 3, (2 * n + 1) * n, m, n, n, n)
    ws_sizes = (72, 12, 6 * n, 36, 36, 36, 36, 6, 6, 6, 36, 36, 6, 6 * n, n, n, n)
    ws_sizes_rows = ((m + 1) * m, 2 * (m + 1), 2 * m, n)  # T, Y, Z, friction feed-forward
    ws_all = ws_sizes + ws_sizes_rows
    off = np.zeros(N_FIELDS, dtype=np.int64)
    off[:8] = N_PAR + np.cumsum((0,) + cst_sizes[:-1])
    off[8:] = N_SCALARS + np.cumsum((0,) + ws_all[:-1])
    return off, N_PAR + sum(cst_sizes), N_SCALARS + sum(ws_all)


@kernel
def _vec(a, off, field, size):
    return a[off[field] : off[field] + size]


@kernel
def _mat(a, off, field, rows, cols):
    return a[off[field] : off[field] + rows * cols].reshape((rows, cols))


@kernel
def clamped_step(ws, state, out, e0, e1, e2, dt, gain, limit):
    """control.integral._clamped_step, compiled: ws[state:state+3] += dt·e, scaled back so
    that gain·‖state‖ ≤ limit; ws[out:out+3] = gain·state; returns that norm."""
    s0, s1, s2 = ws[state] + dt * e0, ws[state + 1] + dt * e1, ws[state + 2] + dt * e2
    size = gain * math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    if size > limit:  # clamp the state with the output
        shrink = limit / size
        s0, s1, s2 = s0 * shrink, s1 * shrink, s2 * shrink
        size = limit
    ws[state], ws[state + 1], ws[state + 2] = s0, s1, s2
    ws[out], ws[out + 1], ws[out + 2] = gain * s0, gain * s1, gain * s2
    return size


@kernel
def integral_step(cst, ws, wrench, e0, e1, e2, u0, u1, u2, rot_err):
    """control.integral.PoseIntegral.update, compiled (the same float operations in the
    same order; the state in ws, the parameters in cst, u the docking axis, rot_err the
    orientation error log3(R_d Rᵀ))."""
    f0, f1, f2 = wrench[0], wrench[1], wrench[2]
    if ws[W_I_LATCHED] != 0.0 or f0 * f0 + f1 * f1 + f2 * f2 > cst[P_I_FREEZE_SQ]:
        ws[W_I_FROZEN] += 1.0
        ws[W_I_LATCHED] = cst[P_I_LATCH]
        return
    if cst[P_I_LATERAL] != 0.0:  # drop the component along the docking axis
        along = e0 * u0 + e1 * u1 + e2 * u2
        e0, e1, e2 = e0 - along * u0, e1 - along * u1, e2 - along * u2
    size = clamped_step(ws, W_I_STATE, W_INTEGRAL, e0, e1, e2, cst[P_I_DT], cst[P_I_GAIN], cst[P_I_LIMIT])
    if size > ws[W_I_MAX]:
        ws[W_I_MAX] = size
    if cst[P_I_ROT_GAIN] != 0.0:
        r0, r1, r2, dt = rot_err[0], rot_err[1], rot_err[2], cst[P_I_DT]
        size = clamped_step(
            ws, W_I_ROT_STATE, W_I_TORQUE, r0, r1, r2, dt, cst[P_I_ROT_GAIN], cst[P_I_ROT_LIMIT]
        )
        if size > ws[W_I_ROT_MAX]:
            ws[W_I_ROT_MAX] = size


@kernel
def hqp_step(J, M, Minv, h, q, v, Jdot_v, twist, pos, ref_twist, ref_pos, ref_accel, rot_err, wrench, cst, ws, off, rec, k):  # fmt: skip
    """One control step's closed-form path (module doc); ``rot_err`` = log3(R_d Rᵀ)."""
    n = J.shape[1]
    JMinv, lam_inv, lam = (
        _mat(ws, off, W_JMINV, 6, n),
        _mat(ws, off, W_LAM_INV, 6, 6),
        _mat(ws, off, W_LAM, 6, 6),
    )
    lam_sqrt, V, root = _mat(ws, off, W_LAM_SQRT, 6, 6), _mat(ws, off, W_V, 6, 6), _vec(ws, off, W_ROOT, 6)
    DK, L = _mat(ws, off, W_DK, 12, 6), _mat(ws, off, W_CHOL, 6, 6)
    K0, P = _vec(cst, off, C_K0, 6), _mat(cst, off, C_P, 6, 6)

    # contact magnitude F, stiffness K_r = s·K0, preload p
    F = 0.0
    if cst[P_USE_FF] != 0.0:
        ww = 0.0
        for i in range(6):
            ww += wrench[i] * wrench[i]
        F = max(math.sqrt(ww) - cst[P_DEADBAND], 0.0)
    s = stiffness_scale(F, cst[P_KMIN], cst[P_KALPHA])
    ws[W_F], ws[W_S], ws[W_SQRT_S] = F, s, math.sqrt(s)
    for i in range(6):
        DK[6 + i, i] = s * K0[i]
    preload_step(ws[W_PRELOAD : W_PRELOAD + 4], F)
    if cst[P_INTEGRAL] != 0.0:  # F_i, M_i from x_d − x, e_R (docs/controllers/integral.md)
        a = off[C_AXIS]
        e0, e1, e2 = ref_pos[0] - pos[0], ref_pos[1] - pos[1], ref_pos[2] - pos[2]
        integral_step(cst, ws, wrench, e0, e1, e2, cst[a], cst[a + 1], cst[a + 2], rot_err)

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
    if low * ws[W_MAX_COND] < top:  # a new largest condition number
        ws[W_MAX_COND] = top / low if low > 0.0 else math.inf
    if low * cst[P_THRESH] < top:  # also when low ≤ 0: lift to λ_max/threshold
        ws[W_FLOOR] += 1.0
        floor = max(top, 1e-300) / cst[P_THRESH]
        for i in range(6):
            eigval[i] = max(eigval[i], floor)
    for i in range(6):
        root[i] = np.sqrt(eigval[i])
    # Λ^½ = Vs Vᵀ, Λ = Vs Vsᵀ with Vs = V diag(λ^-½); D_r/√s = Λ^½ ∘ P
    Vs = _mat(ws, off, W_CHOL2, 6, 6)  # scratch (the back half uses it for a factor)
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
    return hqp_back(J, M, Minv, h, q, v, Jdot_v, twist, pos, ref_twist, ref_pos, ref_accel, rot_err, cst, ws, off, rec, k)  # fmt: skip


@kernel
def hqp_back(J, M, Minv, h, q, v, Jdot_v, twist, pos, ref_twist, ref_pos, ref_accel, rot_err, cst, ws, off, rec, k):  # fmt: skip
    """The step after Λ and D_r/√s (called by :func:`hqp_step`; after :data:`MODAL`, by the
    controller once D_r/√s holds the modal design)."""
    n = J.shape[1]
    m = 3 * n
    DK, z, JMinv = _mat(ws, off, W_DK, 12, 6), _vec(ws, off, W_Z, 12), _mat(ws, off, W_JMINV, 6, n)
    lam_inv, lam = _mat(ws, off, W_LAM_INV, 6, 6), _mat(ws, off, W_LAM, 6, 6)
    F_r, b, y = _vec(ws, off, W_FR, 6), _vec(ws, off, W_B, 6), _vec(ws, off, W_Y, 6)
    L, L2, G = _mat(ws, off, W_CHOL, 6, 6), _mat(ws, off, W_CHOL2, 6, 6), _mat(ws, off, W_G, 6, n)
    grad, a_null, Na = _vec(ws, off, W_GRAD, n), _vec(ws, off, W_A_NULL, n), _vec(ws, off, W_NA, n)
    T, Y = _mat(ws, off, W_T, m + 1, m), _mat(ws, off, W_Y_ROWS, 2, m + 1)
    Z, ff = _mat(ws, off, W_Z_ROWS, 2, m), _vec(ws, off, W_FF, n)
    T_ji, half = _mat(cst, off, C_TJI, 2 * n + 1, n), _vec(cst, off, C_HALF, m)
    preload = ws[W_PRELOAD]
    reg = cst[P_REG]

    for i in range(6):
        for j in range(6):
            DK[i, j] *= ws[W_SQRT_S]
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
    for i in range(3):  # F_i, M_i (0 when off) and the preload along the axis
        F_r[i] += ws[W_INTEGRAL + i] + preload * cst[off[C_AXIS] + i]
    if cst[P_I_ROT_GAIN] != 0.0:
        for i in range(3):
            F_r[3 + i] += ws[W_I_TORQUE + i]
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
        if cst[P_INERTIA] != 0.0:  # M⁻¹Jᵀ(J M⁻¹Jᵀ + εI)⁻¹ b: min ‖Jq̈ − b‖² + ε q̈ᵀMq̈
            for i in range(6):
                for j in range(i + 1):
                    JJ[i, j] = lam_inv[i, j]
                JJ[i, i] += reg
            cholesky(JJ, L2)  # Λ⁻¹ + εI is PD whenever J Jᵀ + εI is
            cholesky_solve(L2, y)
            rows = JMinv  # q̈ = (J M⁻¹)ᵀy
        else:
            cholesky_solve(L, y)
            rows = J  # q̈ = Jᵀy
        for c in range(n):
            t = 0.0
            for i in range(6):
                t += y[i] * rows[i, c]
            X0[c] = t
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
    omega = cst[P_OMEGA]
    if w < omega and chol_ok and cst[P_KSA] > 0.0:
        ws[W_SINGULAR] += 1.0
        for i in range(6):
            for c in range(n):
                G[i, c] = J[i, c]
        for c in range(n):  # G = (J Jᵀ + εI)⁻¹ J, column by column
            cholesky_solve(L, G[:, c])
        gradient_over_w(J, G, grad)
        direction = ff  # scratch until the friction feed-forward
        if cst[P_INERTIA] != 0.0:
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
            gain = cst[P_KSA] * (omega - w) / (omega * norm)
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
    if cst[P_FRICTION] != 0.0:  # ĥ = h + the feed-forward of the final candidate's τ_pre
        f, fb = _vec(cst, off, C_FRICTION_F, n), _vec(cst, off, C_FRICTION_B, n)
        scale = _vec(cst, off, C_FRICTION_SCALE, n)
        friction_feed_forward(Z[1, 2 * n :], v, h, f, fb, scale, int(cst[P_FRICTION_MODE]), ff)
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
        rec[k, 0], rec[k, 1], rec[k, 2], rec[k, 3] = ws[W_F], ws[W_S], preload, w
    ws[W_W] = w
    if ok0 and ok1 and cst[P_EVERY] == 0.0:
        ws[W_FAST] += 1.0
        return FAST
    return SLOW_OK1 if ok0 else SLOW
