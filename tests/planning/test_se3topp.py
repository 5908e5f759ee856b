"""se3topp is time-optimal: its closed-form phase-plane solution against the exact optimum
(quadrature of the speed-dependent bound, and a generic numerical TOPP on the real path),
the pure-translation case equal to the classic bang-bang, every sample within every limit,
continuity; optionally toppra (skipped when it is not installed)."""

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import brentq, minimize_scalar

from compliant_docking import CONF_DIR
from compliant_docking.planning.base import Reference, Waypoints
from compliant_docking.planning.se3topp import (
    Limits,
    bang_bang,
    bang_bang_time,
    screw_timing,
    world_to_body,
)
from tests.helpers import make_cfg
from tests.planning.cases import (
    AXIS,
    away_from,
    coupled_case,
    docking,
    fd_check,
    free_space,
    rotating_case,
    se3topp,
    twophase,
)

#: the issue's example: a screw of ‖ξ_v‖ = 0.33 m with ‖ξ_ω‖ = 1.5 rad about an axis
#: perpendicular to it (centripetal term c = 0.495 m), a_max = 0.05 m/s², v_max = 0.10 m/s
#: (the approach speed), loose angular limits
ISSUE_XI = np.array([0.33, 0.0, 0.0, 0.0, 1.5, 0.0])
ISSUE_LIMITS = Limits(v=0.10, a=0.05, omega=5.0, alpha=5.0)
#: every branch of the closed form: (name, ξ, limits)
CASES = [
    ("issue", ISSUE_XI, ISSUE_LIMITS),  # ramp on the centripetal bound, cruise at v/b
    ("triangle", ISSUE_XI, Limits(10.0, 0.05, 10.0, 10.0)),  # switch at s = ½ on it
    ("mvc", np.array([0.33, 0, 0, 0, 2.5, 0]), Limits(10.0, 0.05, 10.0, 10.0)),  # cruise at √(a/c)
    ("alpha_first", ISSUE_XI, Limits(10.0, 0.05, 10.0, 0.2)),  # α-bound ramp, then centripetal
    ("alpha_only", ISSUE_XI, Limits(10.0, 0.05, 10.0, 0.1)),  # α-bound triangle, never centripetal
    ("oblique", np.array([0.2, 0.1, 0.25, 0.3, -0.9, 0.4]), Limits(0.2, 0.05, 2.0, 2.0)),
]


def quadrature_time(xi, lim):
    """The exact optimum by quadrature, independent of the closed form: the bounds
    ṡ ≤ V = min(v/b, ω/w), |s̈| ≤ A(ṡ) = min(α/w, √(a² − c²ṡ⁴)/b) do not depend on s, so the
    optimum accelerates at A until s = ½ or ṡ = min(V, √(a/c)), cruises, and decelerates
    symmetrically: t(u) = ∫du/A, s(u) = ∫u du/A."""
    b, w = np.linalg.norm(xi[:3]), np.linalg.norm(xi[3:])
    c = np.linalg.norm(np.cross(xi[3:], xi[:3]))

    def A(u):
        return min(lim.alpha / w, math.sqrt(max(lim.a**2 - (c * u * u) ** 2, 0.0)) / b)

    cap = min(lim.v / b, lim.omega / w, math.sqrt(lim.a / c))
    room = lim.a**2 - (b * lim.alpha / w) ** 2  # the kink of A, where the α bound hands over
    kink = math.sqrt(math.sqrt(room) / c) if room > 0 else 0.0

    def integral(f, u):
        points = [kink] if 0.0 < kink < u else None
        return quad(f, 0.0, u, points=points, limit=500, epsabs=0.0, epsrel=1e-12)[0]

    s_of = lambda u: integral(lambda x: x / A(x), u)  # noqa: E731
    t_of = lambda u: integral(lambda x: 1.0 / A(x), u)  # noqa: E731
    if s_of(cap) >= 0.5:
        return 2.0 * t_of(brentq(lambda u: s_of(u) - 0.5, 0.0, cap, xtol=1e-15))
    return 2.0 * t_of(cap) + (1.0 - 2.0 * s_of(cap)) / cap


def path_derivatives(xi, s):
    """World-frame derivatives along T(s) = Exp(sξ), from dT/ds = T ξ^ (ξ the constant body
    twist): p' = R ξ_v, p'' = R' ξ_v = R [ξ_ω]× ξ_v, r' = R ξ_ω, r'' = R [ξ_ω]× ξ_ω = 0."""
    rot = pin.exp6(s * xi).rotation
    w_hat = pin.skew(xi[3:])
    return rot @ xi[:3], rot @ w_hat @ xi[:3], rot @ xi[3:], rot @ w_hat @ xi[3:]


