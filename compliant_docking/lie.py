r"""Lie-group maths on SO(3) and SE(3) for the SE(3) impedance controller and planner.

Conventions (fixed; the controllers depend on them)
---------------------------------------------------
* Twists and wrenches are 6-vectors with the LINEAR part first:
  ``xi = [v; w]`` (v linear, w angular), ``F = [f; m]``.
* Poses are 4x4 homogeneous matrices ``T = [[R, p], [0, 1]]``; the ``*_rp``
  variants take/return the pair ``(R, p)``.
* ``hat6(xi) = [[hat3(w), v], [0, 0]]``, ``exp6(xi) = expm(hat6(xi))`` and ``log6``
  is its inverse for rotation angles below pi.
* ``Ad_T = [[R, hat3(p) R], [0, R]]`` so that ``hat6(Ad_T xi) = T hat6(xi) T^-1``;
  ``ad(xi) = [[hat3(w), hat3(v)], [0, hat3(w)]]`` so that
  ``hat6(ad(xi) eta) = [hat6(xi), hat6(eta)]``.
* ``dexp(lam)`` is the RIGHT-trivialised differential of exp (the "left Jacobian"
  J_l of SE(3)):  d/dt Exp(lam(t)) = hat6(dexp(lam) lam_dot) Exp(lam), i.e.
  ``dexp(lam) = sum_k ad(lam)^k / (k+1)!``.  ``dexp_inv`` is its inverse and
  ``dexp_dot(lam, lam_dot)`` is d/dt dexp(lam(t)) (analytic).

Closed forms used
-----------------
With theta = |w|, x = theta^2 and the scalar functions

    a = sin(theta)/theta,  b = (1 - cos theta)/theta^2,  c = (theta - sin theta)/theta^3,

the SO(3) quantities are

    exp3(w)  = cos(theta) I + hat3(a w) + b w w^T
    J(w)     = I + b hat3(w) + c hat3(w)^2      = a I + hat3(b w) + c w w^T
    J(w)^-1  = I - hat3(w)/2 + e hat3(w)^2      = g I - hat3(w)/2 + e w w^T

with g = (theta/2) cot(theta/2) and e = (1 - g)/theta^2.  For a scalar function f(theta)
write f1 = f'(theta)/theta and f2 = f1'(theta)/theta (both even, smooth in x), so that the
directional derivative along u is D f(w)[u] = f1 (w.u).  The SE(3) left Jacobian is

    dexp([v; w])     = [[J(w), Q(v, w)], [0, J(w)]],
    dexp([v; w])^-1  = [[J^-1, Qi(v, w)], [0, J^-1]],

where the off-diagonal blocks are exactly the directional derivatives of the SO(3)
blocks with respect to w in the direction v (this is the "Q matrix" of the literature,
rewritten without matrix products):

    Q(v, w)  = D_w J(w)[v]    = a1 s I + hat3(b v + b1 s w) + c (v w^T + w v^T) + c1 s w w^T
    Qi(v, w) = D_w J^-1(w)[v] = g1 s I - hat3(v)/2 + e (v w^T + w v^T) + e1 s w w^T
                              = -J^-1 Q J^-1,                  with s = w.v.

The time derivative of dexp along lam(t) = [v(t); w(t)] is then

    d/dt dexp = [[Jd, Qd], [0, Jd]],  Jd = Q(w_dot, w),
    Qd = Q(v_dot, w) + D_w^2 J(w)[v, w_dot]

and the second derivative expands with a2, b2, c2 (see ``_qdot_block``).

Taylor switches
---------------
All coefficient functions suffer from cancellation near theta = 0, more so the higher
the derivative order.  They are evaluated by truncated Taylor series in x = theta^2
below a threshold and by the closed form above it:

* order 0 (a, b, c, g, e):        theta < ``TAYLOR_THETA_0`` = 0.1,  5 terms
* order 1 (a1, b1, c1, g1, e1):   theta < ``TAYLOR_THETA_1`` = 0.5,  9 terms
* order 2 (a2, b2, c2):           theta < ``TAYLOR_THETA_2`` = 1.0,  9 terms

At each threshold the truncation error of the series is below 2e-17 relative and the
round-off of the closed form is below ~5e-12 relative, so both branches agree to
~1e-11 relative (tested).  The series coefficients are exact rationals (written as
integer ratios that Python folds into correctly rounded constants).

Domain
------
``log3``/``log6`` return a rotation vector of norm in [0, pi].  The SE(3) impedance is
only defined for |lam_rot| < pi (the logarithm is not unique at pi); call ``log6`` with
``check=True`` (or ``check_rotation_domain``) to raise a ValueError there.

Performance
-----------
The hot-path functions unpack their inputs with ``tolist()`` and do the 3x3 block
algebra on Python floats (no np.cross, no scipy, no per-call temporaries beyond one
output array): about 5x faster than the same algebra written with numpy 3x3 blocks
(dexp: ~4 us against ~20 us).  ``_benchmark()`` (run this file) prints the timings.  Use
``dexp_all`` when dexp, its inverse and its derivative are all needed: it shares the
trigonometric evaluation and the coefficients.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "TAYLOR_THETA_0",
    "TAYLOR_THETA_1",
    "TAYLOR_THETA_2",
    "PI_MARGIN",
    "hat3",
    "vee3",
    "exp3",
    "log3",
    "so3_left_jacobian",
    "so3_left_jacobian_inv",
    "hat6",
    "vee6",
    "exp6",
    "exp6_rp",
    "log6",
    "log6_rp",
    "check_rotation_domain",
    "se3_from_rp",
    "se3_inverse",
    "relative_pose",
    "adjoint",
    "adjoint_rp",
    "adjoint_inv",
    "coadjoint",
    "ad",
    "dexp",
    "dexp_inv",
    "dexp_dot",
    "dexp_all",
]

TAYLOR_THETA_0 = 0.1
"""Below this angle the order-0 coefficients (a, b, c, g, e) use their Taylor series."""
TAYLOR_THETA_1 = 0.5
"""Below this angle the order-1 coefficients (a1, b1, c1, g1, e1) use their Taylor series."""
TAYLOR_THETA_2 = 1.0
"""Below this angle the order-2 coefficients (a2, b2, c2) use their Taylor series."""
PI_MARGIN = 1e-6
"""Default margin (rad): ``check_rotation_domain`` rejects |lam_rot| >= pi - PI_MARGIN."""

_sqrt = math.sqrt
_sin = math.sin
_cos = math.cos
_atan2 = math.atan2
_PI = math.pi
_fromiter = np.fromiter  # faster than np.array for a flat tuple of floats of known length
_F64 = np.float64


# ----------------------------------------------------------------------------------
# Scalar coefficient functions (public kernels on Python floats: hot-loop callers such as
# the se3_lie controller share one evaluation between log6 and dexp⁻ᵀ)
# ----------------------------------------------------------------------------------
def trig_terms(t):
    """Return (sin t, cos t, 1 - cos t) with 1 - cos t = 2 sin^2(t/2) free of cancellation."""
    h = _sin(0.5 * t)
    return _sin(t), _cos(t), 2.0 * h * h


def coef0(t, x, s, co, omc):
    """Order-0 coefficients (a, b, c, g, e) at theta = t, x = t^2.

    a = sin t / t, b = (1 - cos t)/t^2, c = (t - sin t)/t^3,
    g = (t/2) cot(t/2) = t sin t / (2 (1 - cos t)), e = (1 - g)/t^2.
    ``s, co, omc`` are sin t, cos t, 1 - cos t (ignored below the threshold).
    """
    if t < TAYLOR_THETA_0:
        a = 1.0 + x * (-1 / 6 + x * (1 / 120 + x * (-1 / 5040 + x * (1 / 362880))))
        b = 1 / 2 + x * (-1 / 24 + x * (1 / 720 + x * (-1 / 40320 + x * (1 / 3628800))))
        c = 1 / 6 + x * (-1 / 120 + x * (1 / 5040 + x * (-1 / 362880 + x * (1 / 39916800))))
        e = 1 / 12 + x * (1 / 720 + x * (1 / 30240 + x * (1 / 1209600 + x * (1 / 47900160))))
        g = 1.0 - e * x
    else:
        a = s / t
        b = omc / x
        c = (t - s) / (x * t)
        g = t * s / (2.0 * omc)
        e = (1.0 - g) / x
    return a, b, c, g, e


def coef1(t, x, s, co, omc):
    """Order-1 coefficients f1 = f'(t)/t for f in (a, b, c, g, e).

    a1 = (t cos t - sin t)/t^3,            b1 = (t sin t - 2 (1 - cos t))/t^4,
    c1 = (3 sin t - 3 t + t (1 - cos t))/t^5,
    g1 = (sin t - t)/(2 t (1 - cos t)),    e1 = -(g1 + 2 e)/t^2.
    """
    if t < TAYLOR_THETA_1:
        a1 = -1 / 3 + x * (1 / 30 + x * (-1 / 840 + x * (1 / 45360 + x * (-1 / 3991680 + x * (1 / 518918400 + x * (-1 / 93405312000 + x * (1 / 22230464256000 + x * (-1 / 6758061133824000))))))))  # noqa: E501
        b1 = -1 / 12 + x * (1 / 180 + x * (-1 / 6720 + x * (1 / 453600 + x * (-1 / 47900160 + x * (1 / 7264857600 + x * (-1 / 1494484992000 + x * (1 / 400148356608000 + x * (-1 / 135161222676480000))))))))  # noqa: E501
        c1 = -1 / 60 + x * (1 / 1260 + x * (-1 / 60480 + x * (1 / 4989600 + x * (-1 / 622702080 + x * (1 / 108972864000 + x * (-1 / 25406244864000 + x * (1 / 7602818775552000 + x * (-1 / 2838385676206080000))))))))  # noqa: E501
        g1 = -1 / 6 + x * (-1 / 180 + x * (-1 / 5040 + x * (-1 / 151200 + x * (-1 / 4790016 + x * (-691 / 108972864000 + x * (-1 / 5337446400 + x * (-3617 / 666913927680000 + x * (-43867 / 283838567620608000))))))))  # noqa: E501
        e1 = 1 / 360 + x * (1 / 7560 + x * (1 / 201600 + x * (1 / 5987520 + x * (691 / 130767436800 + x * (1 / 6227020800 + x * (3617 / 762187345920000 + x * (43867 / 319318388573184000 + x * (174611 / 44603203483238400000))))))))  # noqa: E501
    else:
        x2 = x * x
        a1 = (t * co - s) / (x * t)
        b1 = (t * s - 2.0 * omc) / x2
        c1 = (3.0 * s - 3.0 * t + t * omc) / (x2 * t)
        g1 = (s - t) / (2.0 * t * omc)
        e = (1.0 - t * s / (2.0 * omc)) / x
        e1 = -(g1 + 2.0 * e) / x
    return a1, b1, c1, g1, e1


def coef2(t, x, s, co, omc):
    """Order-2 coefficients f2 = f1'(t)/t for f in (a, b, c).

    a2 = (3 sin t - 3 t cos t - t^2 sin t)/t^5,
    b2 = (t^2 cos t - 5 t sin t + 8 (1 - cos t))/t^6,
    c2 = (t^2 sin t - 7 t (1 - cos t) + 15 t - 15 sin t)/t^7.
    """
    if t < TAYLOR_THETA_2:
        a2 = 1 / 15 + x * (-1 / 210 + x * (1 / 7560 + x * (-1 / 498960 + x * (1 / 51891840 + x * (-1 / 7783776000 + x * (1 / 1587890304000 + x * (-1 / 422378820864000 + x * (1 / 141919283810304000))))))))  # noqa: E501
        b2 = 1 / 90 + x * (-1 / 1680 + x * (1 / 75600 + x * (-1 / 5987520 + x * (1 / 726485760 + x * (-1 / 124540416000 + x * (1 / 28582025472000 + x * (-1 / 8447576417280000 + x * (1 / 3122224243826688000))))))))  # noqa: E501
        c2 = 1 / 630 + x * (-1 / 15120 + x * (1 / 831600 + x * (-1 / 77837760 + x * (1 / 10897286400 + x * (-1 / 2117187072000 + x * (1 / 543058483968000 + x * (-1 / 177399104762880000 + x * (1 / 71811157608013824000))))))))  # noqa: E501
    else:
        x2 = x * x
        a2 = (3.0 * s - 3.0 * t * co - x * s) / (x2 * t)
        b2 = (x * co - 5.0 * t * s + 8.0 * omc) / (x2 * x)
        c2 = (x * s - 7.0 * t * omc + 15.0 * (t - s)) / (x2 * x * t)
    return a2, b2, c2


def _coefficients(theta):
    """All scalar coefficients at angle ``theta`` as a dict (for tests and inspection)."""
    t = float(theta)
    x = t * t
    s, co, omc = trig_terms(t)
    out = {}
    for names, vals in (
        ("a b c g e".split(), coef0(t, x, s, co, omc)),
        ("a1 b1 c1 g1 e1".split(), coef1(t, x, s, co, omc)),
        ("a2 b2 c2".split(), coef2(t, x, s, co, omc)),
    ):
        out.update(zip(names, vals))
    return out


# ----------------------------------------------------------------------------------
# Small helpers on Python floats
# ----------------------------------------------------------------------------------
def _vec(a, n):
    """Return the entries of a length-``n`` vector as a list of Python floats."""
    if isinstance(a, np.ndarray):
        if a.ndim != 1:
            a = a.reshape(-1)
        out = a.tolist()
    else:
        out = [float(z) for z in a]
    if len(out) != n:
        raise ValueError(f"expected a vector of length {n}, got {len(out)} entries")
    return out


def _blk(al, k0, k1, k2, x0, x1, x2, y0, y1, y2):
    """Entries (row-major) of  al*I + hat3(k) + x y^T + y x^T."""
    d01 = x0 * y1 + y0 * x1
    d02 = x0 * y2 + y0 * x2
    d12 = x1 * y2 + y1 * x2
    return (
        al + 2.0 * x0 * y0, d01 - k2, d02 + k1,
        d01 + k2, al + 2.0 * x1 * y1, d12 - k0,
        d02 - k1, d12 + k0, al + 2.0 * x2 * y2,
    )


def _six_entries(A, B):
    """Row-major entries of the 6x6 matrix [[A, B], [0, A]] from two row-major 9-tuples."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = A
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = B
    return (a0, a1, a2, b0, b1, b2,
            a3, a4, a5, b3, b4, b5,
            a6, a7, a8, b6, b7, b8,
            0.0, 0.0, 0.0, a0, a1, a2,
            0.0, 0.0, 0.0, a3, a4, a5,
            0.0, 0.0, 0.0, a6, a7, a8)


