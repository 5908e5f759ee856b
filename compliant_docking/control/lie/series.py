"""Scalar kernels of the SO(3)/SE(3) closed forms: the coefficient functions and their
Taylor switches, and small block builders on Python floats.

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
The log3 kernel returns a rotation vector of norm in [0, pi].  The SE(3) impedance is
only defined for |lam_rot| < pi (the logarithm is not unique at pi);
``check_rotation_domain`` raises a ValueError there.

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


def inv_coefficients(t):
    """(g, e, g1, e1) at theta = t: the coefficients of J(w)^-1 and their order-1
    derivatives, as :func:`coef0` and :func:`coef1` give them (the same expressions, bit
    for bit; tests/control/test_lie.py), in one call: the SE(3) impedance's hot path needs
    only these four, and the calls and the unused a, b, c (and a1, b1, c1) cost more than
    its remaining arithmetic."""
    x = t * t
    if t < TAYLOR_THETA_0:  # both series
        e = 1 / 12 + x * (1 / 720 + x * (1 / 30240 + x * (1 / 1209600 + x * (1 / 47900160))))
        g = 1.0 - e * x
    else:
        h = _sin(0.5 * t)
        s, omc = _sin(t), 2.0 * h * h
        g = t * s / (2.0 * omc)
        e = (1.0 - g) / x
        if t >= TAYLOR_THETA_1:  # both closed forms
            g1 = (s - t) / (2.0 * t * omc)
            return g, e, g1, -(g1 + 2.0 * e) / x  # e: coef1's (1 − t s/(2 omc))/x, same bits
    g1 = -1 / 6 + x * (-1 / 180 + x * (-1 / 5040 + x * (-1 / 151200 + x * (-1 / 4790016 + x * (-691 / 108972864000 + x * (-1 / 5337446400 + x * (-3617 / 666913927680000 + x * (-43867 / 283838567620608000))))))))  # noqa: E501
    e1 = 1 / 360 + x * (1 / 7560 + x * (1 / 201600 + x * (1 / 5987520 + x * (691 / 130767436800 + x * (1 / 6227020800 + x * (3617 / 762187345920000 + x * (43867 / 319318388573184000 + x * (174611 / 44603203483238400000))))))))  # noqa: E501
    return g, e, g1, e1


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


def coefficients(theta):
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
def floats(a, n):
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


def block3(al, k0, k1, k2, x0, x1, x2, y0, y1, y2):
    """Entries (row-major) of  al*I + hat3(k) + x y^T + y x^T."""
    d01 = x0 * y1 + y0 * x1
    d02 = x0 * y2 + y0 * x2
    d12 = x1 * y2 + y1 * x2
    return (
        al + 2.0 * x0 * y0, d01 - k2, d02 + k1,
        d01 + k2, al + 2.0 * x1 * y1, d12 - k0,
        d02 - k1, d12 + k0, al + 2.0 * x2 * y2,
    )


def block6_entries(A, B):
    """Row-major entries of the 6x6 matrix [[A, B], [0, A]] from two row-major 9-tuples."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = A
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = B
    return (a0, a1, a2, b0, b1, b2,
            a3, a4, a5, b3, b4, b5,
            a6, a7, a8, b6, b7, b8,
            0.0, 0.0, 0.0, a0, a1, a2,
            0.0, 0.0, 0.0, a3, a4, a5,
            0.0, 0.0, 0.0, a6, a7, a8)


def block6(A, B):
    """6x6 array [[A, B], [0, A]] from two row-major 9-tuples."""
    return _fromiter(block6_entries(A, B), _F64, 36).reshape(6, 6)
