"""The keyed interface: a regular polygonal plug with a pyramidal chamfer and the matching
polygonal socket with a pyramidal entry funnel, as MjSpec fragments.

Plug frame (as the round plug, :mod:`.plug`): one root body ``dock``, origin at the centre
of the mounting face, +z along the plug axis towards the tip; sites ``sensor_site`` at the
origin and ``tcp`` at the tip centre (0, 0, length). Face k of the prism has its outward
normal at azimuth 2πk/sides from +x. Collision: a convex-mesh prism from the mounting
face to the chamfer edge, meeting only the bore boxes, and a convex-mesh frustum (the
chamfer) meeting only the funnel boxes and the floor, as the round plug's shaft and tip.

Socket frame (as the round socket, :mod:`.socket`): root body ``dock`` at the seat, +z out
of the socket; bore face k faces azimuth 2πk/sides. The bore is the intersection of the
half-spaces behind ``sides`` boxes whose inner faces lie in the planes of the nominal bore
(inradius = plug inradius + clearance), and the funnel likewise with tilted boxes whose
inner faces lie in the planes of the nominal pyramid: the free space is exactly the
nominal one, so the clearance between parallel faces is exactly ``clearance`` and every
contact is a box against a convex mesh.

Mated (tcp = seat turned 180° about x): plug face k lies parallel to bore face −k at the
clearance. Both fragments declare the key (:mod:`.fragment`): symmetry ``sides`` and the
socket's yaw play.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from compliant_docking.config.geometry import ContactParams
from compliant_docking.config.keyed import KeyedPlugGeometry, KeyedSocketGeometry
from compliant_docking.sim.geometry.collision import (
    PLUG_COLLISION_GROUP,
    PLUG_RGBA,
    SHAFT_CONAFFINITY,
    TIP_CONAFFINITY,
    apply_contact,
)
from compliant_docking.sim.geometry.fragment import Key, declare_key
from compliant_docking.sim.geometry.plug import add_visual_and_sites, dock_body, stacked_inertia
from compliant_docking.sim.geometry.socket import Box, box_socket_spec, cavity_boxes


def polygon_ring(inradius: float, z: float, sides: int) -> np.ndarray:
    """(sides, 3) corners at height z of the regular polygon whose face k has its outward
    normal at azimuth 2πk/sides and lies at ``inradius`` from the axis: the corners are
    at azimuths (2k + 1)π/sides, at ``inradius / cos(π/sides)``."""
    angle = (2.0 * np.arange(sides) + 1.0) * np.pi / sides
    radius = inradius / math.cos(math.pi / sides)
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.full(sides, z)])


def polygon_area_coeffs(sides: int) -> tuple[float, float]:
    """(area, polar moment) of the regular ``sides``-gon of inradius 1 about its centre.

    n isosceles triangles of height 1 and half-base t = tan(π/n): area n·t, polar moment
    n·∫₀¹ (2x³t + 2x³t³/3) dx = n·(t/2 + t³/6).
    """
    t = math.tan(math.pi / sides)
    return sides * t, sides * (0.5 * t + t**3 / 6.0)


def keyed_plug_inertia(geom: KeyedPlugGeometry) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass and principal inertia of the keyed plug (uniform solid):
    a regular polygon is isotropic in its plane, so the ``dock`` axes are principal."""
    profile = [
        (0.0, geom.chamfer_start, geom.inradius, geom.inradius),
        (geom.chamfer_start, geom.length, geom.inradius, geom.tip_inradius),
    ]
    return stacked_inertia(profile, *polygon_area_coeffs(geom.sides), geom.mass)


def keyed_plug_vertices(geom: KeyedPlugGeometry, z_start: float = 0.0) -> np.ndarray:
    """Vertices (plug frame) of the plug's convex hull from ``z_start`` to the tip."""
    n = geom.sides
    rings = [
        polygon_ring(geom.inradius, geom.chamfer_start, n),
        polygon_ring(geom.tip_inradius, geom.length, n),
    ]
    if z_start < geom.chamfer_start:
        rings.insert(0, polygon_ring(geom.inradius, z_start, n))
    return np.vstack(rings)


def _plug_key(geom: KeyedPlugGeometry) -> Key:
    return Key(geom.sides, None)


def build_keyed_plug(geom: KeyedPlugGeometry, contact: ContactParams | None) -> mujoco.MjSpec:
    """Keyed plug fragment: root body ``dock`` (mounting face, +z to the tip), sites
    ``sensor_site`` (origin) and ``tcp`` (0, 0, length), explicit inertial from
    :func:`keyed_plug_inertia`, collision prism + chamfer frustum, a visual hull, and the
    key (symmetry ``sides``). ``contact``: as for :func:`~.plug.build_plug` (None:
    MuJoCo's defaults; against the socket its higher-priority values apply)."""
    spec = mujoco.MjSpec()
    spec.modelname = "keyed_plug"
    body = dock_body(spec, *keyed_plug_inertia(geom))

    n, z_edge = geom.sides, geom.chamfer_start
    parts = (
        (
            "plug_shaft",
            np.vstack([polygon_ring(geom.inradius, 0.0, n), polygon_ring(geom.inradius, z_edge, n)]),
        ),
        ("plug_tip", keyed_plug_vertices(geom, z_edge)),
    )
    for (name, vertices), conaffinity in zip(parts, (SHAFT_CONAFFINITY, TIP_CONAFFINITY)):
        spec.add_mesh(name=name, uservert=vertices.ravel().tolist())
        g = body.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=name,
            group=PLUG_COLLISION_GROUP,
            rgba=list(PLUG_RGBA),
        )
        apply_contact(g, contact, 0, conaffinity)
    add_visual_and_sites(spec, body, keyed_plug_vertices(geom), geom.length)
    declare_key(spec, _plug_key(geom))
    return spec


def keyed_socket_boxes(geom: KeyedSocketGeometry) -> list[Box]:
    """The keyed socket's collision boxes (socket frame): ``bore_<k>``, ``funnel_<k>``
    for k < sides and ``floor``; inner faces in the planes of the nominal bore and
    pyramid (see :func:`~compliant_docking.sim.geometry.socket.cavity_boxes`)."""
    return cavity_boxes(
        geom.sides,
        geom.bore_inradius,
        geom.insertion_depth,
        geom.funnel_angle_deg,
        geom.funnel_depth,
        geom.wall_thickness,
        geom.floor_thickness,
    )


def build_keyed_socket(geom: KeyedSocketGeometry, contact: ContactParams) -> mujoco.MjSpec:
    """Keyed socket fragment: static root body ``dock`` at the seat (+z out), the boxes of
    :func:`keyed_socket_boxes`, sites ``seat`` and ``mouth``, and the key (symmetry
    ``sides``, yaw play :attr:`KeyedSocketGeometry.yaw_play_deg`)."""
    spec = box_socket_spec(keyed_socket_boxes(geom), contact, geom.mouth_height)
    spec.modelname = "keyed_socket"
    declare_key(spec, Key(geom.sides, geom.yaw_play_deg))
    return spec
