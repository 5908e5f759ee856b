"""Planners twophase, se3topp and tracking: timing laws, limits, geodesics, finite
differences of the world and body references, C² joints, table = sample, configs, and
end-to-end docking with se3topp."""

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from omegaconf import OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.control import lie
from compliant_docking.planning.base import Reference, Waypoints
from compliant_docking.planning.se3topp import (
    Limits,
    SE3ToppPlanner,
    bang_bang,
    bang_bang_time,
    screw_profile,
    world_to_body,
)
from compliant_docking.planning.tracking import TrackingPlanner
from compliant_docking.planning.twophase import TwoPhasePlanner, quintic_segment_time
from tests.helpers import make_cfg

AXIS = np.array([0.0, 0.0, -1.0])
DOWN = np.diag([1.0, -1.0, -1.0])  # plug pointing down (z along −world z)


def docking(ahead=0.18, rot_goal=None, lateral=(0.0, 0.0)):
    """Start `ahead` metres before the goal along −z (plus a lateral offset)."""
    goal = pin.SE3(DOWN if rot_goal is None else rot_goal, np.array([0.55, 0.0, 0.20]))
    start = pin.SE3(DOWN, goal.translation + np.array([*lateral, ahead]))
    return Waypoints(start=start, goal=goal, axis=AXIS)


def free_space():
    return Waypoints(start=pin.SE3(DOWN, np.array([0.55, 0.0, 0.45])), goal=None, axis=AXIS)


def fd_check(traj, t, h=1e-6):
    """Max errors of the world twist/accel against central differences of pose/twist."""
    ref, lo, hi = traj.table(t), traj.table(t - h), traj.table(t + h)
    dp = (hi.pos - lo.pos) / (2 * h)
    omega = np.array([pin.log3(a @ b.T) for a, b in zip(hi.rot, lo.rot)]) / (2 * h)
    dtw = (hi.twist - lo.twist) / (2 * h)
    return (
        np.abs(dp - ref.twist[:, :3]).max(),
        np.abs(omega - ref.twist[:, 3:]).max(),
        np.abs(dtw - ref.accel).max(),
    )


def away_from(t, instants, margin):
    return np.all(np.abs(t[:, None] - np.asarray(instants)[None, :]) > margin, axis=1)


def switch_times(traj):
    """Segment boundaries and ramp ends of an SE3ToppPlanner."""
    out = []
    for sc in traj._screws:
        t_acc = sc.v_p / sc.a_s
        out += [sc.t0, sc.t0 + t_acc, sc.t0 + sc.T - t_acc, sc.t0 + sc.T]
    return out


# --------------------------------------------------------------------------- twophase
def test_twophase_segment_times_follow_the_formula():
    traj = TwoPhasePlanner(docking(0.18), standoff=0.10)
    (n1, a0, a1), (n2, d0, d1) = traj.segments
    assert (n1, n2) == ("approach", "docking") and a0 == 0.0 and a1 == d0
    # approach 0.08 m at 0.10 m/s, 0.20 m/s²: max(1.5, √(5.7735·0.4)) = 1.5197 s (acceleration-bound)
    assert math.isclose(
        a1, max(1.875 * 0.08 / 0.10, math.sqrt(10 / math.sqrt(3) * 0.08 / 0.20)), rel_tol=1e-12
    )
    assert math.isclose(a1, 1.519671, rel_tol=1e-6)
    # docking 0.10 m at 0.02 m/s, 0.05 m/s²: 9.375 s (speed-bound)
    assert math.isclose(d1 - d0, 9.375, rel_tol=1e-12)
    assert math.isclose(traj.duration, 10.894671, rel_tol=1e-6)  # the research code's 10.9 s


@pytest.mark.parametrize("ahead", [0.18, 0.25])
def test_twophase_respects_its_limits_and_one_is_active(ahead):
    traj = TwoPhasePlanner(docking(ahead), standoff=0.10)
    limits = {"approach": (0.10, 0.20), "docking": (0.02, 0.05)}
    for name, t0, t1 in traj.segments:
        t = np.linspace(t0, t1, 20001)[:-1]
        tab = traj.table(t)
        speed = np.linalg.norm(tab.twist[:, :3], axis=1).max()
        accel = np.linalg.norm(tab.accel[:, :3], axis=1).max()
        v, a = limits[name]
        assert speed <= v * (1 + 1e-9) and accel <= a * (1 + 1e-6)
        assert max(speed / v, accel / a) > 0.999  # the shortest quintic within the limits


