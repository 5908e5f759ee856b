"""Closed-form checks of Whitney's quasi-static peg-in-hole theory
(compliant_docking.evaluation.peg_in_hole and .insertion_statics): every part of each
formula is pinned by a limit, a known value or a symmetry."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from compliant_docking.config.store import default_interface
from compliant_docking.evaluation import insertion_statics as statics
from compliant_docking.evaluation.peg_in_hole import (
    PegInHole,
    crossing_force_ratio,
    effective_clearance,
    one_point_force,
    rotational_stiffness_about,
    two_point_engaged_length,
    two_point_tilt,
    wedged,
    wedging_tilt,
)

PLUG, SOCKET, CONTACT = default_interface()
DEG = math.pi / 180.0


def peg(**changes) -> PegInHole:
    """The default interface on the FR3's impedance gains, compliance centre at the tip."""
    base = PegInHole.for_interface(
        PLUG, SOCKET, lateral_stiffness=300.0, angular_stiffness=25.0, compliance_height=0.0, friction=0.3
    )
    return replace(base, **changes)


# ------------------------------------------------------------------ chamfer crossing
def test_crossing_ratio_is_tan_of_wall_angle_plus_friction_angle():
    assert crossing_force_ratio(30 * DEG, 0.0) == pytest.approx(math.tan(30 * DEG), rel=1e-15)
    assert crossing_force_ratio(0.0, 0.3) == pytest.approx(0.3, rel=1e-15)  # a wall: one-point sliding
    for wall, mu in ((30 * DEG, 0.1), (30 * DEG, 0.3), (30 * DEG, 0.6), (45 * DEG, 0.2)):
        expected = (math.tan(wall) + mu) / (1.0 - mu * math.tan(wall))
        assert crossing_force_ratio(wall, mu) == pytest.approx(expected, rel=1e-13)
    # the default interface (30° funnel and chamfer): 0.72 / 1.06 / 1.80 at μ = 0.1 / 0.3 / 0.6
    assert [round(crossing_force_ratio(30 * DEG, mu), 3) for mu in (0.1, 0.3, 0.6)] == [0.719, 1.061, 1.801]


def test_crossing_locks_when_wall_and_friction_angles_reach_ninety_degrees():
    assert crossing_force_ratio(60 * DEG, math.tan(30 * DEG) + 1e-12) == math.inf
    assert crossing_force_ratio(60 * DEG, math.tan(30 * DEG) - 1e-6) > 1e5


# ------------------------------------------------------------------ one-point contact
def test_one_point_force_known_value_and_limits():
    kx, kt, r = 300.0, 25.0, 0.01
    # 300·25·1.6e-3 / (25 + 300·0.1·(0.1 − 0.3·0.01)) = 12 / 27.91
    assert one_point_force(0.002, 0.0004, kx, kt, 0.1, 0.3, r) == pytest.approx(12.0 / 27.91, rel=1e-12)
    # compliance centre at the touching point: the whole lateral spring, whatever K_θ
    for k_t in (0.1, 25.0, 1e6):
        assert one_point_force(0.002, 0.0004, kx, k_t, 0.0, 0.3, r) == pytest.approx(kx * 0.0016, rel=1e-12)
    # a stiff angular spring: the lateral spring again
    assert one_point_force(0.002, 0.0004, kx, 1e12, 0.1, 0.3, r) == pytest.approx(kx * 0.0016, rel=1e-8)
    # friction's moment arm: μ r enters with the lever (L − μ r)
    assert one_point_force(0.002, 0.0004, kx, kt, 0.003, 1.0, 0.003) == pytest.approx(kx * 0.0016, rel=1e-12)
    # linear in the overlap, nothing when the point does not reach the wall
    assert one_point_force(0.0028, 0.0004, kx, kt, 0.1, 0.3, r) == pytest.approx(
        2.0 * one_point_force(0.0016, 0.0004, kx, kt, 0.1, 0.3, r), rel=1e-12
    )
    assert one_point_force(0.0004, 0.0004, kx, kt, 0.1, 0.3, r) == 0.0
    assert one_point_force(0.0001, 0.0004, kx, kt, 0.1, 0.3, r) == 0.0


def test_one_point_force_refuses_a_support_that_lets_the_point_roll_off():
    with pytest.raises(ValueError, match="K_θ"):
        one_point_force(0.002, 0.0004, 300.0, 1e-4, 0.001, 0.3, 0.01)  # 1e-4 + 300·0.001·(0.001 − 0.003) < 0