def _six(A, B):
    """6x6 array [[A, B], [0, A]] from two row-major 9-tuples."""
    return _fromiter(_six_entries(A, B), _F64, 36).reshape(6, 6)


def _j_block(a, b, c, w0, w1, w2):
    """SO(3) left Jacobian J(w) = a I + hat3(b w) + c w w^T."""
    hc = 0.5 * c
    return _blk(a, b * w0, b * w1, b * w2, w0, w1, w2, hc * w0, hc * w1, hc * w2)


def _q_block(b, c, a1, b1, c1, v0, v1, v2, w0, w1, w2):
    """Q(v, w) = D_w J(w)[v] = a1 s I + hat3(b v + b1 s w) + c (v w^T + w v^T) + c1 s w w^T."""
    s = w0 * v0 + w1 * v1 + w2 * v2
    bs = b1 * s
    hs = 0.5 * c1 * s
    return _blk(
        a1 * s,
        b * v0 + bs * w0, b * v1 + bs * w1, b * v2 + bs * w2,
        w0, w1, w2,
        c * v0 + hs * w0, c * v1 + hs * w1, c * v2 + hs * w2,
    )


def _jinv_block(g, e, w0, w1, w2):
    """Inverse SO(3) left Jacobian J(w)^-1 = g I - hat3(w)/2 + e w w^T."""
    he = 0.5 * e
    return _blk(g, -0.5 * w0, -0.5 * w1, -0.5 * w2, w0, w1, w2, he * w0, he * w1, he * w2)