def test_path_derivatives_match_finite_differences():
    """The derivatives the numerical TOPP below uses, against central differences of
    pin.exp6 (h = 1e-4: truncation ~h², rounding ~1e-16/h²; 1e-7)."""
    h = 1e-4
    for xi in (c[1] for c in CASES):
        for s in (0.0, 0.3, 1.0):
            pose = [pin.exp6((s + k * h) * xi) for k in (-1, 0, 1)]
            p = [m.translation for m in pose]
            dp, ddp, dr, ddr = path_derivatives(xi, s)
            assert np.abs((p[2] - p[0]) / (2 * h) - dp).max() < 1e-7
            assert np.abs((p[2] - 2 * p[1] + p[0]) / h**2 - ddp).max() < 1e-6
            assert np.abs(pin.log3(pose[2].rotation @ pose[0].rotation.T) / (2 * h) - dr).max() < 1e-7
            assert np.allclose(ddr, 0.0, atol=1e-15)


def numerical_topp_time(xi, lim, gap=1e-10):
    """A generic TOPP by numerical integration in the phase plane, on the path's world
    derivatives (:func:`path_derivatives`), assuming nothing of the closed form: at each
    (s, ṡ) the admissible s̈ is the intersection of ‖p's̈ + p''ṡ²‖ ≤ a and
    ‖r's̈ + r''ṡ²‖ ≤ α (two quadratics in s̈); the maximum-velocity curve is the least of
    v/‖p'‖, ω/‖r'‖ and, per quadratic, the speed where its discriminant vanishes. The
    maximal-acceleration curve F from rest and the maximal-deceleration curve B into rest
    (time reversed) are integrated in time (DOP853, rtol 1e-11) up to the MVC (stopped
    ``gap`` below it: an O(gap) error) and continued along it as a cruise; then
    T = max over s of t_F(s) + t_B(s): the time of min(F, B), attained where the two meet,
    a flat maximum whose location needs no precision."""
    xi = np.asarray(xi, float)

    def mvc(s):
        dp, ddp, dr, ddr = path_derivatives(xi, s)
        out = min(lim.v / np.linalg.norm(dp), lim.omega / np.linalg.norm(dr))
        for d1, d2, bound in ((dp, ddp, lim.a), (dr, ddr, lim.alpha)):
            cross2 = (d1 @ d1) * (d2 @ d2) - (d1 @ d2) ** 2  # disc ≥ 0 ⇔ u⁴·cross2 ≤ |d1|²bound²
            if cross2 > 0:
                out = min(out, ((d1 @ d1) * bound**2 / cross2) ** 0.25)
        return out

    def accel_range(s, u):
        lo, hi = -math.inf, math.inf
        dp, ddp, dr, ddr = path_derivatives(xi, s)
        for d1, d2, bound in ((dp, ddp, lim.a), (dr, ddr, lim.alpha)):
            qa, qb = d1 @ d1, (d1 @ d2) * u * u
            root = math.sqrt(max(qb * qb - qa * ((d2 @ d2) * u**4 - bound**2), 0.0))
            lo, hi = max(lo, (-qb - root) / qa), min(hi, (-qb + root) / qa)
        return lo, hi

    def curve(backward):
        """t(s) of the curve from rest at s = 0 (forward) or s = 1 (backward, time reversed)."""
        sign, start = (-1.0, 1.0) if backward else (1.0, 0.0)

        def rhs(_, y):
            lo, hi = accel_range(y[0], y[1])
            return [sign * y[1], -lo if backward else hi]

        def at_mvc(_, y):
            return y[1] - (1.0 - gap) * mvc(y[0])

        def at_end(_, y):
            return sign * (y[0] - start) - 1.0

        at_mvc.terminal = at_end.terminal = True
        sol = solve_ivp(
            rhs,
            (0.0, 1e3),
            [start, 0.0],
            method="DOP853",
            rtol=1e-11,
            atol=1e-13,
            dense_output=True,
            events=[at_mvc, at_end],
        )
        t_end, (s_end, u_end) = sol.t[-1], sol.y[:, -1]
        reach = sign * (s_end - start)

        def t_of(s):
            dist = sign * (s - start)  # how far from the start
            if dist >= reach:  # on the MVC (flat in these cases): cruise at u_end
                return t_end + (dist - reach) / u_end
            return brentq(lambda t: sign * (sol.sol(t)[0] - start) - dist, 0.0, t_end, xtol=1e-14)

        return t_of

    t_f, t_b = curve(False), curve(True)
    res = minimize_scalar(
        lambda s: -(t_f(s) + t_b(s)), bounds=(1e-6, 1 - 1e-6), method="bounded", options={"xatol": 1e-8}
    )
    return -res.fun