# ------------------------------------------------------------------ two-point contact
def test_two_point_geometry_is_exact_and_invertible():
    big_r, r = 0.0104, 0.010
    for tilt in (0.5 * DEG, 2 * DEG, 5 * DEG, 10 * DEG):  # the first root: tan θ < l / d
        length = two_point_engaged_length(big_r, r, tilt)
        assert length * math.sin(tilt) + 2 * r * math.cos(tilt) == pytest.approx(2 * big_r, rel=1e-14)
        assert two_point_tilt(big_r, r, length) == pytest.approx(tilt, rel=1e-10)
    # small angles: θ ≈ (D − d)/l
    assert two_point_tilt(big_r, r, 1.0) == pytest.approx(0.0008, rel=1e-3)
    assert two_point_engaged_length(big_r, r, 0.0) == math.inf
    assert two_point_engaged_length(big_r, r, 2 * DEG) == pytest.approx(
        0.0233, abs=1e-4
    )  # MEASUREMENTS: 23 mm
    with pytest.raises(ValueError, match="engaged_length"):
        two_point_tilt(big_r, r, 0.001)  # shorter than √(D² − d²): cannot touch both sides


def test_wedging_condition_and_its_tilt():
    assert wedged(0.0119, 0.010, 0.6) and not wedged(0.0120, 0.010, 0.6)  # l < μ d, d = 20 mm
    big_r, r = 0.0104, 0.010
    for mu in (0.3, 0.6, 1.0):
        tilt = wedging_tilt(big_r, r, mu)
        assert two_point_engaged_length(big_r, r, tilt) == pytest.approx(mu * 2 * r, rel=1e-10)
    assert wedging_tilt(big_r, r, 0.1) == math.inf  # D > d √(1 + μ²): never
    # small clearance: Whitney's c/μ ≈ (R − r)/(μ r)
    assert wedging_tilt(0.010001, r, 0.5) == pytest.approx(0.000001 / (0.5 * r), rel=1e-2)
    assert peg(friction=0.6).wedging_tilt == pytest.approx(wedging_tilt(0.0104, 0.010, 0.6), rel=1e-12)


def test_rotational_stiffness_about_a_point_below_the_compliance_centre():
    assert rotational_stiffness_about(0.0, 300.0, 25.0) == 25.0
    assert rotational_stiffness_about(0.2, 300.0, 25.0) == pytest.approx(25.0 + 300.0 * 0.04, rel=1e-15)
    assert rotational_stiffness_about(-0.2, 300.0, 25.0) == rotational_stiffness_about(0.2, 300.0, 25.0)


# ------------------------------------------------------------- geometry of the interface
def test_interface_numbers():
    p = peg()
    assert p.clearance == pytest.approx(SOCKET.radial_clearance, rel=1e-12)
    assert p.tip_radius == pytest.approx(PLUG.tip_radius, rel=1e-15)
    assert p.mouth_radius == pytest.approx(SOCKET.mouth_radius, rel=1e-12)
    assert p.chamfer_capture == pytest.approx(0.0004 + 0.003 * math.tan(30 * DEG), rel=1e-12)  # 2.13 mm
    assert p.funnel_capture == pytest.approx(SOCKET.mouth_radius - PLUG.tip_radius, rel=1e-12)  # 10.8 mm
    assert 1e3 * p.funnel_capture == pytest.approx(10.79, abs=0.01)