def _qinv_block(g1, e, e1, v0, v1, v2, w0, w1, w2):
    """Qi(v, w) = D_w J^-1(w)[v] = g1 s I - hat3(v)/2 + e (v w^T + w v^T) + e1 s w w^T."""
    s = w0 * v0 + w1 * v1 + w2 * v2
    hs = 0.5 * e1 * s
    return _blk(
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
    m0, m1, m2, m3, m4, m5, m6, m7, m8 = _blk(
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
# SO(3)
# ----------------------------------------------------------------------------------
def hat3(w):
    """Skew matrix hat3(w) with hat3(w) y = w x y."""
    w0, w1, w2 = _vec(w, 3)
    return np.array((0.0, -w2, w1, w2, 0.0, -w0, -w1, w0, 0.0)).reshape(3, 3)


def vee3(W):
    """Inverse of ``hat3``: the vector of the skew part (W - W^T)/2."""
    W = np.asarray(W, dtype=float)
    return 0.5 * np.array((W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]))


def _exp3_list(w0, w1, w2):
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    if t < TAYLOR_THETA_0:
        s = co = omc = 0.0
    else:
        s, co, omc = trig_terms(t)
    a, b, c, _, _ = coef0(t, x, s, co, omc)
    cth = 1.0 - b * x  # = cos(theta), also in the Taylor branch
    return _blk(cth, a * w0, a * w1, a * w2, w0, w1, w2,
                0.5 * b * w0, 0.5 * b * w1, 0.5 * b * w2), a, b, c


def exp3(w):
    """Rodrigues: exp3(w) = cos(theta) I + (sin theta/theta) hat3(w) + b w w^T."""
    w0, w1, w2 = _vec(w, 3)
    R = _exp3_list(w0, w1, w2)[0]
    return np.array(R).reshape(3, 3)


def log3_list(r00, r01, r02, r10, r11, r12, r20, r21, r22):
    """Rotation vector (w0, w1, w2, theta) of a rotation matrix given by its entries.

    theta = atan2(|y|, (tr R - 1)/2) with y = vee3((R - R^T)/2) = sin(theta) n; this is
    accurate to machine precision over [0, pi].  For theta < 2 pi/3 the axis is
    y/|y|; beyond, where |y| = sin(theta) loses relative accuracy, the axis comes from
    the symmetric part (R + R^T)/2 - cos(theta) I = (1 - cos theta) n n^T (largest
    diagonal entry's column), with the sign fixed by n . y >= 0.
    """
    y0 = 0.5 * (r21 - r12)
    y1 = 0.5 * (r02 - r20)
    y2 = 0.5 * (r10 - r01)
    sn = _sqrt(y0 * y0 + y1 * y1 + y2 * y2)
    cs = 0.5 * (r00 + r11 + r22 - 1.0)
    t = _atan2(sn, cs)
    if cs > -0.5:
        if sn == 0.0:
            return 0.0, 0.0, 0.0, 0.0
        f = t / sn
        return f * y0, f * y1, f * y2, t
    # near pi: symmetric part B = (1 - cos) n n^T
    b00 = r00 - cs
    b11 = r11 - cs
    b22 = r22 - cs
    if b00 >= b11 and b00 >= b22:
        n0, n1, n2 = b00, 0.5 * (r01 + r10), 0.5 * (r02 + r20)
    elif b11 >= b22:
        n0, n1, n2 = 0.5 * (r01 + r10), b11, 0.5 * (r12 + r21)
    else:
        n0, n1, n2 = 0.5 * (r02 + r20), 0.5 * (r12 + r21), b22
    nn = _sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    f = t / nn
    if n0 * y0 + n1 * y1 + n2 * y2 < 0.0:
        f = -f
    return f * n0, f * n1, f * n2, t


def log3(R):
    """SO(3) logarithm: rotation vector w with exp3(w) = R and |w| in [0, pi].

    Robust near 0 and near pi (see ``log3_list``).  At exactly pi either of the two
    equivalent vectors +-pi n may be returned.
    """
    R = np.asarray(R, dtype=float)
    w0, w1, w2, _ = log3_list(*R.reshape(-1).tolist())
    return np.array((w0, w1, w2))


def so3_left_jacobian(w):
    """J(w) = sum_k hat3(w)^k/(k+1)! = a I + hat3(b w) + c w w^T.

    Right-trivialised differential of exp3: d/dt exp3(w) = hat3(J(w) w_dot) exp3(w).
    """
    w0, w1, w2 = _vec(w, 3)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    a, b, c, _, _ = coef0(t, x, *(trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)))
    return np.array(_j_block(a, b, c, w0, w1, w2)).reshape(3, 3)