def one_segment(xi, lim):
    """An SE3ToppPlanner with the single (docking) segment Exp(ξ) under ``lim``."""
    start = pin.SE3(np.diag([1.0, -1.0, -1.0]), np.array([0.55, 0.0, 0.45]))
    goal = start * pin.exp6(np.asarray(xi, float))
    axis = np.array([0.0, 0.0, -1.0])
    standoff = abs(float((goal.translation - start.translation) @ axis)) + 1.0  # no approach
    traj = se3topp(
        Waypoints(start=start, goal=goal, axis=axis),
        standoff=standoff,
        v_max_docking=lim.v,
        a_max_docking=lim.a,
        omega_max_docking=lim.omega,
        alpha_max_docking=lim.alpha,
    )
    assert [s[0] for s in traj.segments] == ["docking"]
    return traj


# --------------------------------------------------------------------------- the optimum
def test_issue_example_is_the_exact_optimum():
    """5.373978 s: the quadrature optimum to 1e-12 (both are exact up to rounding: the closed
    form evaluates elliptic integrals to ~1e-15, the quadrature of a smooth integrand (the
    cruise at v/b stays below √(a/c)) converges to its 1e-13 tolerance). The issue's
    5.375 s is this rounded up (coarser integration); the old fixed-acceleration bang-bang
    gave 6.092 s."""
    traj = one_segment(ISSUE_XI, ISSUE_LIMITS)
    assert math.isclose(traj.duration, quadrature_time(ISSUE_XI, ISSUE_LIMITS), rel_tol=1e-12)
    assert math.isclose(traj.duration, 5.375, abs_tol=1.5e-3)
    assert math.isclose(traj.duration, 5.3739785, abs_tol=1e-7)
    prof = traj.profiles()[0]
    assert prof["centripetal"] and prof["shape"] == "trapezoid"
    assert math.isclose(prof["v_p"], ISSUE_LIMITS.v / 0.33, rel_tol=1e-14)  # cruise at v/b


@pytest.mark.parametrize("name, xi, lim", CASES, ids=[c[0] for c in CASES])
def test_duration_equals_the_quadrature_optimum(name, xi, lim):
    """Quadrature of t = ∫du/A(u) is exact to ~1e-10 here (the "mvc" case integrates
    1/√(u₀ − u) up to u₀, which quad handles to about that); 1e-9 is rounding-level."""
    assert math.isclose(screw_timing(xi, lim).T, quadrature_time(xi, lim), rel_tol=1e-9)


@pytest.mark.parametrize("name, xi, lim", CASES, ids=[c[0] for c in CASES])
def test_duration_equals_a_numerical_topp_on_the_real_path(name, xi, lim):
    """A generic phase-plane integration on the actual SE(3) path agrees to 1e-8 (its
    integration tolerance 1e-11 and the 1e-10 stop below the MVC; measured ≤ 3e-11). This
    also checks the premises of the closed form: the bounds do not depend on s, and the
    centripetal term is c ṡ² with c = ‖ξ_ω × ξ_v‖."""
    assert math.isclose(screw_timing(xi, lim).T, numerical_topp_time(xi, lim), rel_tol=1e-8)


