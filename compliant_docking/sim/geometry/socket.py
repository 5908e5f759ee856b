"""The parametric socket: a cylindrical bore below a conical entry funnel, as an MjSpec fragment.

Frame: ``worldbody`` holds one root body ``dock`` without a joint (the assembler fixes
it to the world; its geoms have zero density, so the body is massless and must stay
static).  Its origin is the SEAT, the centre of the bottom of the cylindrical bore,
where the plug tip rests when fully inserted.  +z points out of the socket, towards the
approaching plug, so the plug moves along -z of this frame while inserting.  Sites:
``seat`` at the origin and ``mouth`` at ``(0, 0, insertion_depth + funnel_depth)``.

Collision model: the socket cavity is an intersection of half-spaces.  Each of the
``sectors`` bore pieces is a box whose inner face lies in a plane TANGENT to the bore
cylinder (a circumscribed polygon: inscribed radius = bore radius), and each funnel
piece is a tilted box whose inner face lies in the plane tangent to the funnel cone
along one of its generators.  Every box lies entirely behind its own tangent plane, so
no piece intrudes into the nominal free space: the radial clearance is never below
``radial_clearance``; it grows to ``bore_radius * (1 / cos(pi / sectors) - 1)`` more at
the polygon corners (0.20 mm extra for 16 sectors, 0.37 mm for 12 at the defaults).
Boxes overlap freely behind their faces.  Each funnel box starts exactly on the circle
where the cone meets the bore (its lower end face is perpendicular to the generator),
so funnel and bore meet without a lip or a gap.  A floor box closes the bore; its top
face is the seat plane z = 0.

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
from compliant_docking.sim.geometry.collision import (
    SOCKET_BORE_BIT,
    SOCKET_ENTRY_BIT,
    SOCKET_GROUP,
    SOCKET_PRIORITY,
    SOCKET_RGBA,
    apply_contact,
)


@dataclass(frozen=True)
class Box:
    """One socket piece in the socket frame: centre [m], orientation (w, x, y, z) and
    half-sizes [m].  Local x is the outward normal of the inner face (the face at
    local x = -half_size[0]); local z runs along the bore axis or funnel generator."""

    name: str
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]
    half_size: tuple[float, float, float]


def _frame_quat(x_axis: np.ndarray, y_axis: np.ndarray, z_axis: np.ndarray) -> tuple:
    """Quaternion of the rotation whose columns are the given orthonormal axes."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([x_axis, y_axis, z_axis]).ravel())
    return tuple(float(q) for q in quat)


def _as_tuple(v: np.ndarray) -> tuple:
    return tuple(float(x) for x in v)


def socket_boxes(geom: SocketGeometry) -> list[Box]:
    """The socket's collision boxes, socket frame (origin at the seat, +z out).

    Bore box k faces azimuth 2*pi*k/sectors; its inner face lies in the plane tangent
    to the bore cylinder, from z = 0 to z = insertion_depth.  Funnel box k has its inner
    face in the plane tangent to the funnel cone along the generator at the same
    azimuth, from the bore/funnel circle up to the mouth.  Face half-widths cover the
    polygon edges (each face reaches its neighbours' planes), so the walls are closed.
    """
    return cavity_boxes(
        geom.sectors,
        geom.bore_radius,
        geom.insertion_depth,
        geom.funnel_angle_deg,
        geom.funnel_depth,
        geom.wall_thickness,
        geom.floor_thickness,
    )