def test_twophase_passes_the_pre_dock_point_at_rest():
    wp = docking(0.18, lateral=(0.01, -0.02))
    traj = TwoPhasePlanner(wp, standoff=0.10)
    ref = Reference()
    _, _, t_pre = traj.segments[0]
    traj.sample(t_pre, ref)
    assert np.allclose(ref.pos, wp.goal.translation - 0.10 * AXIS, atol=1e-12)
    assert np.allclose(ref.twist, 0.0, atol=1e-12)
    traj.sample(traj.duration + 1.0, ref)
    assert np.allclose(ref.pos, wp.goal.translation, atol=1e-12) and np.allclose(ref.twist, 0.0)


def test_twophase_without_approach_when_the_start_is_within_the_standoff():
    traj = TwoPhasePlanner(docking(0.08), standoff=0.10)
    assert [s[0] for s in traj.segments] == ["docking"]
    assert math.isclose(traj.duration, quintic_segment_time(0.08, 0.02, 0.05))
    assert traj.notes and "within the standoff" in traj.notes[0]


def test_twophase_fd_and_orientation_interpolation():
    rot_goal = DOWN @ pin.rpy.rpyToMatrix(0.2, -0.1, 0.3)
    traj = TwoPhasePlanner(docking(0.18, rot_goal=rot_goal), standoff=0.10)
    t = np.linspace(0.01, traj.duration - 0.01, 3001)
    e_v, e_w, e_a = fd_check(traj, t)
    assert e_v < 1e-8 and e_w < 1e-8 and e_a < 1e-7
    end = traj.table(np.array([traj.duration]))
    assert np.allclose(end.rot[0], rot_goal, atol=1e-12)


def test_twophase_needs_a_goal():
    with pytest.raises(ValueError, match="needs a goal"):
        TwoPhasePlanner(free_space())


# --------------------------------------------------------------------------- se3topp
def test_bang_bang_time_triangle_and_trapezoid():
    assert math.isclose(bang_bang_time(v_s=5.0, a_s=10.0), 2 / math.sqrt(10.0))  # √a ≤ v
    assert math.isclose(bang_bang_time(v_s=0.2, a_s=0.5), 1 / 0.2 + 0.2 / 0.5)  # 5.4 s


def test_se3topp_reproduces_the_research_case_and_beats_twophase():
    wp = docking(0.18)
    topp, two = SE3ToppPlanner(wp, standoff=0.10), TwoPhasePlanner(wp, standoff=0.10)
    (_, _, t1), (_, _, t2) = topp.segments
    assert math.isclose(t1, 1.3, rel_tol=1e-9) and math.isclose(t2 - t1, 5.4, rel_tol=1e-9)
    assert [p["shape"] for p in topp.profiles()] == ["trapezoid", "trapezoid"]
    assert topp.duration < two.duration


def test_se3topp_triangle_when_the_segment_is_short():
    traj = SE3ToppPlanner(docking(0.12), standoff=0.10)  # approach 0.02 m
    approach = traj.profiles()[0]
    # s-units: v_s = 0.1/0.02 = 5, a_s = 0.2/0.02 = 10, √10 ≤ 5: triangle of 2/√10 s
    assert approach["shape"] == "triangle"
    assert math.isclose(approach["T"], 2 / math.sqrt(10.0), rel_tol=1e-12)
    t = np.linspace(0, approach["T"], 10001)
    speed = np.linalg.norm(traj.table(t).twist[:, :3], axis=1)
    assert math.isclose(speed.max(), 0.02 * math.sqrt(10.0), rel_tol=1e-3)  # peak √a_s·L < v_max


def rotating_case(angle=math.pi / 2):
    """Approach with a rotation about an axis NOT along the translation (centripetal term)."""
    # about an axis that the start rotation moves: world and body angular velocity differ
    rot_goal = DOWN @ pin.exp3(angle * np.array([0.6, 0.8, 0.0]))
    return docking(0.18, rot_goal=rot_goal, lateral=(0.03, -0.02))