def test_effective_clearance_of_the_polygons():
    nominal = SOCKET.radial_clearance
    assert effective_clearance(PLUG, SOCKET, 0.0) == pytest.approx(nominal, rel=1e-12)
    step = 2 * math.pi / SOCKET.sectors
    for azimuth in (0.05, 0.1, 0.15):  # symmetric about a face normal, periodic over the faces
        here = effective_clearance(PLUG, SOCKET, azimuth)
        assert effective_clearance(PLUG, SOCKET, -azimuth) == pytest.approx(here, rel=1e-12)
        assert effective_clearance(PLUG, SOCKET, azimuth + step) == pytest.approx(here, rel=1e-12)
        assert here > nominal
    # between two faces the plug meets both (48 = 3 × 16: a plug vertex on every face normal)
    corner = (SOCKET.bore_radius - PLUG.radius) / math.cos(11.25 * DEG)
    assert effective_clearance(PLUG, SOCKET, step / 2) == pytest.approx(corner, rel=1e-12)
    # a 20-gon has no vertex on face 1's normal (22.5°): its support there is r cos 4.5°
    twenty = replace(PLUG, segments=20)
    expected = SOCKET.bore_radius - PLUG.radius * math.cos(4.5 * DEG)
    assert effective_clearance(twenty, SOCKET, step) == pytest.approx(expected, rel=1e-12)
    assert PegInHole.for_interface(
        PLUG,
        SOCKET,
        lateral_stiffness=1,
        angular_stiffness=1,
        compliance_height=0,
        friction=0.3,
        azimuth_deg=11.25,
    ).clearance == pytest.approx(corner, rel=1e-12)


@pytest.mark.parametrize(
    "change, setting",
    [
        (dict(plug_radius=0.0), "plug_radius"),
        (dict(bore_radius=0.009), "bore_radius"),
        (dict(funnel_angle=0.0), "funnel_angle"),
        (dict(chamfer_angle=math.pi / 2), "chamfer_angle"),
        (dict(chamfer_length=0.1), "chamfer_length"),
        (dict(angular_stiffness=0.0), "angular_stiffness"),
        (dict(friction=-0.1), "friction"),
        (dict(tilt=1.0), "tilt"),
        (dict(lateral_error=math.nan), "lateral_error"),
    ],
)
def test_bad_parameters_name_the_setting(change, setting):
    with pytest.raises(ValueError, match=f"PegInHole.{setting}"):
        peg(**change)


# ----------------------------------------------------------------- the insertion curve
DRIVE = np.arange(-0.012, 0.029, 1e-4)


def test_far_above_the_socket_nothing_touches():
    curve = statics.insertion_curve(peg(lateral_error=0.002, tilt=2 * DEG), np.array([-0.014, -0.010]))
    assert curve.phase == [statics.FREE, statics.FREE]
    np.testing.assert_array_equal(curve.insertion_force, 0.0)
    np.testing.assert_allclose(curve.tip_offset, 0.002, rtol=1e-15)


@pytest.mark.parametrize("mu", [0.1, 0.3, 0.6])
def test_crossing_then_one_point_forces_are_the_closed_forms(mu):
    """A lateral error with the compliance centre at the tip: crossing at tan(β + atan μ),
    then one-point contact of the chamfer edge on the wall at μ times
    :func:`one_point_force` (lever: the centre 3 mm BELOW the edge, −h_c)."""
    p = peg(lateral_error=0.002, friction=mu)
    curve = statics.insertion_curve(p, DRIVE)
    phases = np.array(curve.phase)
    crossing = phases == statics.CROSSING
    assert crossing.any()
    ratio = curve.insertion_force[crossing] / -curve.lateral_force[crossing]
    inclined = np.array(
        ["funnel" in c[0] for c, ph in zip(curve.contacts, curve.phase) if ph == statics.CROSSING]
    )
    np.testing.assert_allclose(ratio[inclined], crossing_force_ratio(p.funnel_angle, mu), rtol=1e-12)
    one = (phases == statics.ONE_POINT) & (curve.depth > 0.005)
    f = one_point_force(0.002, p.clearance, 300.0, 25.0, -p.chamfer_length, mu, p.plug_radius)
    np.testing.assert_allclose(-curve.lateral_force[one], f, rtol=1e-5)  # small angles: θ ~ 1e-4 rad
    np.testing.assert_allclose(curve.insertion_force[one], mu * f, rtol=1e-5)
    assert all(c == ("chamfer edge on wall +",) for c, o in zip(curve.contacts, one) if o)


