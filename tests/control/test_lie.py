"""Tests of compliant_docking.control.lie: the dexp family, the log3 kernel and the scalar
coefficient kernels, with Pinocchio's exp6/log6/adjoints (which replaced lie's general
helpers) and finite differences as references.

Tolerances (stated once, used throughout):
* round trips and identities that involve no differentiation: 1e-13 relative
  (the implementation reaches ~1e-15; the slack covers angles near pi);
* central finite differences with step H = 1e-6: the truncation error is ~H^2 = 1e-12
  and the round-off ~eps/H = 2e-10, so FD_TOL = 1e-7 (relative to the size of the
  quantity, floor 1) leaves a margin of ~100 while any wrong term (relative error of
  order 1e-3 or more for the angles tested) fails;
* Taylor/closed-form switch continuity: 1e-10 relative (achieved ~1e-11);
* pinocchio comparisons: 1e-12 absolute (1e-10 for log6 near pi where pinocchio
  itself is less accurate).
"""

from __future__ import annotations

import math
import sys
import zlib
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

try:
    from compliant_docking.control import lie
except ImportError:  # running without the package installed: use the checkout
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from compliant_docking.control import lie

import pinocchio as pin

H = 1e-6
FD_TOL = 1e-7
RT_TOL = 1e-13
SWITCH_TOL = 1e-10

# Rotation angles covering every branch: exact zero, the Taylor regions of the three
# coefficient orders, each threshold, the closed forms, the log3 symmetric branch
# (beyond 2 pi/3) and the neighbourhood of pi.
ANGLES = [
    0.0,
    1e-12,
    1e-9,
    1e-6,
    1e-3,
    0.05,
    lie.TAYLOR_THETA_0,
    0.3,
    lie.TAYLOR_THETA_1,
    0.8,
    lie.TAYLOR_THETA_2,
    1.7,
    2.2,
    2.8,
    math.pi - 1e-3,
    math.pi - 1e-5,
    math.pi - 1e-6,
    math.pi - 1e-9,
]


def rng_for(*keys):
    """Deterministic generator per test case (hash() of str is salted per process)."""
    return np.random.default_rng(zlib.crc32(repr(("lie", *keys)).encode()))


def unit(rng, n=3):
    u = rng.standard_normal(n)
    return u / np.linalg.norm(u)


def random_lam(rng, theta, vscale=1.0):
    """A twist [v; w] with |w| = theta and a random linear part."""
    return np.concatenate([vscale * rng.standard_normal(3), theta * unit(rng)])


def expm_ref(A):
    """Reference matrix exponential: scaling and squaring of a 30-term Taylor series."""
    nrm = np.abs(A).sum(axis=1).max()
    k = max(0, int(math.ceil(math.log2(nrm))) + 1) if nrm > 0 else 0
    B = A / 2.0**k
    out = np.eye(A.shape[0])
    term = np.eye(A.shape[0])
    for i in range(1, 30):
        term = term @ B / i
        out = out + term
    for _ in range(k):
        out = out @ out
    return out


def dexp_series(lam, terms=60):
    """Definition: dexp = sum_k ad(lam)^k / (k+1)!."""
    A = pin.Motion(lam).action  # ad(lam)
    out = np.zeros((6, 6))
    term = np.eye(6)
    for k in range(terms):
        out += term / math.factorial(k + 1)
        term = term @ A
    return out


def hat6(xi):
    """Test-local hat (independent of the module)."""
    v, w = xi[:3], xi[3:]
    X = np.zeros((4, 4))
    X[:3, :3] = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
    X[:3, 3] = v
    return X


def vee6(X):
    return np.array([X[0, 3], X[1, 3], X[2, 3], X[2, 1], X[0, 2], X[1, 0]])


def exp6(xi):
    return pin.exp6(np.asarray(xi, dtype=float)).homogeneous


def log6(T):
    return pin.log6(np.asarray(T, dtype=float)).vector


def log3(R):
    """The controller's log3 kernel on a 3×3 matrix."""
    return np.array(lie.log3_list(*np.asarray(R, dtype=float).reshape(-1).tolist())[:3])