def coupled_case():
    """A 90° turn with a large lateral move and loose angular limits: the centripetal part
    of the linear acceleration binds (approach limits v, a, ω, α = 0.10, 0.05, 5, 5)."""
    rot_goal = DOWN @ pin.exp3(np.array([0.0, math.pi / 2, 0.0]))
    wp = docking(0.18, rot_goal=rot_goal, lateral=(0.3, 0.0))
    return wp, dict(a_max_approach=0.05, omega_max_approach=5.0, alpha_max_approach=5.0)


@pytest.mark.parametrize("case", ["translation", "screw", "coupled"])
def test_se3topp_limits_hold_along_the_whole_profile(case):
    lims = {"approach": (0.10, 0.20, 0.20, 0.20), "docking": (0.02, 0.05, 0.05, 0.05)}
    if case == "coupled":
        wp, kwargs = coupled_case()
        lims["approach"] = (0.10, 0.05, 5.0, 5.0)
    else:
        wp, kwargs = (docking(0.18) if case == "translation" else rotating_case(math.radians(60))), {}
    traj = SE3ToppPlanner(wp, standoff=0.10, **kwargs)
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


def test_screw_profile_with_a_centripetal_term_keeps_the_linear_acceleration():
    xi = np.array([0.3, 0.0, 0.1, 0.0, 1.2, 0.0])  # ξ_ω × ξ_v ≠ 0
    lim = Limits(v=0.5, a=0.3, omega=5.0, alpha=5.0)
    v_p, a_s = screw_profile(xi, lim)
    b, c = np.linalg.norm(xi[:3]), np.linalg.norm(np.cross(xi[3:], xi[:3]))
    assert b**2 * a_s**2 + c**2 * v_p**4 <= lim.a**2 * (1 + 1e-9)
    assert v_p <= math.sqrt(a_s) * (1 + 1e-12)
    # the chosen profile is at least as fast as any feasible peak on a grid
    T = bang_bang_time(v_p, a_s) if v_p < math.sqrt(a_s) else 2 / math.sqrt(a_s)
    for v in np.linspace(1e-3, v_p * 1.5, 400):
        room = lim.a**2 - (c * v * v) ** 2
        if room <= 0:
            continue
        a = min(lim.alpha / np.linalg.norm(xi[3:]), math.sqrt(room) / b)
        if v * v <= a and v <= lim.v / b:
            assert 1 / v + v / a >= T * (1 - 1e-6)


def test_se3topp_rest_to_rest_at_every_waypoint():
    wp = rotating_case()
    traj = SE3ToppPlanner(wp, standoff=0.10)
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
    traj = SE3ToppPlanner(wp, standoff=0.10)
    name, t0, t1 = traj.segments[0]
    mid = traj.table(np.array([0.5 * (t0 + t1)]))
    rel = wp.start.rotation.T @ mid.rot[0]
    assert math.isclose(np.linalg.norm(pin.log3(rel)), math.pi / 4, abs_tol=1e-12)  # 90° → 45°
    # the pose is T_a·Exp(ξ/2), the midpoint of the constant-screw motion
    xi = traj.profiles()[0]["xi"]
    half = lie.se3_from_rp(wp.start.rotation, wp.start.translation) @ lie.exp6(0.5 * xi)
    assert np.allclose(mid.pos[0], half[:3, 3], atol=1e-12)
    assert np.allclose(mid.rot[0], half[:3, :3], atol=1e-12)
    # …and it is a screw: the position is not the straight-line midpoint
    straight = 0.5 * (wp.start.translation + wp.goal.translation - 0.10 * AXIS)
    assert np.linalg.norm(mid.pos[0] - straight) > 1e-3


def test_se3topp_screw_pose_matches_exp6():
    wp = rotating_case(1.0)
    traj = SE3ToppPlanner(wp, standoff=0.10)
    sc = traj._screws[0]
    s = np.linspace(0.0, 1.0, 11)
    from compliant_docking.planning.se3topp import screw_pose

    rot, pos = screw_pose(sc.rot_a, sc.pos_a, sc.xi, s)
    Ta = lie.se3_from_rp(sc.rot_a, sc.pos_a)
    for k, sk in enumerate(s):
        T = Ta @ lie.exp6(sk * sc.xi)
        assert np.allclose(rot[k], T[:3, :3], atol=1e-13) and np.allclose(pos[k], T[:3, 3], atol=1e-13)


