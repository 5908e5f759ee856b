"""Physics checks of the parametric plug/socket (compliant_docking.sim.geometry)."""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from compliant_docking.config.geometry import check_fit
from compliant_docking.config.store import default_interface
from compliant_docking.sim.compliance_rig import (
    Push,
    Support,
    interface_rig,
    measured_free_radius,
    push_insertion,
)
from compliant_docking.sim.geometry import (
    build_plug,
    build_socket,
    plug_hull_vertices,
    plug_inertia,
)

#: the default interface of conf/ (tool=cone_plug, target=cone_socket)
PLUG, SOCKET, CONTACT = default_interface()


def insert(plug, socket, *, offset=0.0, push=5.0):
    """One push-driven insertion in the compliance rig with benchmarks/contact_geometry.py's
    carrier: a weak wrist (100 N/m, 0.5 N·m/rad) through the mounting face, the tip 2 mm
    above the mouth and ``offset`` along +x, pushed with ``push`` newtons at up to 50 mm/s."""
    support = Support(100.0, 10.0, 0.5, 0.02, compliance_height=plug.length)
    rig = interface_rig(
        plug, socket, replace(CONTACT), support=support, drive=Push(push, 0.05), offset=offset
    )
    return push_insertion(rig)


def _quat_rotate(quat, vec):
    out = np.zeros(3)
    mujoco.mju_rotVecQuat(out, np.asarray(vec, float), np.asarray(quat, float))
    return out


# --------------------------------------------------------------------------- frames
def _arm_with_parts():
    """A one-link 'arm' with the plug on its attachment site and the socket on a frame."""
    plug, socket = replace(PLUG), replace(SOCKET)
    arm = mujoco.MjSpec()
    link = arm.worldbody.add_body(name="link", pos=[0.1, 0.2, 0.5])
    link.add_joint(name="j", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    link.add_geom(name="link_geom", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.2, 0, 0])
    flange_quat = np.array([math.cos(0.3), math.sin(0.3), 0.0, 0.0])
    site = link.add_site(name="attachment_site", pos=[0.0, 0.0, 0.05], quat=flange_quat.tolist())
    site.attach_body(build_plug(plug, replace(CONTACT)).body("dock"), prefix="tool_")
    target_pos = np.array([0.6, -0.1, 0.2])
    target_quat = np.array([math.cos(0.2), 0.0, math.sin(0.2), 0.0])
    arm.worldbody.add_frame(pos=target_pos.tolist(), quat=target_quat.tolist()).attach_body(
        build_socket(socket, replace(CONTACT)).body("dock"), prefix="target_"
    )
    model = arm.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return plug, socket, model, data, flange_quat, target_pos, target_quat