def rel_err(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / max(1.0, np.abs(np.asarray(b)).max())


# ----------------------------------------------------------------------------------
# Scalar coefficients: exact reference series and Taylor-switch continuity
# ----------------------------------------------------------------------------------
NTERMS = 30


def _series_defs():
    """Exact power series in x = theta^2 of every coefficient, from sin/cos only."""
    fact = math.factorial
    sin_over = [Fraction((-1) ** k, fact(2 * k + 1)) for k in range(NTERMS + 2)]  # sin t / t
    omc_over = [Fraction((-1) ** k, fact(2 * k + 2)) for k in range(NTERMS + 2)]  # (1-cos t)/t^2
    ser = {
        "a": sin_over[:NTERMS],
        "b": omc_over[:NTERMS],
        "c": [Fraction((-1) ** k, fact(2 * k + 3)) for k in range(NTERMS)],
    }
    # g = t sin t / (2 (1 - cos t)) = (sin t / t) / (2 (1 - cos t)/t^2): series division.
    num, den = sin_over, [2 * z for z in omc_over]
    g = []
    for k in range(NTERMS + 1):
        g.append((num[k] - sum(g[j] * den[k - j] for j in range(k))) / den[0])
    ser["g"] = g[:NTERMS]
    ser["e"] = [-z for z in g[1 : NTERMS + 1]]  # e = (1 - g)/x

    def d(s):  # f1 = f'(t)/t = 2 df/dx
        return [2 * (k + 1) * s[k + 1] for k in range(len(s) - 1)]

    for n in "abcge":
        ser[n + "1"] = d(ser[n])
    for n in "abc":
        ser[n + "2"] = d(ser[n + "1"])
    return ser


SERIES = _series_defs()
GROUPS = {
    lie.TAYLOR_THETA_0: ["a", "b", "c", "g", "e"],
    lie.TAYLOR_THETA_1: ["a1", "b1", "c1", "g1", "e1"],
    lie.TAYLOR_THETA_2: ["a2", "b2", "c2"],
}


def series_value(name, theta):
    x = Fraction(theta) ** 2
    return float(sum(c * x**k for k, c in enumerate(SERIES[name])))


@pytest.mark.parametrize(
    "theta", [0.0, 1e-8, 1e-4, 0.01, 0.07, 0.099, 0.1, 0.2, 0.45, 0.5, 0.7, 0.99, 1.0, 1.5, 2.5, 3.1]
)
def test_coefficients_match_exact_series(theta):
    """Both branches against exact rational series (truncated far beyond double precision)."""
    got = lie.coefficients(theta)
    for name in SERIES:
        ref = series_value(name, theta)
        # closed forms lose ~1e-12 relative just above their threshold (cancellation)
        assert abs(got[name] - ref) <= 2e-11 * abs(ref), (name, theta, got[name], ref)


@pytest.mark.parametrize("X", [0.5, 30.0, 1e3])
def test_taylor_polynomials_have_the_exact_coefficients(X):
    """Evaluate the Taylor branches (t = 0 forces them) at a large x = X, where the
    highest-order terms dominate, against the exact truncated series."""

    def trunc(name, k):
        return float(sum(c * Fraction(X) ** i for i, c in enumerate(SERIES[name][:k])))

    a, b, c, g, e = lie.coef0(0.0, X, 0.0, 0.0, 0.0)
    got = dict(a=a, b=b, c=c, e=e)
    got.update(zip(["a1", "b1", "c1", "g1", "e1"], lie.coef1(0.0, X, 0.0, 0.0, 0.0)))
    got.update(zip(["a2", "b2", "c2"], lie.coef2(0.0, X, 0.0, 0.0, 0.0)))
    for name, val in got.items():
        ref = trunc(name, 5 if name in "abce" else 9)
        assert abs(val - ref) <= 1e-13 * max(abs(ref), 1.0), name
    assert g == 1.0 - e * X  # g = 1 - e x in the Taylor branch


@pytest.mark.parametrize("threshold", sorted(GROUPS))
def test_taylor_switch_continuity(threshold):
    """One ulp below the threshold (Taylor) vs at the threshold (closed form)."""
    below = lie.coefficients(np.nextafter(threshold, 0.0))
    at = lie.coefficients(threshold)
    for name in GROUPS[threshold]:
        diff = abs(below[name] - at[name])
        assert diff <= SWITCH_TOL * abs(at[name]), (name, below[name], at[name])


@pytest.mark.parametrize("threshold", sorted(GROUPS))
def test_matrix_continuity_across_switch(threshold):
    rng = rng_for("switch", threshold)
    lam, lam_dot = random_lam(rng, 1.0), rng.standard_normal(6)
    w = lam[3:] / np.linalg.norm(lam[3:])
    lam_lo, lam_hi = lam.copy(), lam.copy()
    lam_lo[3:] = np.nextafter(threshold, 0.0) * w
    lam_hi[3:] = threshold * w
    for lo, hi in zip(lie.dexp_all(lam_lo, lam_dot), lie.dexp_all(lam_hi, lam_dot)):
        assert rel_err(lo, hi) <= SWITCH_TOL


# ----------------------------------------------------------------------------------
# SO(3)
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("theta", ANGLES)
def test_log3_kernel_inverts_exp3(theta):
    """The kernel the controller calls, on rotations made by Pinocchio's exp3 (checked
    against a Taylor expm): the rotation vector back to 1e-13 relative, |w| ≤ π."""
    rng = rng_for("so3", theta)
    for _ in range(20):
        w = theta * unit(rng)
        R = pin.exp3(w)
        np.testing.assert_allclose(R, expm_ref(pin.skew(w)), rtol=0, atol=1e-14)
        w0, w1, w2, t = lie.log3_list(*R.reshape(-1).tolist())
        w2_ = np.array([w0, w1, w2])
        assert t == pytest.approx(np.linalg.norm(w2_), rel=1e-15, abs=0.0)
        assert np.linalg.norm(w2_) <= math.pi + 1e-15
        assert np.linalg.norm(w2_ - w) <= RT_TOL * max(theta, 1e-300) or theta == 0.0
        if theta == 0.0:
            assert np.all(w2_ == 0.0)


def test_log3_kernel_of_random_rotations_agrees_with_pinocchio():
    rng = rng_for("randrot")
    for _ in range(200):
        q = unit(rng, 4)
        R = pin.Quaternion(q[0], q[1], q[2], q[3]).toRotationMatrix()
        w = log3(R)
        assert np.linalg.norm(w) <= math.pi + 1e-15
        np.testing.assert_allclose(pin.exp3(w), R, rtol=0, atol=1e-14)
        # the same vector where log3 is well conditioned (its derivative grows as
        # 1/sin θ: at 3.13 rad the two round-offs differ by 2e-12)
        if np.linalg.norm(w) < 2.5:
            np.testing.assert_allclose(w, pin.log3(R), rtol=0, atol=1e-13)


def test_log3_kernel_at_exactly_pi():
    rng = rng_for("pi")
    cases = [np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])]
    for _ in range(20):
        n = unit(rng)
        cases.append(2.0 * np.outer(n, n) - np.eye(3))  # rotation by exactly pi about n
    for R in cases:
        w = log3(R)
        assert abs(np.linalg.norm(w) - math.pi) <= 4e-15
        np.testing.assert_allclose(pin.exp3(w), R, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(log3(np.diag([1.0, -1.0, -1.0])), [math.pi, 0.0, 0.0])


@pytest.mark.parametrize("theta", [1e-9, 1e-3, 0.3, 1.0, 2.0, 3.0, math.pi - 1e-6])
def test_so3_left_jacobian(theta):
    rng = rng_for("Jl", theta)
    w, dw = theta * unit(rng), rng.standard_normal(3)
    J = lie.so3_left_jacobian(w)
    # definition: d/dt exp3(w + t dw) exp3(w)^T = hat3(J dw)
    dR = (pin.exp3(w + H * dw) - pin.exp3(w - H * dw)) / (2 * H)
    np.testing.assert_allclose(pin.unSkew(dR @ pin.exp3(w).T), J @ dw, rtol=0, atol=FD_TOL)
    np.testing.assert_allclose(lie.so3_left_jacobian_inv(w) @ J, np.eye(3), rtol=0, atol=1e-12)


def test_dexp_takes_any_vector_of_six():
    xi = rng_for("inputs").standard_normal(6)
    np.testing.assert_array_equal(lie.dexp(list(xi)), lie.dexp(xi))
    np.testing.assert_array_equal(lie.dexp(xi.reshape(6, 1)), lie.dexp(xi))
    with pytest.raises(ValueError):
        lie.dexp(np.zeros(5))


# ----------------------------------------------------------------------------------
# dexp, dexp_inv, dexp_dot
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("theta", ANGLES)
def test_dexp_finite_difference(theta):
    """d/dt Exp(lam + t delta) Exp(lam)^-1 at t = 0 equals hat6(dexp(lam) delta)."""
    rng = rng_for("dexp", theta)
    lam = random_lam(rng, theta)
    D = lie.dexp(lam)
    Einv = np.linalg.inv(exp6(lam))
    fd = np.empty((6, 6))
    for i in range(6):
        delta = np.zeros(6)
        delta[i] = 1.0
        dT = (exp6(lam + H * delta) - exp6(lam - H * delta)) / (2 * H)
        fd[:, i] = vee6(dT @ Einv)
    assert rel_err(D, fd) <= FD_TOL
    # and the definition as a series in ad(lam)
    assert rel_err(D, dexp_series(lam)) <= 1e-13


@pytest.mark.parametrize("theta", ANGLES)
def test_dexp_inv(theta):
    rng = rng_for("dexp_inv", theta)
    for _ in range(5):
        lam = random_lam(rng, theta, vscale=3.0)
        D, Di = lie.dexp(lam), lie.dexp_inv(lam)
        np.testing.assert_allclose(Di @ D, np.eye(6), rtol=0, atol=1e-12)
        np.testing.assert_allclose(D @ Di, np.eye(6), rtol=0, atol=1e-12)
        assert rel_err(Di, np.linalg.inv(D)) <= 1e-12


@pytest.mark.parametrize("theta", [0.05, 0.3, 1.0, 2.0, 3.0])
def test_dexp_matches_pinocchio_jacobians(theta):
    """dexp(lam) = J_r(-lam) = pin.Jexp6(-lam); dexp_inv(lam) = pin.Jlog6(exp6(-lam)).

    (Pinocchio's own Jexp6/Jlog6 lose up to ~1e-7 near |w| ~ 1e-3, so smaller angles
    are checked against the series definition instead.)
    """
    rng = rng_for("pinJ", theta)
    lam = random_lam(rng, theta)
    np.testing.assert_allclose(lie.dexp(lam), pin.Jexp6(-lam), rtol=0, atol=1e-11)
    np.testing.assert_allclose(lie.dexp_inv(lam), pin.Jlog6(pin.exp6(-lam)), rtol=0, atol=1e-11)


@pytest.mark.parametrize("theta", ANGLES)
@pytest.mark.parametrize("t0", [0.0, 0.2])
def test_dexp_dot_finite_difference(theta, t0):
    """lam(t) = lam0 + t lam_dot + t^2 c; compare dexp_dot with a central FD of dexp."""
    rng = rng_for("dexp_dot", theta, t0)
    # lam(t0) has rotation angle theta; dexp is analytic for all angles < 2 pi, so the
    # curve may cross pi near the end of the range without harm.
    lam_t, lam_dot, curv = random_lam(rng, theta), rng.standard_normal(6), rng.standard_normal(6)
    lam_dot_t = lam_dot + 2.0 * t0 * curv
    lam0 = lam_t - t0 * lam_dot - t0 * t0 * curv

    def lam_at(t):
        return lam0 + t * lam_dot + t * t * curv

    fd = (lie.dexp(lam_at(t0 + H)) - lie.dexp(lam_at(t0 - H))) / (2 * H)
    Dd = lie.dexp_dot(lam_t, lam_dot_t)
    assert rel_err(Dd, fd) <= FD_TOL, rel_err(Dd, fd)
    # the combined function returns exactly the same matrices
    D, Di, Dd2 = lie.dexp_all(lam_t, lam_dot_t)
    np.testing.assert_array_equal(D, lie.dexp(lam_t))
    np.testing.assert_array_equal(Di, lie.dexp_inv(lam_t))
    np.testing.assert_array_equal(Dd2, Dd)


def test_dexp_dot_is_linear_in_lam_dot_and_zero_at_rest():
    rng = rng_for("lin")
    lam, a, b = random_lam(rng, 0.8), rng.standard_normal(6), rng.standard_normal(6)
    np.testing.assert_allclose(
        lie.dexp_dot(lam, 2 * a - b), 2 * lie.dexp_dot(lam, a) - lie.dexp_dot(lam, b), rtol=0, atol=1e-13
    )
    np.testing.assert_array_equal(lie.dexp_dot(lam, np.zeros(6)), np.zeros((6, 6)))
    # at lam = 0: dexp = I + ad/2 + ..., so d/dt dexp = ad(lam_dot)/2
    np.testing.assert_allclose(lie.dexp_dot(np.zeros(6), a), 0.5 * pin.Motion(a).action, rtol=0, atol=1e-15)


# ----------------------------------------------------------------------------------
# The controller relation: lam = log6(T^-1 Td), lam_dot = dexp^-1(lam) (Ad(T~) Vd - V)
# ----------------------------------------------------------------------------------
class _Trajectory:
    """T(t) = T0 Exp(xa t) Exp(xb sin(f t)): smooth, with an exact body twist.

    Body twist (T^-1 dT/dt) = Ad(Exp(xb s))^-1 xa + xb s_dot, s = sin(f t), since
    Exp(xb s) is a one-parameter subgroup.
    """

    def __init__(self, rng, scale):
        self.T0 = exp6(random_lam(rng, 2.0))
        self.xa = scale * rng.standard_normal(6)
        self.xb = scale * rng.standard_normal(6)
        self.f = 0.5 + rng.random()

    def pose(self, t):
        return self.T0 @ exp6(self.xa * t) @ exp6(self.xb * math.sin(self.f * t))

    def twist(self, t):
        B = pin.exp6(self.xb * math.sin(self.f * t))
        return B.actionInverse @ self.xa + self.xb * self.f * math.cos(self.f * t)


@pytest.mark.parametrize("seed", range(6))
def test_controller_relation_lambda_dot(seed):
    rng = rng_for("controller", seed)
    traj = _Trajectory(rng, 0.4)
    # desired = actual offset by a random error (angles from small to ~2.5 rad)
    offset = random_lam(rng, [1e-4, 0.05, 0.4, 1.0, 2.0, 2.5][seed])
    des = _Trajectory(rng, 0.4)
    des.T0 = traj.T0 @ exp6(offset)
    checked = 0
    for t in np.linspace(0.0, 1.5, 7):
        T, Td = traj.pose(t), des.pose(t)
        V, Vd = traj.twist(t), des.twist(t)
        # sanity of the trajectory construction: body twists by finite differences
        dT = (traj.pose(t + H) - traj.pose(t - H)) / (2 * H)
        assert rel_err(vee6(np.linalg.inv(T) @ dT), V) <= FD_TOL
        Tt = np.linalg.solve(T, Td)  # T⁻¹T_d
        lam = log6(Tt)
        lie.check_rotation_domain(lam)
        Vt = pin.SE3(Tt).action @ Vd - V
        lam_dot = lie.dexp_inv(lam) @ Vt
        fd = (
            log6(np.linalg.solve(traj.pose(t + H), des.pose(t + H)))
            - log6(np.linalg.solve(traj.pose(t - H), des.pose(t - H)))
        ) / (2 * H)
        assert rel_err(lam_dot, fd) <= FD_TOL, (t, rel_err(lam_dot, fd))
        # and the forward relation d/dt T~ = hat6(V~) T~
        dTt = (
            np.linalg.solve(traj.pose(t + H), des.pose(t + H))
            - np.linalg.solve(traj.pose(t - H), des.pose(t - H))
        ) / (2 * H)
        assert rel_err(dTt, hat6(Vt) @ Tt) <= FD_TOL
        checked += 1
    assert checked == 7


# ----------------------------------------------------------------------------------
# The pi check
# ----------------------------------------------------------------------------------
def test_rotation_domain_check():
    rng = rng_for("domain")
    n = unit(rng)
    for theta in (0.0, 1.0, 3.0, math.pi - 2 * lie.PI_MARGIN):
        lie.check_rotation_domain(np.concatenate([np.ones(3), theta * n]))
    for theta in (math.pi - 0.5 * lie.PI_MARGIN, math.pi, 4.0, float("nan")):
        with pytest.raises(ValueError) as info:
            lie.check_rotation_domain(np.concatenate([np.ones(3), theta * n]))
        msg = str(info.value)
        assert "\n" not in msg
        assert "requires |λ_rot| < π" in msg and "orientation error" in msg
        if not math.isnan(theta):
            assert f"{theta:.9g}" in msg
    # a custom margin
    with pytest.raises(ValueError):
        lie.check_rotation_domain(np.concatenate([np.zeros(3), 3.0 * n]), margin=0.2)


def test_inv_coefficients_are_coef0_and_coef1_bit_for_bit():
    """The SE(3) impedance's one-call (g, e, g1, e1) repeats coef0's and coef1's expressions:
    equal to the last bit on both sides of both Taylor switches (0.1 and 0.5 rad), so the
    controller's results do not depend on which of them it calls."""
    rng = np.random.default_rng(6)
    thetas = np.concatenate(
        [
            rng.uniform(0.0, 0.1, 500),
            rng.uniform(0.1, 0.5, 500),
            rng.uniform(0.5, 3.1, 500),
            [0.0, 1e-9, 0.1, 0.5],
        ]
    )
    for t in thetas.tolist():
        x = t * t
        trig = lie.trig_terms(t) if t >= lie.TAYLOR_THETA_0 else (0.0, 0.0, 0.0)
        expected = lie.coef0(t, x, *trig)[3:] + lie.coef1(t, x, *trig)[3:]
        assert lie.inv_coefficients(t) == expected, t