def so3_left_jacobian_inv(w):
    """J(w)^-1 = I - hat3(w)/2 + e hat3(w)^2 = g I - hat3(w)/2 + e w w^T (|w| < 2 pi)."""
    w0, w1, w2 = _vec(w, 3)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    _, _, _, g, e = coef0(t, x, *(trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)))
    return np.array(_jinv_block(g, e, w0, w1, w2)).reshape(3, 3)


# ----------------------------------------------------------------------------------
# SE(3): poses, exp/log
# ----------------------------------------------------------------------------------
def hat6(xi):
    """4x4 matrix hat6([v; w]) = [[hat3(w), v], [0, 0]]."""
    v0, v1, v2, w0, w1, w2 = _vec(xi, 6)
    return np.array((0.0, -w2, w1, v0,
                     w2, 0.0, -w0, v1,
                     -w1, w0, 0.0, v2,
                     0.0, 0.0, 0.0, 0.0)).reshape(4, 4)


def vee6(X):
    """Inverse of ``hat6``: [v; w] from a 4x4 twist matrix (skew part for w)."""
    X = np.asarray(X, dtype=float)
    return np.array((X[0, 3], X[1, 3], X[2, 3],
                     0.5 * (X[2, 1] - X[1, 2]), 0.5 * (X[0, 2] - X[2, 0]),
                     0.5 * (X[1, 0] - X[0, 1])))