def test_fragments_have_one_dock_body_and_documented_sites():
    plug, socket = replace(PLUG), replace(SOCKET)
    for spec in (build_plug(plug, replace(CONTACT)), build_socket(socket, replace(CONTACT))):
        roots = [b.name for b in spec.worldbody.bodies]
        assert roots == ["dock"]
        assert not spec.body("dock").joints
    model = build_plug(plug, replace(CONTACT)).compile()
    np.testing.assert_allclose(model.site("sensor_site").pos, 0.0, atol=1e-12)
    np.testing.assert_allclose(model.site("sensor_site").quat, [1, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(model.site("tcp").pos, [0, 0, plug.length], atol=1e-12)
    model = build_socket(socket, replace(CONTACT)).compile()
    np.testing.assert_allclose(model.site("seat").pos, 0.0, atol=1e-12)
    np.testing.assert_allclose(model.site("mouth").pos, [0, 0, 0.045], atol=1e-12)


def test_attach_places_sites_where_documented():
    plug, socket, model, data, flange_quat, target_pos, target_quat = _arm_with_parts()
    # every mesh was renamed with its fragment's prefix (no name clash between the parts)
    assert all(model.mesh(i).name.startswith(("tool_", "target_")) for i in range(model.nmesh))
    flange = data.site_xpos[model.site("attachment_site").id]
    np.testing.assert_allclose(data.site_xpos[model.site("tool_sensor_site").id], flange, atol=1e-12)
    np.testing.assert_allclose(
        data.site_xmat[model.site("tool_sensor_site").id],
        data.site_xmat[model.site("attachment_site").id],
        atol=1e-12,
    )
    link_quat = data.xquat[model.body("link").id]
    world_flange_quat = np.zeros(4)
    mujoco.mju_mulQuat(world_flange_quat, link_quat, flange_quat)
    expected_tcp = flange + _quat_rotate(world_flange_quat, [0, 0, plug.length])
    np.testing.assert_allclose(data.site_xpos[model.site("tool_tcp").id], expected_tcp, atol=1e-12)
    np.testing.assert_allclose(data.site_xpos[model.site("target_seat").id], target_pos, atol=1e-12)
    expected_mouth = target_pos + _quat_rotate(target_quat, [0, 0, socket.mouth_height])
    np.testing.assert_allclose(data.site_xpos[model.site("target_mouth").id], expected_mouth, atol=1e-12)


def test_plug_and_socket_ignore_default_collision_geoms():
    """The arm's sphere (contype = conaffinity = 1) overlaps the plug: no contact."""
    *_, model, data, _, _, _ = _arm_with_parts()
    mujoco.mj_collision(model, data)
    link_geom = model.geom("link_geom").id
    touching = {(data.contact.geom1[i], data.contact.geom2[i]) for i in range(data.ncon)}
    assert all(link_geom not in pair for pair in touching)
    plug_geoms = [i for i in range(model.ngeom) if model.geom(i).name.startswith("tool_")]
    dist = mujoco.mj_geomDistance(model, data, link_geom, plug_geoms[0], 1.0, None)
    assert dist < 0.0, "the test needs the sphere to overlap the plug"


# -------------------------------------------------------------------------- clearance
@pytest.mark.parametrize("sectors", [12, 16])
def test_bore_free_radius_never_below_nominal(sectors):
    socket = replace(SOCKET, sectors=sectors)
    for z in (0.002, 0.015, 0.028):
        lowest, highest = measured_free_radius(socket, CONTACT, z)
        assert lowest >= socket.bore_radius - 1e-9
        assert lowest == pytest.approx(socket.bore_radius, abs=1e-7)
        assert highest == pytest.approx(socket.bore_radius / math.cos(math.pi / sectors), abs=2e-6)


@pytest.mark.parametrize("sectors", [12, 16])
def test_plug_sized_cylinder_fits_with_nominal_clearance(sectors):
    """A plug-radius cylinder offset by just under the clearance, in any direction, touches
    no wall piece; offset just past the clearance towards a face, it penetrates."""
    socket = replace(SOCKET, sectors=sectors)
    spec = build_socket(socket, replace(CONTACT))
    probe_body = spec.worldbody.add_body(name="probe", mocap=True)
    probe_body.add_geom(
        name="probe",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[socket.plug_radius, 0.012, 0],
        pos=[0, 0, 0.015],
    )
    model = spec.compile()
    data = mujoco.MjData(model)
    probe = model.geom("probe").id
    bores = [model.geom(f"wall_{k}").id for k in range(sectors)]

    def min_distance(offset, azimuth):
        data.mocap_pos[0] = [offset * math.cos(azimuth), offset * math.sin(azimuth), 0.0]
        mujoco.mj_forward(model, data)
        return min(mujoco.mj_geomDistance(model, data, probe, b, 0.01, None) for b in bores)

    c = socket.radial_clearance
    for azimuth in np.linspace(0.0, 2.0 * math.pi, 90, endpoint=False):
        assert min_distance(c - 2e-6, azimuth) > 0.0
    assert min_distance(c + 2e-5, 0.0) < 0.0  # towards the centre of face 0


def test_funnel_radius_and_mouth_match_formula():
    socket = replace(SOCKET)
    slope = math.tan(math.radians(socket.funnel_angle_deg))
    assert socket.mouth_radius == pytest.approx(socket.bore_radius + socket.funnel_depth * slope)
    heights = np.array([0.031, 0.038, 0.0445])
    measured = [measured_free_radius(socket, CONTACT, z) for z in heights]
    lowest = np.array([lo for lo, _ in measured])
    np.testing.assert_allclose(lowest, [socket.free_radius(z) for z in heights], atol=1e-7)
    corner = np.array([hi for _, hi in measured])  # walls closed up to the polygon corners
    np.testing.assert_allclose(corner, lowest / math.cos(math.pi / socket.sectors), atol=2e-6)
    fit_slope, fit_intercept = np.polyfit(heights, lowest, 1)
    assert fit_slope == pytest.approx(slope, rel=1e-5)
    assert fit_slope * socket.mouth_height + fit_intercept == pytest.approx(socket.mouth_radius, abs=1e-7)


def test_funnel_meets_bore_without_lip_or_gap():
    """Just below and just above the bore/funnel circle the free radius is continuous
    (no lip) and every ray hits a wall (no gap)."""
    socket = replace(SOCKET)
    for dz in (-1e-5, 1e-5):
        z = socket.insertion_depth + dz
        lowest, _ = measured_free_radius(socket, CONTACT, z)  # raises if a ray escapes
        assert lowest == pytest.approx(socket.free_radius(z), abs=1e-8)
        assert lowest >= socket.bore_radius - 1e-9


def test_bore_is_closed_at_the_seat():
    socket = replace(SOCKET)
    model = build_socket(socket, replace(CONTACT)).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geomid = np.zeros(1, dtype=np.int32)
    start = np.array([0.003, -0.002, socket.mouth_height])
    dist = mujoco.mj_ray(model, data, start, np.array([0.0, 0.0, -1.0]), None, 1, -1, geomid)
    assert dist == pytest.approx(socket.mouth_height, abs=1e-9)
    assert model.geom(geomid[0]).name == "floor"


# --------------------------------------------------------------------------- insertion
@pytest.mark.parametrize("offset, sectors", [(0.0, 16), (0.003, 16), (0.003, 12)])
def test_plug_seats_in_rig(offset, sectors):
    result = insert(replace(PLUG), replace(SOCKET, sectors=sectors), offset=offset)
    assert result.seated and not result.jammed
    assert result.seat_time < 2.0
    assert abs(result.final_tip_height) < 1e-4
    assert -result.steady_contact_dist < 20e-6  # 5 N on the seat: a few micrometres


def test_seated_penetration_stays_small_at_30_newton():
    """Contact softness against the scale that matters, the 0.4 mm clearance: pressed with
    30 N the plug sinks less than a fifth of it; striking the seat at the rig's 50 mm/s
    (over twice the planners' fastest approach) less than 60 %. (The 5 ms time constant
    gives ~53 µm and ~200 µm; the earlier 2 ms gave ~9 µm and ~75 µm but resolved impacts
    within one step, see ContactParams.)"""
    result = insert(replace(PLUG), replace(SOCKET), offset=0.003, push=30.0)
    clearance = replace(SOCKET).radial_clearance
    assert result.seated
    assert -result.steady_contact_dist < 0.2 * clearance
    assert -result.min_contact_dist < 0.6 * clearance  # impact


def test_oversized_plug_does_not_seat():
    """Negative control for the rig: a plug wider than the bore must stop at the bore."""
    plug = replace(PLUG, radius=0.0106)
    result = insert(plug, replace(SOCKET))
    assert not result.seated
    assert result.final_tip_height > 0.025


# -------------------------------------------------------------------------- validation
@pytest.mark.parametrize(
    "make, setting",
    [
        (lambda: replace(SOCKET, radial_clearance=-0.0001), "radial_clearance"),
        (lambda: replace(SOCKET, radial_clearance=0.0), "radial_clearance"),
        (lambda: replace(SOCKET, funnel_angle_deg=0.0), "funnel_angle_deg"),
        (lambda: replace(SOCKET, funnel_angle_deg=85.0), "funnel_angle_deg"),
        (lambda: replace(SOCKET, sectors=6), "sectors"),
        (lambda: replace(SOCKET, insertion_depth=-0.01), "insertion_depth"),
        (lambda: replace(PLUG, chamfer_length=0.02), "chamfer_length"),
        (lambda: replace(PLUG, chamfer_angle_deg=80.0), "chamfer_angle_deg"),
        (lambda: replace(PLUG, radius=0.0), "radius"),
        (lambda: replace(PLUG, segments=4), "segments"),
        (lambda: replace(CONTACT, solref=(-0.002, 1.0)), "solref"),
        (lambda: replace(CONTACT, condim=2), "condim"),
        (lambda: check_fit(replace(PLUG, radius=0.011), replace(SOCKET)), "PlugGeometry.radius"),
        (lambda: check_fit(replace(PLUG, length=0.02), replace(SOCKET)), "PlugGeometry.length"),
    ],
)
def test_bad_parameters_raise_value_error_naming_the_setting(make, setting):
    with pytest.raises(ValueError, match=setting):
        make()


def test_fit_check_boundaries():
    """The default pair fits; the plug radius may approach the bore radius (plug radius +
    clearance) but not reach it, and the plug must be longer than the bore is deep."""
    check_fit(replace(PLUG), replace(SOCKET))  # raises if not
    bore, depth = SOCKET.bore_radius, SOCKET.insertion_depth
    assert bore == pytest.approx(SOCKET.plug_radius + SOCKET.radial_clearance, rel=1e-12)
    check_fit(replace(PLUG, radius=bore * (1.0 - 1e-9)), replace(SOCKET))
    with pytest.raises(ValueError, match="PlugGeometry.radius"):
        check_fit(replace(PLUG, radius=bore), replace(SOCKET))
    check_fit(replace(PLUG, length=depth * (1.0 + 1e-9)), replace(SOCKET))
    with pytest.raises(ValueError, match="PlugGeometry.length"):
        check_fit(replace(PLUG, length=depth), replace(SOCKET))


# ----------------------------------------------------------------------------- inertia
def test_plug_inertia_of_a_plain_cylinder_is_the_closed_form_and_mujoco_compiles_it():
    """With a vanishing chamfer (1e-9°) the plug is a solid cylinder of radius r and length L:
    centre of mass at L/2, inertia m(3r² + L²)/12 across and m r²/2 along the axis. The
    compiled dock body carries exactly that (no inertia from the collision geoms)."""
    plug = replace(PLUG, chamfer_angle_deg=1e-9)
    m, r, L = plug.mass, plug.radius, plug.length
    mass, com, inertia = plug_inertia(plug)
    assert mass == m
    np.testing.assert_allclose(com, [0.0, 0.0, L / 2], rtol=0, atol=1e-13)
    # 1e-13 m, 1e-12: Gauss-Legendre is exact on these polynomials, 1e-9° of chamfer moves
    # the centre of mass by ~1e-14 m
    np.testing.assert_allclose(inertia, [m * (3 * r * r + L * L) / 12] * 2 + [m * r * r / 2], rtol=1e-12)
    body = build_plug(plug, replace(CONTACT)).compile().body("dock")
    assert body.mass[0] == pytest.approx(m, rel=1e-12)
    np.testing.assert_allclose(body.ipos, com, atol=1e-15)
    np.testing.assert_allclose(body.inertia, inertia, rtol=1e-12)
    np.testing.assert_allclose(body.iquat, [1, 0, 0, 0], atol=1e-12)


def test_plug_inertia_matches_mujoco_mesh_inertia():
    """Independent check: MuJoCo's own inertia of a fine hull of the plug, same mass."""
    plug = replace(PLUG, chamfer_length=0.008)  # a long chamfer makes the cone matter
    spec = mujoco.MjSpec()
    spec.add_mesh(name="hull", uservert=plug_hull_vertices(plug, 256).ravel().tolist())
    body = spec.worldbody.add_body(name="plug")
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="hull", mass=plug.mass)
    model = spec.compile()
    mass, com, inertia = plug_inertia(plug)
    compiled = model.body("plug")
    assert compiled.mass[0] == pytest.approx(mass, rel=1e-9)
    np.testing.assert_allclose(compiled.ipos, com, atol=2e-6)
    np.testing.assert_allclose(np.sort(compiled.inertia), np.sort(inertia), rtol=2e-3)
