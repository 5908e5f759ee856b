"""The jamming map's theoretical boundaries in closed form, and their frame against the
framework's misalignment (evaluation/map_boundaries.py, docs/jamming_map.md).

Our interface (conf/tool/cone_plug.yaml, conf/target/cone_socket.yaml): r = 10 mm, chamfer
α = 30° over h_c = 3 mm, clearance δ = 0.4 mm, bore H = 30 mm, funnel β = 30° over
h_f = 15 mm, μ = 0.3. By hand: R_m = 10.4 + 15 tan 30° = 19.060 mm, r_t = 10 − 3 tan 30° =
8.268 mm, so the funnel captures c_f = 10.792 mm, the chamfer c_c = 0.4 + 3 tan 30° =
2.132 mm.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

from compliant_docking.config.store import default_interface
from compliant_docking.evaluation.map_boundaries import MapBoundaries
from compliant_docking.sim.misalignment import Misalignment

TAN30 = math.tan(math.radians(30.0))


@pytest.fixture(scope="module")
def interface():
    return default_interface()


@pytest.fixture(scope="module")
def bounds(interface) -> MapBoundaries:
    plug, socket, contact = interface
    return MapBoundaries.for_interface(plug, socket, contact.friction[0])


def test_capture_widths_and_heights_of_our_geometry(bounds):
    assert bounds.funnel_capture_m == pytest.approx(
        0.0104 + 0.015 * TAN30 - (0.010 - 0.003 * TAN30), rel=1e-12
    )
    assert bounds.funnel_capture_m == pytest.approx(10.792e-3, abs=1e-6)
    assert bounds.chamfer_capture_m == pytest.approx(0.0004 + 0.003 * TAN30, rel=1e-12)
    assert (bounds.mouth_height_m, bounds.lip_height_m) == pytest.approx((0.045, 0.030), rel=1e-12)


def test_two_point_tilt_is_where_the_seated_cylinder_touches_both_walls(bounds):
    """At the tilt, the 27 mm of cylinder in the bore (H − h_c) spans the bore exactly:
    l sin θ + d cos θ = D; small angle ≈ (D − d)/l = 0.8/27 rad = 1.70°."""
    theta = math.radians(bounds.two_point_tilt_deg)
    assert 0.027 * math.sin(theta) + 0.020 * math.cos(theta) == pytest.approx(0.0208, rel=1e-12)
    assert bounds.two_point_tilt_deg == pytest.approx(math.degrees(0.8 / 27.0), abs=0.03)


def test_wedging_tilts_exact_and_small_angle(bounds, interface):
    """Exact: D = d (cos θ + μ sin θ) (11.66° at μ = 0.3, docs/peg_in_hole.md's 11.7°); Whitney's
    c/μ = ((D − d)/D)/μ = 7.35°; μ = 0.6: 4.06°; μ = 0: never."""
    theta = math.radians(bounds.wedging_tilt_deg)
    assert 0.020 * (math.cos(theta) + 0.3 * math.sin(theta)) == pytest.approx(0.0208, rel=1e-12)
    assert bounds.wedging_tilt_small_angle_deg == pytest.approx(math.degrees(0.8 / 20.8 / 0.3), rel=1e-12)
    plug, socket, _ = interface
    assert MapBoundaries.for_interface(plug, socket, 0.6).wedging_tilt_deg == pytest.approx(4.06, abs=0.005)
    never = MapBoundaries.for_interface(plug, socket, 0.0)
    assert math.isinf(never.wedging_tilt_deg) and math.isinf(never.wedging_tilt_small_angle_deg)


@pytest.mark.parametrize("tilt", [0.0, 1.0, 2.5, 5.0])
def test_the_limits_put_the_plug_axis_on_the_capture_radius(bounds, tilt):
    """At either limit |x / cos θ + s tan θ| is the capture (funnel at the mouth, chamfer at
    the lip); upright (θ = 0) the limits are ± the capture."""
    theta = math.radians(tilt)
    for (low, high), capture, height in (
        (bounds.funnel_limits(tilt), bounds.funnel_capture_m, 0.045),
        (bounds.chamfer_limits(tilt), bounds.chamfer_capture_m, 0.030),
    ):
        for x in (low, high):
            assert abs(x / math.cos(theta) + height * math.tan(theta)) == pytest.approx(capture, rel=1e-12)
        assert low < high
        if tilt == 0.0:
            assert (low, high) == pytest.approx((-capture, capture), rel=1e-12)


@pytest.mark.parametrize(("x", "tilt"), [(0.004, 3.0), (-0.005, 5.0), (0.0015, 0.5)])
def test_the_map_frame_is_the_misalignment_frame(x, tilt):
    """The preset's socket (seat at x, tilted θ with yaw 90°, sim/misalignment.py) seen from
    the upright plug's axis (x = 0 in the believed frame): at height s above the true seat
    along its axis, the plug's axis is u = −(x / cos θ + s tan θ) off it, the formula the
    limits solve (a tilt leaning away from +x, or −u, gives another number). The yaw turns
    the socket with it: its face at 270° (a face centre of the 16-gon) faces the error."""
    true = Misalignment(x=x, yaw_deg=90.0, tilt_deg=tilt).apply(pin.SE3.Identity())
    for s in (0.030, 0.045):
        # the point of the plug's axis (0, 0, Z) at socket height s: solve along the vertical
        axis_z = true.rotation[:, 2]
        z = (s - (np.zeros(3) - true.translation) @ axis_z) / axis_z[2]
        rel = true.rotation.T @ (np.array([0.0, 0.0, z]) - true.translation)
        assert rel[2] == pytest.approx(s, abs=1e-15)
        theta = math.radians(tilt)
        # the yaw turns the true socket's axes: the believed +x is its −y (its x is out of the plane)
        assert -rel[1] == pytest.approx(-(x / math.cos(theta) + s * math.tan(theta)), rel=1e-12)
        assert rel[0] == pytest.approx(0.0, abs=1e-15)


def test_regions(bounds, interface):
    """Upright and centred: the chamfer; 5 mm off: the funnel; 3°: two-point before the seat;
    11 mm off: missed; μ = 0.6 at 4.5° (over its 4.06°): wedged; a tilt leaning towards the
    offset (x < 0 here) brings a funnel landing onto the chamfer (±2.8 mm at 1.5°: the
    chamfer's limits are [−2.92, 1.35] mm; upright both land on the funnel)."""
    assert bounds.region(0.0, 0.0) == "chamfer"
    assert bounds.region(0.005, 0.0) == "funnel"
    assert bounds.region(0.0, 3.0) == "two-point"
    assert bounds.region(0.011, 0.0) == "missed"
    assert bounds.region(0.0028, 1.5) == "funnel" and bounds.region(-0.0028, 1.5) == "chamfer"
    assert bounds.region(0.0028, 0.0) == "funnel" and bounds.region(-0.0028, 0.0) == "funnel"
    plug, socket, _ = interface
    assert MapBoundaries.for_interface(plug, socket, 0.6).region(0.0, 4.5) == "wedged"
    wider = MapBoundaries.for_interface(plug, replace(socket, funnel_depth=0.025), 0.3)
    assert wider.region(0.011, 0.0) == "funnel"  # a deeper funnel has a wider mouth
