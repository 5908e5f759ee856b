"""The keyed interface: a regular polygonal plug with a pyramidal chamfer and the matching
polygonal socket with a pyramidal entry funnel, as MjSpec fragments.

Plug frame (as the round plug, :mod:`.plug`): one root body ``dock``, origin at the centre
of the mounting face, +z along the plug axis towards the tip; sites ``sensor_site`` at the
origin and ``tcp`` at the tip centre (0, 0, length). Face k of the prism has its outward
normal at azimuth 2πk/sides from +x. Collision: one convex mesh, the plug's convex hull
(prism and pyramidal chamfer), meeting every socket piece, as the round plug's.

Socket frame (as the round socket, :mod:`.socket`): root body ``dock`` at the seat, +z out
of the socket; bore face k faces azimuth 2πk/sides. The block is built as the round
socket's (:func:`~.socket.cavity_pieces`): wall piece k is the convex solid behind bore
face k (the plane of the nominal bore, inradius = plug inradius + clearance) and behind
funnel face k (the plane of the nominal pyramid), on a floor slab. The free space is
exactly the nominal one, so the clearance between parallel faces is exactly
``clearance``, and every contact is between two convex meshes.

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
from compliant_docking.sim.geometry.fragment import Key, declare_key
from compliant_docking.sim.geometry.plug import (
    add_hull_collider,
    add_visual_and_sites,
    dock_body,
    stacked_inertia,
)
from compliant_docking.sim.geometry.socket import Piece, cavity_pieces, piece_socket_spec


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


def keyed_plug_vertices(geom: KeyedPlugGeometry) -> np.ndarray:
    """Vertices (plug frame) of the plug's convex hull: the polygon at the mounting face,
    at the chamfer edge and at the tip face."""
    n = geom.sides
    return np.vstack(
        [
            polygon_ring(geom.inradius, 0.0, n),
            polygon_ring(geom.inradius, geom.chamfer_start, n),
            polygon_ring(geom.tip_inradius, geom.length, n),
        ]
    )


def _plug_key(geom: KeyedPlugGeometry) -> Key:
    return Key(geom.sides, None)


def build_keyed_plug(geom: KeyedPlugGeometry, contact: ContactParams | None) -> mujoco.MjSpec:
    """Keyed plug fragment: root body ``dock`` (mounting face, +z to the tip), sites
    ``sensor_site`` (origin) and ``tcp`` (0, 0, length), explicit inertial from
    :func:`keyed_plug_inertia`, the convex hull as its collision geom ``plug_hull`` and as
    its visual, and the key (symmetry ``sides``). ``contact``: as for :func:`~.plug.build_plug` (None:
    MuJoCo's defaults; against the socket its higher-priority values apply)."""
    spec = mujoco.MjSpec()
    spec.modelname = "keyed_plug"
    body = dock_body(spec, *keyed_plug_inertia(geom))

    hull = keyed_plug_vertices(geom)
    add_hull_collider(spec, body, "plug_hull", hull, contact)
    add_visual_and_sites(spec, body, hull, geom.length)
    declare_key(spec, _plug_key(geom))
    return spec


def keyed_socket_pieces(geom: KeyedSocketGeometry) -> list[Piece]:
    """The keyed socket's convex pieces (socket frame): ``wall_<k>`` for k < sides and
    ``floor``; inner faces in the planes of the nominal bore and pyramid (see
    :func:`~compliant_docking.sim.geometry.socket.cavity_pieces`)."""
    return cavity_pieces(
        geom.sides,
        geom.bore_inradius,
        geom.insertion_depth,
        geom.funnel_angle_deg,
        geom.funnel_depth,
        geom.wall_thickness,
        geom.floor_thickness,
    )


def build_keyed_socket(geom: KeyedSocketGeometry, contact: ContactParams) -> mujoco.MjSpec:
    """Keyed socket fragment: static root body ``dock`` at the seat (+z out), the pieces of
    :func:`keyed_socket_pieces`, sites ``seat`` and ``mouth``, and the key (symmetry
    ``sides``, yaw play :attr:`KeyedSocketGeometry.yaw_play_deg`)."""
    spec = piece_socket_spec(keyed_socket_pieces(geom), contact, geom.mouth_height)
    spec.modelname = "keyed_socket"
    declare_key(spec, Key(geom.sides, geom.yaw_play_deg))
    return spec
