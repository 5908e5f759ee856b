"""SE(3): hat/vee, exp/log, inverse and relative pose, adjoints and ad.

Twists and wrenches are ``[linear; angular]``; poses 4×4 homogeneous matrices (the
``*_rp`` variants take or return ``(R, p)``). ``Ad_T = [[R, hat3(p) R], [0, R]]``.
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.control.lie.series import (
    PI_MARGIN,
    TAYLOR_THETA_0,
    block6,
    coef0,
    floats,
    trig_terms,
)
from compliant_docking.control.lie.so3 import exp3_entries, log3_list

_sqrt = math.sqrt
_PI = math.pi
_fromiter = np.fromiter
_F64 = np.float64


def hat6(xi):
    """4x4 matrix hat6([v; w]) = [[hat3(w), v], [0, 0]]."""
    v0, v1, v2, w0, w1, w2 = floats(xi, 6)
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
    v0, v1, v2, w0, w1, w2 = floats(xi, 6)
    R, a, b, c = exp3_entries(w0, w1, w2)
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
    w = floats(lam, 6)[3:]
    t = _sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    raise_if_near_pi(t, margin)


def raise_if_near_pi(t, margin):
    if not t < _PI - margin:  # also catches NaN
        raise ValueError(
            f"orientation error |λ_rot| = {t:.9g} rad ({math.degrees(t):.7g} deg) is not below "
            f"π - {margin:g}: the SE(3) impedance requires |λ_rot| < π "
            f"(the pose-error logarithm is not unique at π)"
        )


def _log6_list(r, p0, p1, p2, check, margin):
    w0, w1, w2, t = log3_list(*r)
    if check:
        raise_if_near_pi(t, margin)
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
    p0, p1, p2 = floats(p, 3)
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
    p0, p1, p2 = floats(p, 3)
    return block6(*_adjoint_entries(R.reshape(-1).tolist(), p0, p1, p2))


def adjoint(T):
    """Ad_T = [[R, hat3(p) R], [0, R]] of a 4x4 pose: hat6(Ad_T xi) = T hat6(xi) T^-1."""
    T = np.asarray(T, dtype=float)
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2) = T[:3].tolist()
    return block6(*_adjoint_entries((r00, r01, r02, r10, r11, r12, r20, r21, r22), p0, p1, p2))


def adjoint_inv(T):
    """Ad_T^-1 = Ad_{T^-1} = [[R^T, -R^T hat3(p)], [0, R^T]]."""
    T = np.asarray(T, dtype=float)
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2) = T[:3].tolist()
    # T^-1 = (R^T, -R^T p)
    q0 = -(r00 * p0 + r10 * p1 + r20 * p2)
    q1 = -(r01 * p0 + r11 * p1 + r21 * p2)
    q2 = -(r02 * p0 + r12 * p1 + r22 * p2)
    return block6(*_adjoint_entries((r00, r10, r20, r01, r11, r21, r02, r12, r22), q0, q1, q2))


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
    v0, v1, v2, w0, w1, w2 = floats(xi, 6)
    return block6((0.0, -w2, w1, w2, 0.0, -w0, -w1, w0, 0.0),
                (0.0, -v2, v1, v2, 0.0, -v0, -v1, v0, 0.0))


# ----------------------------------------------------------------------------------
