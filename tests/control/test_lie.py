"""Tests of compliant_docking.control.lie: round trips, finite differences, Taylor switches, pinocchio.

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
    A = lie.ad(lam)
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
    assert rel_err(lie.exp6(lam_lo), lie.exp6(lam_hi)) <= SWITCH_TOL
    assert rel_err(lie.log6(lie.exp6(lam_lo)), lam_lo) <= RT_TOL
    assert rel_err(lie.log6(lie.exp6(lam_hi)), lam_hi) <= RT_TOL


# ----------------------------------------------------------------------------------
# SO(3)
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("theta", ANGLES)
def test_so3_exp_log_round_trip(theta):
    rng = rng_for("so3", theta)
    for _ in range(20):
        w = theta * unit(rng)
        R = lie.exp3(w)
        np.testing.assert_allclose(R, expm_ref(lie.hat3(w)), rtol=0, atol=1e-14)
        np.testing.assert_allclose(R @ R.T, np.eye(3), rtol=0, atol=1e-14)
        w2 = lie.log3(R)
        assert np.linalg.norm(w2) <= math.pi + 1e-15
        assert np.linalg.norm(w2 - w) <= RT_TOL * max(theta, 1e-300) or theta == 0.0
        if theta == 0.0:
            assert np.all(w2 == 0.0)


def test_log3_of_random_rotations_has_norm_at_most_pi():
    rng = rng_for("randrot")
    for _ in range(200):
        q = unit(rng, 4)
        R = pin.Quaternion(q[0], q[1], q[2], q[3]).toRotationMatrix()
        w = lie.log3(R)
        assert np.linalg.norm(w) <= math.pi + 1e-15
        np.testing.assert_allclose(lie.exp3(w), R, rtol=0, atol=1e-14)


def test_log3_at_exactly_pi():
    rng = rng_for("pi")
    cases = [np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])]
    for _ in range(20):
        n = unit(rng)
        cases.append(2.0 * np.outer(n, n) - np.eye(3))  # rotation by exactly pi about n
    for R in cases:
        w = lie.log3(R)
        assert abs(np.linalg.norm(w) - math.pi) <= 4e-15
        np.testing.assert_allclose(lie.exp3(w), R, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(lie.log3(np.diag([1.0, -1.0, -1.0])), [math.pi, 0.0, 0.0])


@pytest.mark.parametrize("theta", [1e-9, 1e-3, 0.3, 1.0, 2.0, 3.0, math.pi - 1e-6])
def test_so3_left_jacobian(theta):
    rng = rng_for("Jl", theta)
    w, dw = theta * unit(rng), rng.standard_normal(3)
    J = lie.so3_left_jacobian(w)
    # definition: d/dt exp3(w + t dw) exp3(w)^T = hat3(J dw)
    dR = (lie.exp3(w + H * dw) - lie.exp3(w - H * dw)) / (2 * H)
    np.testing.assert_allclose(lie.vee3(dR @ lie.exp3(w).T), J @ dw, rtol=0, atol=FD_TOL)
    np.testing.assert_allclose(lie.so3_left_jacobian_inv(w) @ J, np.eye(3), rtol=0, atol=1e-12)


# ----------------------------------------------------------------------------------
# SE(3) exp/log, poses, pinocchio reference
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("theta", ANGLES)
def test_se3_exp_log_round_trip_and_pinocchio(theta):
    rng = rng_for("se3", theta)
    for _ in range(20):
        lam = random_lam(rng, theta)
        T = lie.exp6(lam)
        np.testing.assert_allclose(T, expm_ref(hat6(lam)), rtol=0, atol=1e-13)
        R, p = lie.exp6_rp(lam)
        np.testing.assert_array_equal(T[:3, :3], R)
        np.testing.assert_array_equal(T[:3, 3], p)
        lam2 = lie.log6(T)
        assert np.linalg.norm(lam2 - lam) <= RT_TOL * max(1.0, np.linalg.norm(lam))
        np.testing.assert_array_equal(lie.log6_rp(R, p), lam2)
        # pinocchio as an independent reference ([linear; angular] ordering too)
        M = pin.exp6(lam)
        np.testing.assert_allclose(T, M.homogeneous, rtol=0, atol=1e-12)
        np.testing.assert_allclose(lam2, pin.log6(M).vector, rtol=0, atol=1e-12 if theta < 2.5 else 1e-10)


def test_log6_of_pinocchio_random_poses():
    for _ in range(100):
        M = pin.SE3.Random()
        M.translation *= 3.0
        lam = lie.log6(M.homogeneous)
        np.testing.assert_allclose(lam, pin.log6(M).vector, rtol=0, atol=1e-10)
        np.testing.assert_allclose(lie.exp6(lam), M.homogeneous, rtol=0, atol=1e-13)


def test_pose_helpers():
    rng = rng_for("pose")
    T, Td = lie.exp6(random_lam(rng, 2.0)), lie.exp6(random_lam(rng, 1.0))
    np.testing.assert_allclose(lie.se3_inverse(T), np.linalg.inv(T), rtol=0, atol=1e-13)
    np.testing.assert_allclose(lie.relative_pose(T, Td), np.linalg.inv(T) @ Td, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(lie.se3_from_rp(T[:3, :3], T[:3, 3]), T)
    xi = rng.standard_normal(6)
    np.testing.assert_array_equal(lie.hat6(xi), hat6(xi))
    np.testing.assert_array_equal(lie.vee6(lie.hat6(xi)), xi)
    # list input and (6, 1) input are accepted
    np.testing.assert_array_equal(lie.exp6(list(xi)), lie.exp6(xi))
    np.testing.assert_array_equal(lie.dexp(xi.reshape(6, 1)), lie.dexp(xi))
    with pytest.raises(ValueError):
        lie.dexp(np.zeros(5))


# ----------------------------------------------------------------------------------
# Adjoints
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("theta", [0.0, 1e-6, 0.7, 2.0, math.pi - 1e-6])
def test_adjoint(theta):
    rng = rng_for("Ad", theta)
    T = lie.exp6(random_lam(rng, theta, vscale=2.0))
    Ti = np.linalg.inv(T)
    Ad = lie.adjoint(T)
    for _ in range(6):
        xi = rng.standard_normal(6)
        np.testing.assert_allclose(hat6(Ad @ xi), T @ hat6(xi) @ Ti, rtol=0, atol=1e-13)
    np.testing.assert_allclose(Ad, pin.SE3(T).action, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(lie.adjoint_rp(T[:3, :3], T[:3, 3]), Ad)
    np.testing.assert_allclose(lie.adjoint_inv(T), np.linalg.inv(Ad), rtol=0, atol=1e-12)
    np.testing.assert_allclose(lie.adjoint_inv(T), pin.SE3(T).inverse().action, rtol=0, atol=1e-13)
    np.testing.assert_allclose(lie.coadjoint(T), np.linalg.inv(Ad).T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(lie.coadjoint(T), pin.SE3(T).dualAction, rtol=0, atol=1e-14)


def test_ad_is_the_commutator():
    rng = rng_for("ad")
    for _ in range(10):
        xi, eta = 2.0 * rng.standard_normal(6), rng.standard_normal(6)
        X, Y = hat6(xi), hat6(eta)
        np.testing.assert_allclose(hat6(lie.ad(xi) @ eta), X @ Y - Y @ X, rtol=0, atol=1e-13)
    # ad is the derivative of Ad along exp: d/dt Ad(exp6(t xi)) at 0 = ad(xi)
    xi = rng.standard_normal(6)
    dAd = (lie.adjoint(lie.exp6(H * xi)) - lie.adjoint(lie.exp6(-H * xi))) / (2 * H)
    np.testing.assert_allclose(dAd, lie.ad(xi), rtol=0, atol=FD_TOL)


# ----------------------------------------------------------------------------------
# dexp, dexp_inv, dexp_dot
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("theta", ANGLES)
def test_dexp_finite_difference(theta):
    """d/dt Exp(lam + t delta) Exp(lam)^-1 at t = 0 equals hat6(dexp(lam) delta)."""
    rng = rng_for("dexp", theta)
    lam = random_lam(rng, theta)
    D = lie.dexp(lam)
    Einv = np.linalg.inv(lie.exp6(lam))
    fd = np.empty((6, 6))
    for i in range(6):
        delta = np.zeros(6)
        delta[i] = 1.0
        dT = (lie.exp6(lam + H * delta) - lie.exp6(lam - H * delta)) / (2 * H)
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
    np.testing.assert_allclose(lie.dexp_dot(np.zeros(6), a), 0.5 * lie.ad(a), rtol=0, atol=1e-15)


# ----------------------------------------------------------------------------------
# The controller relation: lam = log6(T^-1 Td), lam_dot = dexp^-1(lam) (Ad(T~) Vd - V)
# ----------------------------------------------------------------------------------
class _Trajectory:
    """T(t) = T0 Exp(xa t) Exp(xb sin(f t)): smooth, with an exact body twist.

    Body twist (T^-1 dT/dt) = Ad(Exp(xb s))^-1 xa + xb s_dot, s = sin(f t), since
    Exp(xb s) is a one-parameter subgroup.
    """

    def __init__(self, rng, scale):
        self.T0 = lie.exp6(random_lam(rng, 2.0))
        self.xa = scale * rng.standard_normal(6)
        self.xb = scale * rng.standard_normal(6)
        self.f = 0.5 + rng.random()

    def pose(self, t):
        return self.T0 @ lie.exp6(self.xa * t) @ lie.exp6(self.xb * math.sin(self.f * t))

    def twist(self, t):
        B = lie.exp6(self.xb * math.sin(self.f * t))
        return lie.adjoint_inv(B) @ self.xa + self.xb * self.f * math.cos(self.f * t)


@pytest.mark.parametrize("seed", range(6))
def test_controller_relation_lambda_dot(seed):
    rng = rng_for("controller", seed)
    traj = _Trajectory(rng, 0.4)
    # desired = actual offset by a random error (angles from small to ~2.5 rad)
    offset = random_lam(rng, [1e-4, 0.05, 0.4, 1.0, 2.0, 2.5][seed])
    des = _Trajectory(rng, 0.4)
    des.T0 = traj.T0 @ lie.exp6(offset)
    checked = 0
    for t in np.linspace(0.0, 1.5, 7):
        T, Td = traj.pose(t), des.pose(t)
        V, Vd = traj.twist(t), des.twist(t)
        # sanity of the trajectory construction: body twists by finite differences
        dT = (traj.pose(t + H) - traj.pose(t - H)) / (2 * H)
        assert rel_err(vee6(np.linalg.inv(T) @ dT), V) <= FD_TOL
        Tt = lie.relative_pose(T, Td)
        lam = lie.log6(Tt, check=True)
        Vt = lie.adjoint(Tt) @ Vd - V
        lam_dot = lie.dexp_inv(lam) @ Vt
        fd = (
            lie.log6(lie.relative_pose(traj.pose(t + H), des.pose(t + H)))
            - lie.log6(lie.relative_pose(traj.pose(t - H), des.pose(t - H)))
        ) / (2 * H)
        assert rel_err(lam_dot, fd) <= FD_TOL, (t, rel_err(lam_dot, fd))
        # and the forward relation d/dt T~ = hat6(V~) T~
        dTt = (
            lie.relative_pose(traj.pose(t + H), des.pose(t + H))
            - lie.relative_pose(traj.pose(t - H), des.pose(t - H))
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


def test_log6_check_flag():
    rng = rng_for("log6check")
    n, p = unit(rng), rng.standard_normal(3)
    near_pi = lie.se3_from_rp(lie.exp3((math.pi - 1e-8) * n), p)
    ok = lie.se3_from_rp(lie.exp3((math.pi - 1e-3) * n), p)
    lie.log6(near_pi)  # no check by default
    with pytest.raises(ValueError, match=r"\|λ_rot\| = 3\.14159"):
        lie.log6(near_pi, check=True)
    with pytest.raises(ValueError, match="SE\\(3\\) impedance requires"):
        lie.log6_rp(near_pi[:3, :3], p, check=True)
    lam = lie.log6(ok, check=True)
    assert abs(np.linalg.norm(lam[3:]) - (math.pi - 1e-3)) <= 1e-12