@pytest.mark.parametrize("case", ["translation", "screw", "coupled"])
def test_se3topp_world_twist_and_accel_are_derivatives(case):
    if case == "coupled":
        wp, kwargs = coupled_case()
        traj = SE3ToppPlanner(wp, standoff=0.10, **kwargs)
    else:
        traj = SE3ToppPlanner(docking(0.18) if case == "translation" else rotating_case(), standoff=0.10)
    t = np.linspace(0.0, traj.duration, 4001)
    t = t[away_from(t, switch_times(traj), 1e-4)]
    e_v, e_w, e_a = fd_check(traj, t)
    assert e_v < 1e-8 and e_w < 1e-8 and e_a < 1e-7, (e_v, e_w, e_a)


def test_se3topp_body_twist_and_its_derivative():
    """World → body conversion V_b = [Rᵀẋ; Rᵀω], V̇_b = [Rᵀẍ − ω_b × v_b; Rᵀω̇] agrees with
    finite differences of the pose (log6(T(t−h)⁻¹T(t+h))/2h) and of V_b, and with ξ ṡ, ξ s̈."""
    traj = SE3ToppPlanner(rotating_case(), standoff=0.10)
    t = np.linspace(0.0, traj.duration, 1501)
    t = t[away_from(t, switch_times(traj), 1e-4)]
    h = 1e-6
    ref, lo, hi = traj.table(t), traj.table(t - h), traj.table(t + h)
    Vb, dVb = world_to_body(ref.rot, ref.twist, ref.accel)
    Vb_lo, _ = world_to_body(lo.rot, lo.twist, lo.accel)
    Vb_hi, _ = world_to_body(hi.rot, hi.twist, hi.accel)
    fd_twist = np.array(
        [lie.log6_rp(Rl.T @ Rh, Rl.T @ (ph - pl)) for Rl, Rh, pl, ph in zip(lo.rot, hi.rot, lo.pos, hi.pos)]
    ) / (2 * h)
    assert np.abs(fd_twist - Vb).max() < 1e-8
    assert np.abs((Vb_hi - Vb_lo) / (2 * h) - dVb).max() < 1e-7
    # on a constant-screw segment V_b = ξ ṡ and V̇_b = ξ s̈
    sc = traj._screws[0]
    k = t < sc.T
    _, ds, dds = bang_bang(t[k], sc.v_p, sc.a_s, sc.T)
    assert np.allclose(Vb[k], np.outer(ds, sc.xi), atol=1e-12)
    assert np.allclose(dVb[k], np.outer(dds, sc.xi), atol=1e-12)


def test_se3topp_rejects_bad_limits_and_free_space():
    with pytest.raises(ValueError, match="omega_max_docking"):
        SE3ToppPlanner(docking(), omega_max_docking=0.0)
    with pytest.raises(ValueError, match="needs a goal"):
        SE3ToppPlanner(free_space())


# --------------------------------------------------------------------------- tracking
def test_tracking_segments_and_geometry():
    wp = free_space()
    traj = TrackingPlanner(wp)
    names = [s[0] for s in traj.segments]
    assert names == ["transition_1", "circle", "transition_2", "figure8"]
    bounds = [(s[1], s[2]) for s in traj.segments]
    assert np.allclose(bounds, [(0, 1.5), (1.5, 6.5), (6.5, 8.0), (8.0, 13.0)])
    assert traj.duration == 13.0
    p0 = wp.start.translation
    circle = traj.table(np.linspace(1.5, 6.5, 2001))
    centre = p0 + np.array([0.0, 0.0, -0.06])
    assert np.allclose(np.linalg.norm(circle.pos - centre, axis=1), 0.10, atol=1e-12)
    assert np.allclose(circle.pos[:, 0], p0[0])  # vertical circle in the y-z plane
    assert np.isclose(circle.pos[:, 1].max(), p0[1] + 0.10, atol=1e-6)
    eight = traj.table(np.linspace(8.0, 13.0, 20001))
    assert np.allclose(eight.pos[:, 2], p0[2])  # horizontal
    assert np.isclose(np.abs(eight.pos[:, 0] - p0[0]).max(), 0.10, atol=1e-6)
    assert np.isclose(np.abs(eight.pos[:, 1] - p0[1]).max(), 0.07, atol=1e-6)
    assert np.allclose(traj.table(np.array([13.0, 20.0])).pos, p0, atol=1e-12)  # ends at the start
    assert np.allclose(traj.table(np.linspace(0, 20, 50)).rot, wp.start.rotation)  # orientation held