def test_toppra_agrees_when_installed():
    """toppra (optional, not a dependency) on the TCP position path, the norm bound
    ‖ẍ‖ ≤ a as 2000 half-spaces (Fibonacci directions; a circumscribed polytope, at most
    ~0.1 % looser) and ‖ẋ‖ ≤ v on an arc-length coordinate, 200 grid intervals (its
    collocation error, measured 0.04 % here): within 0.2 % of the closed form."""
    pytest.importorskip("toppra")  # imports matplotlib.pyplot: only here, lazily
    import toppra
    import toppra.algorithm
    import toppra.constraint as tc

    b = float(np.linalg.norm(ISSUE_XI[:3]))
    ss = np.linspace(0.0, 1.0, 401)
    q = np.array([np.r_[pin.exp6(s * ISSUE_XI).translation, b * s] for s in ss])
    path = toppra.SplineInterpolator(ss, q)
    n = 2000
    i = np.arange(n) + 0.5
    polar, azim = np.arccos(1 - 2 * i / n), np.pi * (1 + 5**0.5) * i
    dirs = np.c_[
        np.cos(azim) * np.sin(polar), np.sin(azim) * np.sin(polar), np.cos(polar), np.zeros(n)
    ]  # no bound on the arc-length coordinate's acceleration
    acc = tc.SecondOrderConstraint(
        lambda q, qd, qdd: qdd,
        lambda q: dirs,
        lambda q: np.full(n, ISSUE_LIMITS.a),
        dof=4,
        discretization_scheme=tc.DiscretizationType.Interpolation,
    )
    vel = tc.JointVelocityConstraint(np.array([[-1e3, 1e3]] * 3 + [[-ISSUE_LIMITS.v, ISSUE_LIMITS.v]]))
    inst = toppra.algorithm.TOPPRA(
        [vel, acc], path, gridpoints=np.linspace(0, 1, 201), parametrizer="ParametrizeConstAccel"
    )
    duration = inst.compute_trajectory(0, 0).duration
    assert math.isclose(duration, screw_timing(ISSUE_XI, ISSUE_LIMITS).T, rel_tol=2e-3)


# --------------------------------------------------------------------------- pure translation
@pytest.mark.parametrize(
    "ahead, lateral", [(0.18, (0.0, 0.0)), (0.12, (0.0, 0.0)), (0.18, (0.01, -0.02)), (0.08, (0.0, 0.0))]
)
def test_pure_translation_is_the_classic_bang_bang_exactly(ahead, lateral):
    """No rotation → no centripetal term: each segment is the closed-form bang-bang (same
    floating-point operations as before, so the default docking reference is unchanged
    bit for bit), T = 1/v_s + v_s/a_s or 2/√a_s with v_s = v/L, a_s = a/L."""
    down = np.diag([1.0, -1.0, -1.0])
    goal = pin.SE3(down, np.array([0.55, 0.0, 0.20]))
    start = pin.SE3(down, goal.translation + np.array([*lateral, ahead]))
    traj = se3topp(Waypoints(start=start, goal=goal, axis=np.array([0.0, 0.0, -1.0])))
    lims = {"approach": (0.10, 0.20), "docking": (0.02, 0.05)}
    t = np.linspace(-0.5, traj.duration + 0.5, 5001)
    tab = traj.table(t)
    for prof, (name, t0, t1) in zip(traj.profiles(), traj.segments):
        length = float(np.linalg.norm(prof["xi"][:3]))
        v_s, a_s = lims[name][0] / length, lims[name][1] / length
        peak = min(v_s, math.sqrt(a_s))
        assert not prof["centripetal"] and prof["a_s"] == a_s and prof["v_p"] == peak
        assert t1 - t0 == bang_bang_time(peak, a_s)
        k = (t >= t0) & (t < t1)
        s, ds, dds = bang_bang(t[k] - t0, peak, a_s, t1 - t0)
        speed = np.linalg.norm(tab.twist[k, :3], axis=1)
        assert np.allclose(speed, ds * length, rtol=1e-12, atol=1e-15)
        assert np.allclose(
            np.linalg.norm(tab.accel[k, :3], axis=1), np.abs(dds) * length, rtol=1e-12, atol=1e-15
        )


def test_research_case_durations_are_unchanged():
    """The research iiwa14 case: 1.3 s + 5.4 s = 6.7 s, to the last bit of the previous
    planner (pinned: 1.2999999999999996 and 6.700000000000002)."""
    down = np.diag([1.0, -1.0, -1.0])
    goal = pin.SE3(down, np.array([0.55, 0.0, 0.20]))
    start = pin.SE3(down, goal.translation + np.array([0.0, 0.0, 0.18]))
    traj = se3topp(Waypoints(start=start, goal=goal, axis=np.array([0.0, 0.0, -1.0])))
    assert traj.segments == [
        ("approach", 0.0, 1.2999999999999996),
        ("docking", 1.2999999999999996, 6.700000000000002),
    ]


# --------------------------------------------------------------------------- limits, continuity
def sample(traj, n=40001):
    name, t0, t1 = traj.segments[0]
    switches = t0 + np.array(traj.profiles()[0]["switch_times"])
    t = np.unique(np.concatenate([np.linspace(t0, t1, n), switches, switches - 1e-9, switches + 1e-9]))
    return t[(t >= t0) & (t <= t1)], traj.table(t[(t >= t0) & (t <= t1)])


