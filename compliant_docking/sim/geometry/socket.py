"""The parametric socket: a cylindrical bore below a conical entry funnel, as an MjSpec fragment.

Frame: ``worldbody`` holds one root body ``dock`` without a joint (the assembler fixes
it to the world; its geoms have zero density, so the body is massless and must stay
static).  Its origin is the SEAT, the centre of the bottom of the cylindrical bore,
where the plug tip rests when fully inserted.  +z points out of the socket, towards the
approaching plug, so the plug moves along -z of this frame while inserting.  Sites:
``seat`` at the origin and ``mouth`` at ``(0, 0, insertion_depth + funnel_depth)``.

Collision model: the socket is a solid block with a cavity, built from convex pieces
whose every face that can be touched is a face of that solid.  The cavity is a regular
``sectors``-gon bore circumscribing the bore circle (face k at azimuth 2*pi*k/sectors,
inscribed radius = bore radius) below a pyramid circumscribing the funnel cone.  Wall
piece k is the solid behind bore face k AND behind funnel face k: one convex polyhedron
whose inner surface is the bore face, the lip edge where bore and funnel meet (a convex
edge of the solid, so it belongs to one piece and is never split) and the funnel face.
Its sides reach past the polygon corners into the neighbouring pieces, which bury them
(more than 0.3 mm deep at the defaults, against contact penetrations of micrometres).
Below the seat plane every wall piece reaches down through the floor slab (a box), whose
top face is the seat plane z = 0.  No piece intrudes into the nominal free space: the radial
clearance is never below ``radial_clearance``; it grows to ``bore_radius * (1 / cos(pi /
sectors) - 1)`` more at the polygon corners (0.20 mm extra for 16 sectors).

Why not simpler pieces: a box per bore face and a tilted box per funnel face (the first
model) leaves each bore box's top face just under the funnel boxes, buried by a depth
that vanishes at the lip, and each funnel box's lower end face just inside the bore box;
contacts found there point up (a ledge the solid does not have) or down into the socket
(docs/contact.md has the audit).

Contact parameters: :class:`~compliant_docking.config.geometry.ContactParams` is
written on every plug and socket collision geom.  Note for MuJoCo 4.0.0: a contact's
margin is the SUM of both geoms' margins and acts as a contact offset (the constraint
pushes the surfaces apart to that distance), and the geom ``gap`` attribute had no
measurable effect, so any margin directly eats clearance; the default margin is 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from compliant_docking.config.geometry import ContactParams, SocketGeometry
from compliant_docking.sim.geometry.collision import SOCKET_GROUP, SOCKET_RGBA, make_socket_collider


@dataclass(frozen=True)
class Piece:
    """One convex socket piece: its name and the vertices [m] of the convex polyhedron,
    socket frame (MuJoCo collides the convex hull of a mesh's vertices). ``box``: the
    piece is the axis-aligned box its vertices span, built as a box primitive (whose
    support function is analytic: cheaper to collide than a mesh)."""

    name: str
    vertices: tuple[tuple[float, float, float], ...]
    box: bool = False


def _rotate_z(points: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _as_piece(name: str, points: np.ndarray, box: bool = False) -> Piece:
    return Piece(name, tuple((float(x), float(y), float(z)) for x, y, z in points), box)


def socket_pieces(geom: SocketGeometry) -> list[Piece]:
    """The socket's convex pieces, socket frame (origin at the seat, +z out): ``wall_<k>``
    for k < sectors and ``floor`` (see :func:`cavity_pieces`)."""
    return cavity_pieces(
        geom.sectors,
        geom.bore_radius,
        geom.insertion_depth,
        geom.funnel_angle_deg,
        geom.funnel_depth,
        geom.wall_thickness,
        geom.floor_thickness,
    )


def cavity_pieces(
    sectors: int,
    bore_inradius: float,
    depth: float,
    funnel_angle_deg: float,
    funnel_depth: float,
    wall_thickness: float,
    floor_thickness: float,
) -> list[Piece]:
    """Convex pieces of a block holding a ``sectors``-gon bore of inradius
    ``bore_inradius`` (faces at azimuths 2*pi*k/sectors, z from 0 to ``depth``) below a
    pyramidal funnel whose faces lean out by ``funnel_angle_deg`` up to the mouth at
    ``depth + funnel_depth``.

    Wall piece ``wall_<k>``, in the frame of face k (x along the face's outward normal,
    y along the face, z up), is the prism over the profile (x, z): (r_b, -f), (r_b,
    depth), (r_m, mouth), (r_m + t, mouth), (r_m + t, -f) with r_b the bore inradius, r_m
    the funnel's inradius at the mouth, t = ``wall_thickness`` and f =
    ``floor_thickness``, from y = -w to w with w = (r_m + t) tan(pi/sectors): the solid
    behind both of face k's planes, wide enough to close the walls at the mouth.
    ``floor``: the square slab -f <= z <= 0, |x|, |y| <= r_m + t, under the block (a box:
    it costs less to collide than a mesh; the seat is its top face inside the bore).
    """
    n = sectors
    rb, t, f = bore_inradius, wall_thickness, floor_thickness
    mouth = depth + funnel_depth
    rm = rb + funnel_depth * math.tan(math.radians(funnel_angle_deg))
    w = (rm + t) * math.tan(math.pi / n)
    profile = ((rb, -f), (rb, depth), (rm, mouth), (rm + t, mouth), (rm + t, -f))
    prism = np.array([(x, y, z) for x, z in profile for y in (-w, w)])
    pieces = [_as_piece(f"wall_{k}", _rotate_z(prism, 2.0 * math.pi * k / n)) for k in range(n)]
    a = rm + t  # the square circumscribing the block's inscribed circle
    slab = np.array([(x, y, z) for x in (-a, a) for y in (-a, a) for z in (-f, 0.0)])
    return pieces + [_as_piece("floor", slab, box=True)]


def build_socket(geom: SocketGeometry, contact: ContactParams) -> mujoco.MjSpec:
    """Socket fragment: static root body ``dock``, origin at the seat, +z out of the socket.

    Geoms: convex meshes ``wall_<k>`` for k < sectors and ``floor`` (see
    :func:`socket_pieces`), drawn semi-transparent.  Sites ``seat`` (origin) and
    ``mouth`` (0, 0, insertion_depth + funnel_depth).
    """
    return piece_socket_spec(socket_pieces(geom), contact, geom.mouth_height)


def piece_socket_spec(pieces: list[Piece], contact: ContactParams, mouth_height: float) -> mujoco.MjSpec:
    """A socket fragment made of convex ``pieces``, each a mesh geom (a box primitive for a
    ``box`` piece) meeting every plug piece, with the sites ``seat`` at the origin and
    ``mouth`` at (0, 0, mouth_height)."""
    spec = mujoco.MjSpec()
    spec.modelname = "socket"
    body = spec.worldbody.add_body(name="dock")
    for piece in pieces:
        if piece.box:
            low, high = np.min(piece.vertices, axis=0), np.max(piece.vertices, axis=0)
            g = body.add_geom(
                name=piece.name,
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=(0.5 * (low + high)).tolist(),
                size=(0.5 * (high - low)).tolist(),
                group=SOCKET_GROUP,
                rgba=list(SOCKET_RGBA),
            )
        else:
            spec.add_mesh(name=piece.name, uservert=np.ravel(piece.vertices).tolist())
            g = body.add_geom(
                name=piece.name,
                type=mujoco.mjtGeom.mjGEOM_MESH,
                meshname=piece.name,
                group=SOCKET_GROUP,
                rgba=list(SOCKET_RGBA),
            )
        make_socket_collider(g, contact)
    body.add_site(name="seat", pos=[0.0, 0.0, 0.0])
    body.add_site(name="mouth", pos=[0.0, 0.0, mouth_height])
    return spec