def cavity_boxes(
    sectors: int,
    bore_inradius: float,
    depth: float,
    funnel_angle_deg: float,
    funnel_depth: float,
    wall_thickness: float,
    floor_thickness: float,
) -> list[Box]:
    """Boxes bounding a ``sectors``-gon bore of inradius ``bore_inradius`` (faces at
    azimuths 2*pi*k/sectors, z from 0 to ``depth``) below a pyramidal funnel whose faces
    lean out by ``funnel_angle_deg`` up to ``depth + funnel_depth``, and a floor box
    whose top face is z = 0.  Every box lies behind the plane of its inner face, so the
    free space is exactly the intersection of those half-spaces (see the module doc).
    """
    n = sectors
    rb, t = bore_inradius, wall_thickness
    alpha = math.radians(funnel_angle_deg)
    generator_length = funnel_depth / math.cos(alpha)
    mouth = rb + funnel_depth * math.tan(alpha)
    half_width_bore = (rb + t) * math.tan(math.pi / n)
    half_width_funnel = (mouth + t) * math.tan(math.pi / n)
    up = np.array([0.0, 0.0, 1.0])
    bores, funnels = [], []
    for k in range(n):
        phi = 2.0 * math.pi * k / n
        radial = np.array([math.cos(phi), math.sin(phi), 0.0])
        tangent = np.array([-math.sin(phi), math.cos(phi), 0.0])
        bores.append(
            Box(
                name=f"bore_{k}",
                pos=_as_tuple((rb + 0.5 * t) * radial + 0.5 * depth * up),
                quat=_frame_quat(radial, tangent, up),
                half_size=(0.5 * t, half_width_bore, 0.5 * depth),
            )
        )
        normal = math.cos(alpha) * radial - math.sin(alpha) * up  # out of the cavity
        generator = math.sin(alpha) * radial + math.cos(alpha) * up  # up the funnel wall
        base = rb * radial + depth * up  # on the bore circle
        funnels.append(
            Box(
                name=f"funnel_{k}",
                pos=_as_tuple(base + 0.5 * generator_length * generator + 0.5 * t * normal),
                quat=_frame_quat(normal, tangent, generator),
                half_size=(0.5 * t, half_width_funnel, 0.5 * generator_length),
            )
        )
    floor_half = (rb + t) / math.cos(math.pi / n)  # reaches the outer polygon corners
    floor = Box(
        name="floor",
        pos=(0.0, 0.0, -0.5 * floor_thickness),
        quat=(1.0, 0.0, 0.0, 0.0),
        half_size=(floor_half, floor_half, 0.5 * floor_thickness),
    )
    return bores + funnels + [floor]


def build_socket(geom: SocketGeometry, contact: ContactParams) -> mujoco.MjSpec:
    """Socket fragment: static root body ``dock``, origin at the seat, +z out of the socket.

    Geoms: ``bore_<k>`` and ``funnel_<k>`` for k < sectors and ``floor`` (see
    :func:`socket_boxes`), drawn semi-transparent.  Sites ``seat`` (origin) and
    ``mouth`` (0, 0, insertion_depth + funnel_depth).
    """
    return box_socket_spec(socket_boxes(geom), contact, geom.mouth_height)


def box_socket_spec(boxes: list[Box], contact: ContactParams, mouth_height: float) -> mujoco.MjSpec:
    """A socket fragment made of ``boxes`` (names ``bore_*`` meet the plug's shaft, the
    others its tip), with the sites ``seat`` at the origin and ``mouth`` at
    (0, 0, mouth_height)."""
    spec = mujoco.MjSpec()
    spec.modelname = "socket"
    body = spec.worldbody.add_body(name="dock")
    for box in boxes:
        g = body.add_geom(
            name=box.name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=list(box.pos),
            quat=list(box.quat),
            size=list(box.half_size),
            group=SOCKET_GROUP,
            rgba=list(SOCKET_RGBA),
        )
        bit = SOCKET_BORE_BIT if box.name.startswith("bore_") else SOCKET_ENTRY_BIT
        apply_contact(g, contact, bit, 0)
        # The socket's contact parameters govern every plug/socket contact (MuJoCo uses
        # the parameters of the geom with the higher priority instead of mixing them).
        g.priority = SOCKET_PRIORITY
    body.add_site(name="seat", pos=[0.0, 0.0, 0.0])
    body.add_site(name="mouth", pos=[0.0, 0.0, mouth_height])
    return spec