@pytest.mark.parametrize("name, xi, lim", CASES, ids=[c[0] for c in CASES])
def test_every_sample_respects_every_limit_and_one_binds(name, xi, lim):
    """Norms and world-axis components within each limit to 1e-12 relative (the samples are
    closed-form: rounding of ellipj/arctan2 is ~1e-15; margin 1000×). Time-optimality in the
    samples: at every instant one limit is active to 1e-9 (a bang on the speed-dependent
    acceleration bound, or the cruise on the speed bound, or the flat MVC ṡ = √(a/c) where
    the centripetal part alone uses all of a)."""
    traj = one_segment(xi, lim)
    t, tab = sample(traj)
    ratios = []
    for vec, bound in (
        (tab.twist[:, :3], lim.v),
        (tab.accel[:, :3], lim.a),
        (tab.twist[:, 3:], lim.omega),
        (tab.accel[:, 3:], lim.alpha),
    ):
        assert np.abs(vec).max() <= bound * (1 + 1e-12)
        norm = np.linalg.norm(vec, axis=1)
        assert norm.max() <= bound * (1 + 1e-12), (name, norm.max() / bound)
        ratios.append(norm / bound)
    # not at the ends nor at a switching instant, where s̈ is a convention (and a classic
    # triangle has a rounding-size "cruise" between t_acc and T − t_acc: 2e-15 s here)
    switches = traj.segments[0][1] + np.array(traj.profiles()[0]["switch_times"])
    near = np.abs(t[:, None] - switches[None, :]).min(axis=1) <= 1e-12
    inner = (t > t[0] + 1e-6) & (t < t[-1] - 1e-6) & ~near
    active = np.max(ratios, axis=0)[inner]
    assert active.min() > 1 - 1e-9, (name, active.min())


@pytest.mark.parametrize("name, xi, lim", CASES, ids=[c[0] for c in CASES])
def test_position_and_velocity_are_continuous(name, xi, lim):
    """Across every switching instant (1e-9 s either side) the pose moves by at most
    max speed × 2e-9 and the twist by at most max accel × 2e-9 (+ rounding 1e-15); the
    acceleration jumps only where the profile switches between bang and cruise. At the
    ends: exactly at rest at the waypoints."""
    traj = one_segment(xi, lim)
    t0 = traj.segments[0][1]
    for ts in t0 + np.array(traj.profiles()[0]["switch_times"]):
        tab = traj.table(np.array([ts - 1e-9, ts, ts + 1e-9]))
        assert np.abs(np.diff(tab.pos, axis=0)).max() <= lim.v * 1e-9 + 1e-15
        assert np.abs(np.diff(tab.twist[:, :3], axis=0)).max() <= lim.a * 1e-9 + 1e-15
        assert np.abs(np.diff(tab.twist[:, 3:], axis=0)).max() <= lim.alpha * 1e-9 + 1e-15
    end = traj.table(np.array([0.0, traj.duration]))
    assert not end.twist.any() and not end.accel[1].any()  # s̈ = a_s at t = 0 (a bang from rest)
    goal = pin.SE3(np.diag([1.0, -1.0, -1.0]), np.array([0.55, 0.0, 0.45])) * pin.exp6(xi)
    assert np.allclose(end.pos[1], goal.translation, atol=1e-14)
    assert np.allclose(end.rot[1], goal.rotation, atol=1e-14)


@pytest.mark.parametrize("name, xi, lim", CASES, ids=[c[0] for c in CASES])
def test_twist_and_acceleration_are_derivatives(name, xi, lim):
    """Central differences (h = 1e-6) of the pose and twist away from the switching instants:
    errors ~h² × jerk and ~ε/h, below 1e-8 (twist) and 1e-7 (acceleration)."""
    traj = one_segment(xi, lim)
    switches = np.array(traj.profiles()[0]["switch_times"])
    t = np.linspace(0.0, traj.duration, 3001)
    t = t[np.all(np.abs(t[:, None] - switches[None, :]) > 1e-4, axis=1)]
    h = 1e-6
    ref, lo, hi = traj.table(t), traj.table(t - h), traj.table(t + h)
    omega = np.array([pin.log3(a @ b.T) for a, b in zip(hi.rot, lo.rot)]) / (2 * h)
    assert np.abs((hi.pos - lo.pos) / (2 * h) - ref.twist[:, :3]).max() < 1e-8
    assert np.abs(omega - ref.twist[:, 3:]).max() < 1e-8
    assert np.abs((hi.twist - lo.twist) / (2 * h) - ref.accel).max() < 1e-7


