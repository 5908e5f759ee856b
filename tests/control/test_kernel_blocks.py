"""The compiled blocks shared by the step kernels (control/kernel_blocks.py) against the
numpy/LAPACK pieces they twin: the friction feed-forward (impedance keeps the numpy one) and
the Cholesky factor/solve (LAPACK dpotrf/dposv)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import lapack

from compliant_docking.config import FrictionComp
from compliant_docking.control.base import FrictionFeedForward
from compliant_docking.control.kernel_blocks import (
    cholesky,
    cholesky_solve,
    friction_code,
    friction_feed_forward,
)


@pytest.mark.parametrize("mode", list(FrictionComp))
def test_friction_twin_matches_the_numpy_feed_forward(mode):
    """Same formula, so the same values to 1e-12 relative (libm's tanh against numpy's)."""
    rng = np.random.default_rng(7)
    n = 7
    f = rng.uniform(0.0, 2.0, n)
    f[2] = 0.0  # a joint without friction: scale 1 in the torque modes
    b = rng.uniform(0.0, 1.0, n)
    ff = FrictionFeedForward(f, b, mode)
    for _ in range(50):
        tau, v, h = rng.normal(scale=5.0, size=(3, n))
        v *= 0.01  # speeds around the velocity mode's 0.01 rad/s scale, where tanh bends
        out = np.empty(n)
        friction_feed_forward(tau, v, h, ff.f, ff.b, ff._scale, friction_code(mode), out)
        np.testing.assert_allclose(out, ff(tau.copy(), v, h), rtol=1e-12, atol=1e-15)


def test_cholesky_twin_matches_lapack():
    rng = np.random.default_rng(8)
    L = np.zeros((6, 6))
    for _ in range(50):
        B = rng.standard_normal((6, 6))
        A = B @ B.T + 1e-3 * np.eye(6)
        assert cholesky(A, L)
        np.testing.assert_allclose(np.tril(L), np.linalg.cholesky(A), rtol=0, atol=1e-12 * np.abs(A).max())
        x = rng.standard_normal(6)
        _, expected, info = lapack.dposv(A, x)
        cholesky_solve(L, x)
        assert info == 0
        np.testing.assert_allclose(x, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


@pytest.mark.parametrize(
    "bad",
    [
        np.diag([1.0, 1.0, -1.0, 1.0, 1.0, 1.0]),
        np.diag([1.0, 0.0, 1, 1, 1, 1]),
        np.diag([1.0, 2.0, -1e-12, 1, 1, 1]),
    ],
)
def test_cholesky_refuses_what_lapack_refuses(bad):
    assert lapack.dpotrf(bad)[1] != 0
    assert not cholesky(bad, np.zeros((6, 6)))


def test_cholesky_refuses_a_nan_pivot():
    """OpenBLAS's dposv lets a NaN pivot through; the kernels refuse it and hand the step to
    the numpy path (TaskInertia.solve, the lstsq fallback), so the outcome is LAPACK's."""
    assert not cholesky(np.diag([1.0, 1, 1, np.nan, 1, 1]), np.zeros((6, 6)))
    assert not cholesky(np.full((6, 6), np.nan), np.zeros((6, 6)))
