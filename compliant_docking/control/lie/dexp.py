"""dexp, the right-trivialised differential of exp on SE(3) (its left Jacobian), its
inverse and its analytic time derivative.

dexp([v; w]) = [[J(w), Q(v, w)], [0, J(w)]] and dexp⁻¹ = [[J⁻¹, Qi], [0, J⁻¹]], where the
off-diagonal blocks are the directional derivatives of the SO(3) blocks with respect to
w in the direction v; the time derivative along λ(t) is [[Jd, Qd], [0, Jd]], Jd = Q(ẇ, w),
Qd = Q(v̇, w) + D²_w J(w)[v, ẇ] (see the package docstring for the formulas and the
Taylor switches).
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.control.lie.series import (
    TAYLOR_THETA_0,
    block3,
    block6,
    block6_entries,
    coef0,
    coef1,
    coef2,
    floats,
    trig_terms,
)
from compliant_docking.control.lie.so3 import j_block, jinv_block

_sqrt = math.sqrt
_fromiter = np.fromiter
_F64 = np.float64


def _q_block(b, c, a1, b1, c1, v0, v1, v2, w0, w1, w2):
    """Q(v, w) = D_w J(w)[v] = a1 s I + hat3(b v + b1 s w) + c (v w^T + w v^T) + c1 s w w^T."""
    s = w0 * v0 + w1 * v1 + w2 * v2
    bs = b1 * s
    hs = 0.5 * c1 * s
    return block3(
        a1 * s,
        b * v0 + bs * w0, b * v1 + bs * w1, b * v2 + bs * w2,
        w0, w1, w2,
        c * v0 + hs * w0, c * v1 + hs * w1, c * v2 + hs * w2,
    )



def _qinv_block(g1, e, e1, v0, v1, v2, w0, w1, w2):
    """Qi(v, w) = D_w J^-1(w)[v] = g1 s I - hat3(v)/2 + e (v w^T + w v^T) + e1 s w w^T."""
    s = w0 * v0 + w1 * v1 + w2 * v2
    hs = 0.5 * e1 * s
    return block3(
        g1 * s,
        -0.5 * v0, -0.5 * v1, -0.5 * v2,
        w0, w1, w2,
        e * v0 + hs * w0, e * v1 + hs * w1, e * v2 + hs * w2,
    )


def _qdot_block(b, c, a1, b1, c1, a2, b2, c2, v0, v1, v2, w0, w1, w2, u0, u1, u2, z0, z1, z2):
    """d/dt Q(v(t), w(t)) with v_dot = u, w_dot = z.

    Qd = Q(u, w) + D_w^2 J(w)[v, z], where with s_v = w.v, s_z = w.z, s_u = w.u, r = v.z:

        alpha = a1 (s_u + r) + a2 s_v s_z
        k     = b u + (b1 (s_u + r) + b2 s_v s_z) w + b1 s_v z + b1 s_z v
        sym   = w p^T + p w^T + c (v z^T + z v^T),
        p     = c u + c1 s_v z + c1 s_z v + (c1 (s_u + r) + c2 s_v s_z)/2 w
        Qd    = alpha I + hat3(k) + sym.
    """
    sv = w0 * v0 + w1 * v1 + w2 * v2
    sz = w0 * z0 + w1 * z1 + w2 * z2
    sur = w0 * u0 + w1 * u1 + w2 * u2 + v0 * z0 + v1 * z1 + v2 * z2
    svz = sv * sz
    al = a1 * sur + a2 * svz
    kw = b1 * sur + b2 * svz
    b1v = b1 * sv
    b1z = b1 * sz
    pw = 0.5 * (c1 * sur + c2 * svz)
    c1v = c1 * sv
    c1z = c1 * sz
    p0 = c * u0 + c1v * z0 + c1z * v0 + pw * w0
    p1 = c * u1 + c1v * z1 + c1z * v1 + pw * w1
    p2 = c * u2 + c1v * z2 + c1z * v2 + pw * w2
    m0, m1, m2, m3, m4, m5, m6, m7, m8 = block3(
        al,
        b * u0 + kw * w0 + b1v * z0 + b1z * v0,
        b * u1 + kw * w1 + b1v * z1 + b1z * v1,
        b * u2 + kw * w2 + b1v * z2 + b1z * v2,
        w0, w1, w2, p0, p1, p2,
    )
    cv0 = c * v0
    cv1 = c * v1
    cv2 = c * v2
    d01 = cv0 * z1 + z0 * cv1
    d02 = cv0 * z2 + z0 * cv2
    d12 = cv1 * z2 + z1 * cv2
    return (
        m0 + 2.0 * cv0 * z0, m1 + d01, m2 + d02,
        m3 + d01, m4 + 2.0 * cv1 * z1, m5 + d12,
        m6 + d02, m7 + d12, m8 + 2.0 * cv2 * z2,
    )


def _jdot_block(b, c, a1, b1, c1, w0, w1, w2, z0, z1, z2):
    """d/dt J(w(t)) = Q(w_dot, w) (directional derivative of J along w_dot = z)."""
    return _q_block(b, c, a1, b1, c1, z0, z1, z2, w0, w1, w2)


# ----------------------------------------------------------------------------------


# ----------------------------------------------------------------------------------
# dexp and friends
# ----------------------------------------------------------------------------------
def dexp(lam):
    """Right-trivialised differential of exp6 (SE(3) left Jacobian).

    d/dt exp6(lam(t)) = hat6(dexp(lam) lam_dot) exp6(lam);
    dexp(lam) = sum_k ad(lam)^k/(k+1)! = [[J(w), Q(v, w)], [0, J(w)]]  (lam = [v; w]).
    """
    v0, v1, v2, w0, w1, w2 = floats(lam, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    a, b, c, _, _ = coef0(t, x, *trig)
    a1, b1, c1, _, _ = coef1(t, x, *trig)
    return block6(j_block(a, b, c, w0, w1, w2),
                _q_block(b, c, a1, b1, c1, v0, v1, v2, w0, w1, w2))


def dexp_inv(lam):
    """Closed-form inverse of ``dexp``: [[J^-1, Qi], [0, J^-1]], Qi = -J^-1 Q J^-1.

    J^-1 = g I - hat3(w)/2 + e w w^T and Qi = D_w J^-1(w)[v] (see module docstring).
    Valid for |w| < 2 pi (the impedance uses |w| < pi).
    """
    v0, v1, v2, w0, w1, w2 = floats(lam, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    _, _, _, g, e = coef0(t, x, *trig)
    _, _, _, g1, e1 = coef1(t, x, *trig)
    return block6(jinv_block(g, e, w0, w1, w2),
                _qinv_block(g1, e, e1, v0, v1, v2, w0, w1, w2))


def dexp_dot(lam, lam_dot):
    """Analytic time derivative d/dt dexp(lam(t)) given lam and lam_dot.

    = [[Jd, Qd], [0, Jd]] with Jd = Q(w_dot, w) and Qd = Q(v_dot, w) + D_w^2 J(w)[v, w_dot].
    """
    v0, v1, v2, w0, w1, w2 = floats(lam, 6)
    u0, u1, u2, z0, z1, z2 = floats(lam_dot, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    _, b, c, _, _ = coef0(t, x, *trig)
    a1, b1, c1, _, _ = coef1(t, x, *trig)
    a2, b2, c2 = coef2(t, x, *trig)
    return block6(_jdot_block(b, c, a1, b1, c1, w0, w1, w2, z0, z1, z2),
                _qdot_block(b, c, a1, b1, c1, a2, b2, c2,
                            v0, v1, v2, w0, w1, w2, u0, u1, u2, z0, z1, z2))


def dexp_all(lam, lam_dot):
    """(dexp(lam), dexp_inv(lam), dexp_dot(lam, lam_dot)) sharing trig and coefficients.

    This is what the SE(3) impedance controller needs every step.  Returns three 6x6
    arrays (non-overlapping views of one (3, 6, 6) buffer, freshly allocated per call).
    """
    v0, v1, v2, w0, w1, w2 = floats(lam, 6)
    u0, u1, u2, z0, z1, z2 = floats(lam_dot, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    a, b, c, g, e = coef0(t, x, *trig)
    a1, b1, c1, g1, e1 = coef1(t, x, *trig)
    a2, b2, c2 = coef2(t, x, *trig)
    out = _fromiter(
        block6_entries(j_block(a, b, c, w0, w1, w2),
                     _q_block(b, c, a1, b1, c1, v0, v1, v2, w0, w1, w2))
        + block6_entries(jinv_block(g, e, w0, w1, w2),
                       _qinv_block(g1, e, e1, v0, v1, v2, w0, w1, w2))
        + block6_entries(_jdot_block(b, c, a1, b1, c1, w0, w1, w2, z0, z1, z2),
                       _qdot_block(b, c, a1, b1, c1, a2, b2, c2,
                                   v0, v1, v2, w0, w1, w2, u0, u1, u2, z0, z1, z2)),
        _F64, 108,
    ).reshape(3, 6, 6)
    return out[0], out[1], out[2]



def _benchmark(number=20000):  # pragma: no cover - manual tool
    """Print per-call timings (microseconds) of the hot-path functions."""
    import timeit

    import pinocchio as pin

    rng = np.random.default_rng(0)
    out = {}
    for label, scale in (("small angle (Taylor)", 0.05), ("large angle (closed form)", 1.5)):
        lam = rng.standard_normal(6)
        lam[3:] *= scale / np.linalg.norm(lam[3:])
        lam_dot = rng.standard_normal(6)
        cases = {
            "pin.Jexp6": lambda: pin.Jexp6(-lam),
            "dexp": lambda: dexp(lam),
            "dexp_inv": lambda: dexp_inv(lam),
            "dexp_dot": lambda: dexp_dot(lam, lam_dot),
            "dexp_all": lambda: dexp_all(lam, lam_dot),
        }
        for name, fn in cases.items():
            best = min(timeit.repeat(fn, number=number, repeat=5)) / number * 1e6
            out[(label, name)] = best
            print(f"{label:28s} {name:12s} {best:6.2f} us")
    return out


if __name__ == "__main__":  # pragma: no cover
    _benchmark()