def test_centripetal_profile_is_symmetric_and_rest_to_rest():
    """s(T − u) = 1 − s(u), ṡ symmetric, s̈ antisymmetric (the bounds are symmetric in s̈)."""
    tm = screw_timing(ISSUE_XI, ISSUE_LIMITS)
    u = np.linspace(0.0, tm.T, 2001)
    s, ds, dds = tm(u)
    s_r, ds_r, dds_r = tm(tm.T - u)
    assert np.allclose(s + s_r, 1.0, atol=1e-14) and np.allclose(ds, ds_r, atol=1e-14)
    mid = np.abs(u[:, None] - np.array(tm.switch_times())[None, :]).min(axis=1) > 1e-9
    assert np.allclose(dds[mid], -dds_r[mid], atol=1e-14)
    assert (s[0], ds[0], dds[0]) == (0.0, 0.0, ISSUE_LIMITS.a / 0.33)
    assert (s[-1], ds[-1], dds[-1]) == (1.0, 0.0, 0.0)
    assert np.all(np.diff(s) > 0)


# planner-level cases (moved from the former test_planners.py)


def switch_times(traj):
    """Segment boundaries and the instants where s̈ (or its rate) jumps, of an SE3ToppPlanner."""
    return [t0 + u for (_, t0, _), prof in zip(traj.segments, traj.profiles()) for u in prof["switch_times"]]


# --------------------------------------------------------------------------- twophase
def test_bang_bang_time_triangle_and_trapezoid():
    assert math.isclose(bang_bang_time(v_s=5.0, a_s=10.0), 2 / math.sqrt(10.0))  # √a ≤ v
    assert math.isclose(bang_bang_time(v_s=0.2, a_s=0.5), 1 / 0.2 + 0.2 / 0.5)  # 5.4 s


def test_se3topp_reproduces_the_research_case_and_beats_twophase():
    wp = docking(0.18)
    topp, two = se3topp(wp, standoff=0.10), twophase(wp, standoff=0.10)
    (_, _, t1), (_, _, t2) = topp.segments
    assert math.isclose(t1, 1.3, rel_tol=1e-9) and math.isclose(t2 - t1, 5.4, rel_tol=1e-9)
    assert [p["shape"] for p in topp.profiles()] == ["trapezoid", "trapezoid"]
    assert topp.duration < two.duration


def test_se3topp_triangle_when_the_segment_is_short():
    traj = se3topp(docking(0.12), standoff=0.10)  # approach 0.02 m
    approach = traj.profiles()[0]
    # s-units: v_s = 0.1/0.02 = 5, a_s = 0.2/0.02 = 10, √10 ≤ 5: triangle of 2/√10 s
    assert approach["shape"] == "triangle"
    assert math.isclose(approach["T"], 2 / math.sqrt(10.0), rel_tol=1e-12)
    t = np.linspace(0, approach["T"], 10001)
    speed = np.linalg.norm(traj.table(t).twist[:, :3], axis=1)
    assert math.isclose(speed.max(), 0.02 * math.sqrt(10.0), rel_tol=1e-3)  # peak √a_s·L < v_max


@pytest.mark.parametrize("case", ["translation", "screw", "coupled"])
def test_se3topp_limits_hold_along_the_whole_profile(case):
    lims = {"approach": (0.10, 0.20, 0.20, 0.20), "docking": (0.02, 0.05, 0.05, 0.05)}
    if case == "coupled":
        wp, kwargs = coupled_case()
        lims["approach"] = (0.10, 0.05, 5.0, 5.0)
    else:
        wp, kwargs = (docking(0.18) if case == "translation" else rotating_case(math.radians(60))), {}
    traj = se3topp(wp, standoff=0.10, **kwargs)
    if case == "coupled":
        xi = traj.profiles()[0]["xi"]
        assert np.linalg.norm(np.cross(xi[3:], xi[:3])) > 0.5  # a real centripetal term
    for name, t0, t1 in traj.segments:
        t = np.linspace(t0, t1, 40001)
        tab = traj.table(t)
        v, a, w, al = lims[name]
        parts = [(tab.twist[:, :3], v), (tab.accel[:, :3], a), (tab.twist[:, 3:], w), (tab.accel[:, 3:], al)]
        ratios = []
        for vec, lim in parts:
            assert np.abs(vec).max() <= lim * (1 + 1e-9)  # every world-axis component
            norm = np.linalg.norm(vec, axis=1).max()
            assert norm <= lim * (1 + 1e-9)  # and the norm
            ratios.append(norm / lim)
        assert max(ratios) > 0.999, (name, ratios)  # time-optimal: some limit is reached