def test_tracking_is_c2_across_segment_joints():
    traj = TrackingPlanner(free_space())
    eps = 1e-7
    for _, _, t_end in traj.segments:
        tab = traj.table(np.array([t_end - eps, t_end, t_end + eps]))
        for block, tol in ((tab.pos, 1e-9), (tab.twist, 1e-6), (tab.accel, 1e-5)):
            assert np.abs(block[0] - block[1]).max() < tol and np.abs(block[2] - block[1]).max() < tol
        assert np.allclose(tab.twist[1], 0.0, atol=1e-12) and np.allclose(tab.accel[1], 0.0, atol=1e-12)


def test_tracking_twist_and_accel_are_derivatives():
    traj = TrackingPlanner(free_space())
    t = np.linspace(0.0, 15.0, 6001)
    e_v, e_w, e_a = fd_check(traj, t)
    assert e_v < 1e-8 and e_w < 1e-9 and e_a < 1e-6


def test_tracking_refuses_a_target():
    with pytest.raises(ValueError, match="target=none"):
        TrackingPlanner(docking())


# --------------------------------------------------------------------------- all planners
@pytest.mark.parametrize(
    "make",
    [
        lambda: TwoPhasePlanner(docking(0.18)),
        lambda: SE3ToppPlanner(rotating_case()),
        lambda: TrackingPlanner(free_space()),
    ],
    ids=["twophase", "se3topp", "tracking"],
)
def test_table_equals_sample(make):
    traj = make()
    t = np.concatenate([[-1.0, 0.0], np.linspace(0.0, traj.duration + 1.0, 37), [traj.duration]])
    table, ref = traj.table(t), Reference()
    for k, tk in enumerate(t):
        traj.sample(float(tk), ref)
        assert np.array_equal(table.pos[k], ref.pos) and np.array_equal(table.rot[k], ref.rot)
        assert np.array_equal(table.twist[k], ref.twist) and np.array_equal(table.accel[k], ref.accel)


# --------------------------------------------------------------------------- configs
@pytest.mark.parametrize("planner", ["twophase", "se3topp", "tracking"])
def test_config_defaults_match_the_schema_and_unknown_keys_are_rejected(planner):
    cfg = make_cfg(f"trajectory={planner}")
    node = OmegaConf.to_container(cfg.trajectory)
    assert node["name"] == planner
    with pytest.raises(Exception, match="bogus"):
        make_cfg(f"trajectory={planner}", "trajectory.bogus=1")


def test_planned_durations_on_the_default_scene():
    from compliant_docking.sim.simulate import prepare

    two = prepare(make_cfg("trajectory=twophase")).planner
    topp = prepare(make_cfg("trajectory=se3topp")).planner
    # the default scene is the research code's iiwa14 case: start 0.18 m before the seat,
    # goal at the seat (the press past it comes after the motion), standoff 0.10 m:
    # approach 0.08 m, docking 0.10 m → twophase 1.52 + 9.375 s, se3topp 1.3 + 5.4 s
    assert math.isclose(two.duration, 1.52 + 9.375, rel_tol=1e-3)
    # approach in s-units: v = 0.1/0.08 = 1.25, a = 0.2/0.08 = 2.5, √a > v: trapezoid 1/v + v/a
    assert math.isclose(topp.duration, (1 / 1.25 + 1.25 / 2.5) + 5.4, rel_tol=1e-9)
    assert topp.duration < two.duration


# --------------------------------------------------------------------------- end to end
def available_controllers():
    """Every controller with a config option in conf/controller/ (impedance, hqp, se3_lie, …)."""
    return sorted(p.stem for p in (Path(CONF_DIR) / "controller").glob("*.yaml"))


#: the research code's iiwa14 geometry (now the default scene): start 0.18 m before the
#: seat, standoff 0.10 m, goal at the seat: se3topp 1.3 + 5.4 s, twophase 10.9 s
RESEARCH_CASE = ("task.stroke=[0.0,0.0,-0.18]",)


@pytest.mark.parametrize("controller", available_controllers())
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
