"""Compiled building blocks shared by the laws: a Cholesky factorization and solve that
report failure as LAPACK does, and the friction feed-forward.

The friction feed-forward (:func:`friction_feed_forward`) is the one implementation of that
law: ``control.base.FrictionFeedForward`` calls it for every mode (the numpy laws), the step
kernels call it in their loop; tests/control/test_kernel_blocks.py checks it against its
closed form in numpy.

:func:`cholesky` and :func:`cholesky_solve` are not a second implementation of one of our
laws: they are LAPACK's dpotrf/dpotrs (dposv) written out so that a kernel can call them
without leaving compiled code. ``control.base.TaskInertia`` (the numpy laws' Λ solve) calls
LAPACK's dposv itself, with the condition estimate dpocon that has no compiled counterpart;
calling these blocks there instead would not be bit-identical (OpenBLAS sums in another
order: the factor and the solution differ in the last bits on 1998 of 2000 random 6×6
systems), so the numpy laws keep LAPACK, and
tests/control/test_kernel_blocks.py checks the compiled forms against it.
"""

from __future__ import annotations

import math

from compliant_docking.config import FrictionComp
from compliant_docking.control.jit import kernel

#: friction modes as the kernels number them
FRICTION_CODES = {
    FrictionComp.torque: 0,
    FrictionComp.velocity: 1,
    FrictionComp.torque_unbiased: 2,
    FrictionComp.yielding: 3,
}
#: yielding: joint speed against the feed-forward from which it is off [rad/s]
YIELD_SPEED = 0.02


def friction_code(mode: FrictionComp | str) -> int:
    """The kernels' number for a ``friction_comp`` mode."""
    return FRICTION_CODES[FrictionComp(mode)]


@kernel
def cholesky(A, L):
    """Lower Cholesky factor of the symmetric A (its lower triangle is read) into L's lower
    triangle; False (as LAPACK dpotrf's info ≠ 0) when a pivot is not positive (or NaN).
    LAPACK's dpotrf in compiled form (module doc), not a law of ours."""
    m = A.shape[0]
    for j in range(m):
        s = A[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        L[j, j] = d
        for i in range(j + 1, m):
            t = A[i, j]
            for k in range(j):
                t -= L[i, k] * L[j, k]
            L[i, j] = t / d
    return True


@kernel
def cholesky_solve(L, x):
    """x ← (L Lᵀ)⁻¹ x in place, L from :func:`cholesky` (LAPACK's dpotrs in compiled form)."""
    m = L.shape[0]
    for i in range(m):
        t = x[i]
        for k in range(i):
            t -= L[i, k] * x[k]
        x[i] = t / L[i, i]
    for i in range(m - 1, -1, -1):
        t = x[i]
        for k in range(i + 1, m):
            t -= L[k, i] * x[k]
        x[i] = t / L[i, i]


@kernel
def friction_feed_forward(tau_pre, v, h, f, b, scale, mode, out):
    """The friction feed-forward (``control.base.FrictionFeedForward``, which calls it for
    every mode; mode: :data:`FRICTION_CODES`): out = f·tanh(x) + b·v with x = 2τ_pre/f (torque), v/0.01 (velocity) or 2(τ_pre − h)/f
    (torque_unbiased); ``scale`` holds the factor of each mode. yielding: torque_unbiased's
    y = tanh(2(τ_pre − h)/f) times 1 − min(|v|/0.02, 1) where v·y < 0: out = f·y' + b·v."""
    for i in range(out.shape[0]):
        if mode == 1:
            x = v[i] * scale[i]
        elif mode == 2 or mode == 3:
            x = (tau_pre[i] - h[i]) * scale[i]
        else:
            x = tau_pre[i] * scale[i]
        y = math.tanh(x)
        if mode == 3 and v[i] * y < 0.0:  # the joint moves against it: yield
            y *= 1.0 - min(abs(v[i]) / YIELD_SPEED, 1.0)
        out[i] = y * f[i] + b[i] * v[i]
