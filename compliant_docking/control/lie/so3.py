"""SO(3): the logarithm kernel of the SE(3) impedance (robust near 0 and π) and the left
Jacobian with its inverse (the SO(3) blocks of dexp).

J(w) = a I + hat3(b w) + c w wᵀ and J(w)⁻¹ = g I − hat3(w)/2 + e w wᵀ with the coefficient
functions of :mod:`compliant_docking.control.lie.series`. The general helpers (hat/vee,
exp/log as matrices) are Pinocchio's: ``pin.skew``, ``pin.unSkew``, ``pin.exp3``, ``pin.log3``.
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.control.lie.series import (
    TAYLOR_THETA_0,
    block3,
    coef0,
    floats,
    trig_terms,
)

_sqrt = math.sqrt
_atan2 = math.atan2


def j_block(a, b, c, w0, w1, w2):
    """SO(3) left Jacobian J(w) = a I + hat3(b w) + c w w^T."""
    hc = 0.5 * c
    return block3(a, b * w0, b * w1, b * w2, w0, w1, w2, hc * w0, hc * w1, hc * w2)



def jinv_block(g, e, w0, w1, w2):
    """Inverse SO(3) left Jacobian J(w)^-1 = g I - hat3(w)/2 + e w w^T."""
    he = 0.5 * e
    return block3(g, -0.5 * w0, -0.5 * w1, -0.5 * w2, w0, w1, w2, he * w0, he * w1, he * w2)



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


def so3_left_jacobian(w):
    """J(w) = sum_k hat3(w)^k/(k+1)! = a I + hat3(b w) + c w w^T.

    Right-trivialised differential of exp3: d/dt exp3(w) = hat3(J(w) w_dot) exp3(w).
    """
    w0, w1, w2 = floats(w, 3)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    a, b, c, _, _ = coef0(t, x, *(trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)))
    return np.array(j_block(a, b, c, w0, w1, w2)).reshape(3, 3)


def so3_left_jacobian_inv(w):
    """J(w)^-1 = I - hat3(w)/2 + e hat3(w)^2 = g I - hat3(w)/2 + e w w^T (|w| < 2 pi)."""
    w0, w1, w2 = floats(w, 3)
    x = w0 * w0 + w1 * w1 + w2 * w2
    t = _sqrt(x)
    _, _, _, g, e = coef0(t, x, *(trig_terms(t) if t >= TAYLOR_THETA_0 else (0.0, 0.0, 0.0)))
    return np.array(jinv_block(g, e, w0, w1, w2)).reshape(3, 3)


# ----------------------------------------------------------------------------------