def _exp6_list(xi):
    v0, v1, v2, w0, w1, w2 = _vec(xi, 6)
    R, a, b, c = _exp3_list(w0, w1, w2)
    # p = J(w) v = a v + b w x v + c w (w.v)
    cs = c * (w0 * v0 + w1 * v1 + w2 * v2)
    p0 = a * v0 + b * (w1 * v2 - w2 * v1) + cs * w0
    p1 = a * v1 + b * (w2 * v0 - w0 * v2) + cs * w1
    p2 = a * v2 + b * (w0 * v1 - w1 * v0) + cs * w2
    return R, p0, p1, p2


def exp6(xi):
    """SE(3) exponential of xi = [v; w] as a 4x4 matrix [[exp3(w), J(w) v], [0, 1]]."""
    R, p0, p1, p2 = _exp6_list(xi)
    r0, r1, r2, r3, r4, r5, r6, r7, r8 = R
    return _fromiter((r0, r1, r2, p0, r3, r4, r5, p1, r6, r7, r8, p2,
                      0.0, 0.0, 0.0, 1.0), _F64, 16).reshape(4, 4)


def exp6_rp(xi):
    """SE(3) exponential as the pair (R, p)."""
    R, p0, p1, p2 = _exp6_list(xi)
    return np.array(R).reshape(3, 3), np.array((p0, p1, p2))