def test_screw_timing_beats_every_fixed_acceleration_bang_bang():
    """With a centripetal term the time-optimal profile is faster than every bang-bang of
    fixed |s̈| that keeps ‖ẍ‖² = b²s̈² + c²ṡ⁴ ≤ a² at its peak (the family the planner
    used to optimise over): 2.106 s against 2.349 s for this screw (−10 %)."""
    xi = np.array([0.3, 0.0, 0.1, 0.0, 1.2, 0.0])  # ξ_ω × ξ_v ≠ 0
    lim = Limits(v=0.5, a=0.3, omega=5.0, alpha=5.0)
    timing = screw_timing(xi, lim)
    assert timing.centripetal
    b, c = np.linalg.norm(xi[:3]), np.linalg.norm(np.cross(xi[3:], xi[:3]))
    best = math.inf
    for v in np.linspace(1e-3, 2.0, 4000):
        room = lim.a**2 - (c * v * v) ** 2
        if room <= 0:
            continue
        a = min(lim.alpha / np.linalg.norm(xi[3:]), math.sqrt(room) / b)
        if v * v <= a and v <= lim.v / b:
            best = min(best, bang_bang_time(v, a))
    assert timing.T < 0.91 * best


def test_se3topp_rest_to_rest_at_every_waypoint():
    wp = rotating_case()
    traj = se3topp(wp, standoff=0.10)
    ref = Reference()
    pre_dock = wp.goal.translation - 0.10 * AXIS
    for t, pos, rot in (
        (0.0, wp.start.translation, wp.start.rotation),
        (traj.segments[0][2], pre_dock, wp.goal.rotation),
        (traj.duration, wp.goal.translation, wp.goal.rotation),
        (traj.duration + 2.0, wp.goal.translation, wp.goal.rotation),
    ):
        traj.sample(t, ref)
        assert np.allclose(ref.pos, pos, atol=1e-12) and np.allclose(ref.rot, rot, atol=1e-12)
        assert np.allclose(ref.twist, 0.0, atol=1e-12)
    traj.sample(traj.duration + 2.0, ref)
    assert np.allclose(ref.accel, 0.0)


def test_se3topp_geodesic_midpoint():
    wp = rotating_case(math.pi / 2)
    traj = se3topp(wp, standoff=0.10)
    name, t0, t1 = traj.segments[0]
    mid = traj.table(np.array([0.5 * (t0 + t1)]))
    rel = wp.start.rotation.T @ mid.rot[0]
    assert math.isclose(np.linalg.norm(pin.log3(rel)), math.pi / 4, abs_tol=1e-12)  # 90° → 45°
    # the pose is T_a·Exp(ξ/2), the midpoint of the constant-screw motion
    xi = traj.profiles()[0]["xi"]
    half = pin.SE3(wp.start.rotation, wp.start.translation) * pin.exp6(0.5 * xi)
    assert np.allclose(mid.pos[0], half.translation, atol=1e-12)
    assert np.allclose(mid.rot[0], half.rotation, atol=1e-12)
    # …and it is a screw: the position is not the straight-line midpoint
    straight = 0.5 * (wp.start.translation + wp.goal.translation - 0.10 * AXIS)
    assert np.linalg.norm(mid.pos[0] - straight) > 1e-3


def test_se3topp_screw_pose_matches_exp6():
    wp = rotating_case(1.0)
    traj = se3topp(wp, standoff=0.10)
    sc = traj.screws[0]
    s = np.linspace(0.0, 1.0, 11)
    from compliant_docking.planning.se3topp import screw_pose

    rot, pos = screw_pose(sc.rot_a, sc.pos_a, sc.xi, s)
    Ta = pin.SE3(sc.rot_a, sc.pos_a)
    for k, sk in enumerate(s):
        T = Ta * pin.exp6(sk * sc.xi)
        assert np.allclose(rot[k], T.rotation, atol=1e-13) and np.allclose(pos[k], T.translation, atol=1e-13)