def test_mirrored_errors_mirror_the_curve():
    right = statics.insertion_curve(peg(lateral_error=0.001, tilt=2 * DEG), DRIVE)
    left = statics.insertion_curve(peg(lateral_error=-0.001, tilt=-2 * DEG), DRIVE)
    assert right.phase == left.phase
    np.testing.assert_allclose(left.insertion_force, right.insertion_force, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(left.lateral_force, -right.lateral_force, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(left.tilt, -right.tilt, rtol=1e-9, atol=1e-15)


def test_without_friction_sliding_in_the_bore_costs_nothing():
    curve = statics.insertion_curve(peg(lateral_error=0.002, friction=0.0), DRIVE)
    one = np.array(curve.phase) == statics.ONE_POINT
    np.testing.assert_allclose(curve.insertion_force[one], 0.0, atol=1e-12)


def test_two_point_contact_starts_where_the_rigid_geometry_says():
    """A stiff support keeps the tilt: two-point contact starts when the engaged length
    (chamfer edge to lip, along the axis) is two_point_engaged_length(θ_0); the tip is then
    (h_c + l) cos θ − r sin θ below the lip."""
    tilt = 3 * DEG
    p = peg(tilt=tilt, lateral_stiffness=1e6, angular_stiffness=1e6)
    curve = statics.insertion_curve(p, np.arange(0.0175, 0.0185, 1e-5))
    engaged = two_point_engaged_length(p.bore_radius, p.plug_radius, tilt)
    expected = (p.chamfer_length + engaged) * math.cos(tilt) - p.plug_radius * math.sin(tilt)
    assert curve.onset(statics.TWO_POINT) == pytest.approx(expected, abs=2e-5)
    two = np.array(curve.phase) == statics.TWO_POINT
    assert all(
        set(c) == {"lip on side +", "chamfer edge on wall -"} for c, t in zip(curve.contacts, two) if t
    )


def test_two_point_force_with_the_centre_at_the_tip_is_whitneys_small_angle_form():
    """F_z ≈ 2 μ K_θ (θ_0 − θ) / l in two-point contact (the lateral spring hardly loaded):
    within 5 % at 2° (the neglected terms are the lateral force and the moment arms' r θ)."""
    p = peg(tilt=2 * DEG)
    curve = statics.insertion_curve(p, np.arange(0.026, 0.029, 2e-4))
    two = (np.array(curve.phase) == statics.TWO_POINT) & (
        curve.depth > curve.onset(statics.TWO_POINT) + 0.001
    )
    tilt = curve.tilt[two]  # the lip is level with the plug's axial height (depth + r sin θ) / cos θ
    engaged = (curve.depth[two] + p.plug_radius * np.sin(tilt)) / np.cos(tilt) - p.chamfer_length
    approx = 2 * 0.3 * 25.0 * (p.tilt - curve.tilt[two]) / engaged
    np.testing.assert_allclose(curve.insertion_force[two], approx, rtol=0.05)
    np.testing.assert_allclose(
        tilt, [two_point_tilt(p.bore_radius, p.plug_radius, e) for e in engaged], rtol=1e-9
    )


def test_a_higher_compliance_centre_stiffens_the_two_point_contact():
    forces = []
    for height in (0.0, 0.1, 0.2):
        curve = statics.insertion_curve(peg(tilt=3 * DEG, compliance_height=height), np.array([0.028]))
        assert curve.phase == [statics.TWO_POINT]
        forces.append(float(curve.insertion_force[0]))
    assert forces[0] < forces[1] < forces[2]


def test_wedging_stops_the_theory_only_inside_the_condition():
    wedging = statics.insertion_curve(peg(tilt=5 * DEG, friction=0.6), DRIVE)
    sliding = statics.insertion_curve(peg(tilt=5 * DEG, friction=0.3), DRIVE)
    assert statics.WEDGED in wedging.phase and statics.TWO_POINT not in wedging.phase
    assert statics.TWO_POINT in sliding.phase and statics.WEDGED not in sliding.phase
    start = wedging.onset(statics.WEDGED)
    assert start == pytest.approx(sliding.onset(statics.TWO_POINT), abs=2e-4)
    # engaged length at the wedge below μ d = 12 mm, and the plug goes no deeper
    assert start - 0.003 < 0.012
    after = np.array(wedging.phase) == statics.WEDGED
    assert np.all(np.isinf(wedging.insertion_force[after]))
    assert np.nanmax(wedging.depth) <= start + 1e-12


def test_stall_depth_is_where_the_push_no_longer_suffices():
    curve = statics.insertion_curve(peg(tilt=3 * DEG), np.arange(0.015, 0.029, 1e-4))
    depth = curve.stall_depth(1.0)
    first = int(np.flatnonzero(curve.depth == depth)[0])
    assert curve.insertion_force[first] > 1.0 >= curve.insertion_force[first - 1]
    assert math.isnan(curve.stall_depth(1e3))