def check_rotation_domain(lam, margin=PI_MARGIN):
    """Raise ValueError unless the rotation part of ``lam`` = [v; w] has |w| < pi - margin.

    The exponential coordinates of the pose error used by the SE(3) impedance are only
    unique (and the impedance only defined) for |lam_rot| < pi.
    """
    w = _vec(lam, 6)[3:]
    t = _sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    _raise_if_near_pi(t, margin)


def _raise_if_near_pi(t, margin):
    if not t < _PI - margin:  # also catches NaN
        raise ValueError(
            f"orientation error |λ_rot| = {t:.9g} rad ({math.degrees(t):.7g} deg) is not below "
            f"π - {margin:g}: the SE(3) impedance requires |λ_rot| < π "
            f"(the pose-error logarithm is not unique at π)"
        )


def _log6_list(r, p0, p1, p2, check, margin):
    w0, w1, w2, t = log3_list(*r)
    if check:
        _raise_if_near_pi(t, margin)
    x = t * t
    _, _, _, g, e = coef0(t, x, *(trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)))
    # v = J^-1 p = g p - (w x p)/2 + e w (w.p)
    es = e * (w0 * p0 + w1 * p1 + w2 * p2)
    v0 = g * p0 - 0.5 * (w1 * p2 - w2 * p1) + es * w0
    v1 = g * p1 - 0.5 * (w2 * p0 - w0 * p2) + es * w1
    v2 = g * p2 - 0.5 * (w0 * p1 - w1 * p0) + es * w2
    return _fromiter((v0, v1, v2, w0, w1, w2), _F64, 6)


def log6(T, check=False, margin=PI_MARGIN):
    """SE(3) logarithm of a 4x4 pose: lam = [J(w)^-1 p; log3(R)], |w| <= pi.

    With ``check=True`` raise ValueError when |w| >= pi - ``margin`` (use this for the
    impedance pose error, which requires |lam_rot| < pi).
    """
    T = np.asarray(T, dtype=float)
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2) = T[:3].tolist()
    return _log6_list((r00, r01, r02, r10, r11, r12, r20, r21, r22), p0, p1, p2, check, margin)


def log6_rp(R, p, check=False, margin=PI_MARGIN):
    """``log6`` for a pose given as (R, p)."""
    R = np.asarray(R, dtype=float)
    p0, p1, p2 = _vec(p, 3)
    return _log6_list(R.reshape(-1).tolist(), p0, p1, p2, check, margin)