@pytest.mark.parametrize("case", ["translation", "screw", "coupled"])
def test_se3topp_world_twist_and_accel_are_derivatives(case):
    if case == "coupled":
        wp, kwargs = coupled_case()
        traj = se3topp(wp, standoff=0.10, **kwargs)
    else:
        traj = se3topp(docking(0.18) if case == "translation" else rotating_case(), standoff=0.10)
    t = np.linspace(0.0, traj.duration, 4001)
    t = t[away_from(t, switch_times(traj), 1e-4)]
    e_v, e_w, e_a = fd_check(traj, t)
    assert e_v < 1e-8 and e_w < 1e-8 and e_a < 1e-7, (e_v, e_w, e_a)


def test_se3topp_body_twist_and_its_derivative():
    """World → body conversion V_b = [Rᵀẋ; Rᵀω], V̇_b = [Rᵀẍ − ω_b × v_b; Rᵀω̇] agrees with
    finite differences of the pose (log6(T(t−h)⁻¹T(t+h))/2h) and of V_b, and with ξ ṡ, ξ s̈."""
    traj = se3topp(rotating_case(), standoff=0.10)
    t = np.linspace(0.0, traj.duration, 1501)
    t = t[away_from(t, switch_times(traj), 1e-4)]
    h = 1e-6
    ref, lo, hi = traj.table(t), traj.table(t - h), traj.table(t + h)
    Vb, dVb = world_to_body(ref.rot, ref.twist, ref.accel)
    Vb_lo, _ = world_to_body(lo.rot, lo.twist, lo.accel)
    Vb_hi, _ = world_to_body(hi.rot, hi.twist, hi.accel)
    fd_twist = np.array(
        [
            pin.log6(pin.SE3(Rl.T @ Rh, Rl.T @ (ph - pl))).vector
            for Rl, Rh, pl, ph in zip(lo.rot, hi.rot, lo.pos, hi.pos)
        ]
    ) / (2 * h)
    assert np.abs(fd_twist - Vb).max() < 1e-8
    assert np.abs((Vb_hi - Vb_lo) / (2 * h) - dVb).max() < 1e-7
    # on a constant-screw segment V_b = ξ ṡ and V̇_b = ξ s̈
    sc = traj.screws[0]
    k = t < sc.T
    _, ds, dds = sc.timing(t[k])
    assert np.allclose(Vb[k], np.outer(ds, sc.xi), atol=1e-12)
    assert np.allclose(dVb[k], np.outer(dds, sc.xi), atol=1e-12)


def test_se3topp_rejects_bad_limits_and_free_space():
    with pytest.raises(ValueError, match="omega_max_docking"):
        se3topp(docking(), omega_max_docking=0.0)
    with pytest.raises(ValueError, match="needs a goal"):
        se3topp(free_space())


# --------------------------------------------------------------------------- tracking
def available_controllers():
    """Every controller with a config option in conf/controller/ (impedance, hqp, se3_lie, …)."""
    return sorted(p.stem for p in (Path(CONF_DIR) / "controller").glob("*.yaml"))


#: the research code's iiwa14 geometry (now the default scene): start 0.18 m before the
#: seat, standoff 0.10 m, goal at the seat: se3topp 1.3 + 5.4 s, twophase 10.9 s
RESEARCH_CASE = ("task.stroke=[0.0,0.0,-0.18]",)


#: the planner docks with the default controller in the fast suite, with the other controllers
#: in the nightly suite (`slow`): the plan does not depend on the controller (its durations
#: are checked in the impedance cell), and each other controller docks the default scene in
#: its own fast tests (tests/control/test_hqp.py, test_se3_lie.py)
_OTHER_CONTROLLERS = pytest.mark.slow(reason="the impedance cell proves the se3topp docking")


@pytest.mark.parametrize(
    "controller",
    [c if c == "impedance" else pytest.param(c, marks=_OTHER_CONTROLLERS) for c in available_controllers()],
)
def test_se3topp_docks_on_iiwa14(controller, tmp_path):
    from compliant_docking.run.runner import execute
    from compliant_docking.sim.simulate import prepare

    cfg = make_cfg("trajectory=se3topp", f"controller={controller}", "task.progress=false", *RESEARCH_CASE)
    record = execute(cfg, tmp_path, figures=False, echo=False)
    assert record["status"] == "ok", record["error"]
    assert record["success"] is True, record["gate_failures"]
    assert math.isclose(record["sim_time_s"], 6.7 + 3.0, abs_tol=2e-3)
    twophase = prepare(make_cfg("trajectory=twophase", f"controller={controller}", *RESEARCH_CASE))
    assert math.isclose(twophase.planner.duration, 10.8947, rel_tol=1e-4)
