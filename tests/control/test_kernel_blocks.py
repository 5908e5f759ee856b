"""The compiled blocks shared by the laws (control/kernel_blocks.py): the friction
feed-forward (the one implementation, FrictionFeedForward calls it for every mode) against
its closed form in numpy, and the Cholesky factor/solve against LAPACK dpotrf/dposv, whose
compiled form it is."""

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


def _closed_form(mode, tau, v, h, f, b):
    """The feed-forward of docs/controllers/friction.md in numpy (FrictionFeedForward's doc)."""
    scale = 2.0 / np.where(f > 0.0, f, 1.0)
    if mode is FrictionComp.velocity:
        y = np.tanh(v / 0.01)
    elif mode is FrictionComp.torque:
        y = np.tanh(tau * scale)
    else:
        y = np.tanh((tau - h) * scale)
    if mode is FrictionComp.yielding:  # scaled down on a joint moving against it
        y = np.where(v * y < 0.0, y * (1.0 - np.minimum(np.abs(v) / 0.02, 1.0)), y)
    return f * y + b * v


@pytest.mark.parametrize("mode", list(FrictionComp))
def test_friction_feed_forward_is_its_closed_form(mode):
    """Every mode of FrictionFeedForward (the compiled block) against the numpy closed form.
    The only difference is tanh's: numpy's SIMD tanh and libm's (numba's math.tanh) differ
    by up to 3 ulp on about a third of the arguments (measured on 1.2e7 draws), so the
    torques agree to a few ulp of f, not bit for bit; any wrong term is ≫ that."""
    rng = np.random.default_rng(7)
    n = 7
    f = rng.uniform(0.0, 2.0, n)
    f[2] = 0.0  # a joint without friction: scale 1 in the torque modes
    b = rng.uniform(0.0, 1.0, n)
    ff = FrictionFeedForward(f, b, mode)
    eps = np.finfo(float).eps
    for _ in range(50):
        tau, v, h = rng.normal(scale=5.0, size=(3, n))
        v *= 0.01  # speeds around the velocity mode's 0.01 rad/s scale, where tanh bends
        expected = _closed_form(mode, tau, v, h, f, b)
        np.testing.assert_allclose(ff(tau, v, h), expected, rtol=0, atol=8 * eps * (f.max() + 1.0))
        out = np.empty(n)  # the kernels' call: the same block, the same numbers
        friction_feed_forward(tau, v, h, ff.f, ff.b, ff.scale, friction_code(mode), out)
        assert np.array_equal(out, ff(tau, v, h))


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