def se3_from_rp(R, p):
    """4x4 homogeneous matrix from (R, p)."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def se3_inverse(T):
    """Inverse pose [[R^T, -R^T p], [0, 1]]."""
    T = np.asarray(T, dtype=float)
    Ti = np.eye(4)
    Rt = T[:3, :3].T
    Ti[:3, :3] = Rt
    Ti[:3, 3] = -(Rt @ T[:3, 3])
    return Ti


def relative_pose(T, Td):
    """T^-1 Td = [[R^T Rd, R^T (pd - p)], [0, 1]] (the impedance pose error T~)."""
    T = np.asarray(T, dtype=float)
    Td = np.asarray(Td, dtype=float)
    out = np.eye(4)
    Rt = T[:3, :3].T
    out[:3, :3] = Rt @ Td[:3, :3]
    out[:3, 3] = Rt @ (Td[:3, 3] - T[:3, 3])
    return out


# ----------------------------------------------------------------------------------
# Adjoints
# ----------------------------------------------------------------------------------
def _adjoint_entries(r, p0, p1, p2):
    """Entries of R and hat3(p) R."""
    r0, r1, r2, r3, r4, r5, r6, r7, r8 = r
    # hat3(p) R: row i = p x (column j of R)
    return r, (
        p1 * r6 - p2 * r3, p1 * r7 - p2 * r4, p1 * r8 - p2 * r5,
        p2 * r0 - p0 * r6, p2 * r1 - p0 * r7, p2 * r2 - p0 * r8,
        p0 * r3 - p1 * r0, p0 * r4 - p1 * r1, p0 * r5 - p1 * r2,
    )


def adjoint_rp(R, p):
    """Ad_T = [[R, hat3(p) R], [0, R]] for T = (R, p); acts on twists [v; w]."""
    R = np.asarray(R, dtype=float)
    p0, p1, p2 = _vec(p, 3)
    return _six(*_adjoint_entries(R.reshape(-1).tolist(), p0, p1, p2))


def adjoint(T):
    """Ad_T = [[R, hat3(p) R], [0, R]] of a 4x4 pose: hat6(Ad_T xi) = T hat6(xi) T^-1."""
    T = np.asarray(T, dtype=float)
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2) = T[:3].tolist()
    return _six(*_adjoint_entries((r00, r01, r02, r10, r11, r12, r20, r21, r22), p0, p1, p2))


def adjoint_inv(T):
    """Ad_T^-1 = Ad_{T^-1} = [[R^T, -R^T hat3(p)], [0, R^T]]."""
    T = np.asarray(T, dtype=float)
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2) = T[:3].tolist()
    # T^-1 = (R^T, -R^T p)
    q0 = -(r00 * p0 + r10 * p1 + r20 * p2)
    q1 = -(r01 * p0 + r11 * p1 + r21 * p2)
    q2 = -(r02 * p0 + r12 * p1 + r22 * p2)
    return _six(*_adjoint_entries((r00, r10, r20, r01, r11, r21, r02, r12, r22), q0, q1, q2))


def coadjoint(T):
    """Ad_T^-T = [[R, 0], [hat3(p) R, R]]: maps a wrench [f; m] in the frame of T's
    child to T's parent frame (F' = Ad_T^-T F, so that F'.(Ad_T V) = F.V)."""
    T = np.asarray(T, dtype=float)
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2) = T[:3].tolist()
    r, (h0, h1, h2, h3, h4, h5, h6, h7, h8) = _adjoint_entries(
        (r00, r01, r02, r10, r11, r12, r20, r21, r22), p0, p1, p2)
    return _fromiter(
        (r00, r01, r02, 0.0, 0.0, 0.0,
         r10, r11, r12, 0.0, 0.0, 0.0,
         r20, r21, r22, 0.0, 0.0, 0.0,
         h0, h1, h2, r00, r01, r02,
         h3, h4, h5, r10, r11, r12,
         h6, h7, h8, r20, r21, r22), _F64, 36
    ).reshape(6, 6)


def ad(xi):
    """ad(xi) = [[hat3(w), hat3(v)], [0, hat3(w)]]: hat6(ad(xi) eta) = [hat6(xi), hat6(eta)]."""
    v0, v1, v2, w0, w1, w2 = _vec(xi, 6)
    return _six((0.0, -w2, w1, w2, 0.0, -w0, -w1, w0, 0.0),
                (0.0, -v2, v1, v2, 0.0, -v0, -v1, v0, 0.0))


# ----------------------------------------------------------------------------------
# dexp and friends
# ----------------------------------------------------------------------------------
def dexp(lam):
    """Right-trivialised differential of exp6 (SE(3) left Jacobian).

    d/dt exp6(lam(t)) = hat6(dexp(lam) lam_dot) exp6(lam);
    dexp(lam) = sum_k ad(lam)^k/(k+1)! = [[J(w), Q(v, w)], [0, J(w)]]  (lam = [v; w]).
    """
    v0, v1, v2, w0, w1, w2 = _vec(lam, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    a, b, c, _, _ = coef0(t, x, *trig)
    a1, b1, c1, _, _ = coef1(t, x, *trig)
    return _six(_j_block(a, b, c, w0, w1, w2),
                _q_block(b, c, a1, b1, c1, v0, v1, v2, w0, w1, w2))


def dexp_inv(lam):
    """Closed-form inverse of ``dexp``: [[J^-1, Qi], [0, J^-1]], Qi = -J^-1 Q J^-1.

    J^-1 = g I - hat3(w)/2 + e w w^T and Qi = D_w J^-1(w)[v] (see module docstring).
    Valid for |w| < 2 pi (the impedance uses |w| < pi).
    """
    v0, v1, v2, w0, w1, w2 = _vec(lam, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    _, _, _, g, e = coef0(t, x, *trig)
    _, _, _, g1, e1 = coef1(t, x, *trig)
    return _six(_jinv_block(g, e, w0, w1, w2),
                _qinv_block(g1, e, e1, v0, v1, v2, w0, w1, w2))


def dexp_dot(lam, lam_dot):
    """Analytic time derivative d/dt dexp(lam(t)) given lam and lam_dot.

    = [[Jd, Qd], [0, Jd]] with Jd = Q(w_dot, w) and Qd = Q(v_dot, w) + D_w^2 J(w)[v, w_dot].
    """
    v0, v1, v2, w0, w1, w2 = _vec(lam, 6)
    u0, u1, u2, z0, z1, z2 = _vec(lam_dot, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    _, b, c, _, _ = coef0(t, x, *trig)
    a1, b1, c1, _, _ = coef1(t, x, *trig)
    a2, b2, c2 = coef2(t, x, *trig)
    return _six(_jdot_block(b, c, a1, b1, c1, w0, w1, w2, z0, z1, z2),
                _qdot_block(b, c, a1, b1, c1, a2, b2, c2,
                            v0, v1, v2, w0, w1, w2, u0, u1, u2, z0, z1, z2))


def dexp_all(lam, lam_dot):
    """(dexp(lam), dexp_inv(lam), dexp_dot(lam, lam_dot)) sharing trig and coefficients.

    This is what the SE(3) impedance controller needs every step.  Returns three 6x6
    arrays (non-overlapping views of one (3, 6, 6) buffer, freshly allocated per call).
    """
    v0, v1, v2, w0, w1, w2 = _vec(lam, 6)
    u0, u1, u2, z0, z1, z2 = _vec(lam_dot, 6)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    trig = trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
    a, b, c, g, e = coef0(t, x, *trig)
    a1, b1, c1, g1, e1 = coef1(t, x, *trig)
    a2, b2, c2 = coef2(t, x, *trig)
    out = _fromiter(
        _six_entries(_j_block(a, b, c, w0, w1, w2),
                     _q_block(b, c, a1, b1, c1, v0, v1, v2, w0, w1, w2))
        + _six_entries(_jinv_block(g, e, w0, w1, w2),
                       _qinv_block(g1, e, e1, v0, v1, v2, w0, w1, w2))
        + _six_entries(_jdot_block(b, c, a1, b1, c1, w0, w1, w2, z0, z1, z2),
                       _qdot_block(b, c, a1, b1, c1, a2, b2, c2,
                                   v0, v1, v2, w0, w1, w2, u0, u1, u2, z0, z1, z2)),
        _F64, 108,
    ).reshape(3, 6, 6)
    return out[0], out[1], out[2]


def _benchmark(number=20000):  # pragma: no cover - manual tool
    """Print per-call timings (microseconds) of the hot-path functions."""
    import timeit

    rng = np.random.default_rng(0)
    out = {}
    for label, scale in (("small angle (Taylor)", 0.05), ("large angle (closed form)", 1.5)):
        lam = rng.standard_normal(6)
        lam[3:] *= scale / np.linalg.norm(lam[3:])
        lam_dot = rng.standard_normal(6)
        T = exp6(lam)
        cases = {
            "exp6": lambda: exp6(lam),
            "log6": lambda: log6(T),
            "log6(check)": lambda: log6(T, check=True),
            "adjoint": lambda: adjoint(T),
            "ad": lambda: ad(lam),
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
