"""Collision filtering, geom groups and colours shared by the plug and the socket builders.

Socket geoms have ``contype`` = :data:`SOCKET_BORE_BIT` (bore boxes) or
:data:`SOCKET_ENTRY_BIT` (funnel boxes, floor) and ``conaffinity = 0``; plug geoms
have ``contype = 0`` and a ``conaffinity`` naming the socket bits they meet.  So plug
and socket collide with each other and with nothing else: not with themselves, not
with geoms left at MuJoCo's default contype/conaffinity of 1, not with visual-only
geoms (contype = conaffinity = 0).  Geom groups: visual-only :data:`VISUAL_GROUP`,
plug collision :data:`PLUG_COLLISION_GROUP`, socket :data:`SOCKET_GROUP` (its boxes
are drawn semi-transparent so the insertion can be seen).
"""

from __future__ import annotations

import mujoco

from compliant_docking.config.geometry import ContactParams

SOCKET_BORE_BIT = 1 << 1
"""contype of the socket's bore boxes."""

SOCKET_ENTRY_BIT = 1 << 2
"""contype of the socket's funnel boxes and floor box."""

SHAFT_CONAFFINITY = SOCKET_BORE_BIT
"""conaffinity of the plug's shaft: it meets the bore walls only."""

TIP_CONAFFINITY = SOCKET_ENTRY_BIT
"""conaffinity of the default plug's chamfer frustum: funnel and floor only."""

ALL_SOCKET_BITS = SOCKET_BORE_BIT | SOCKET_ENTRY_BIT
"""conaffinity of plug geoms that meet every socket piece."""

VISUAL_GROUP = 2
PLUG_COLLISION_GROUP = 3
SOCKET_GROUP = 0

#: geom priority of the socket pieces (the plug's geoms keep 0)
SOCKET_PRIORITY = 1

PLUG_RGBA = (0.45, 0.55, 0.70, 1.0)
SOCKET_RGBA = (0.90, 0.55, 0.20, 0.35)

PLUG_COLLISION_MODELS = ("cylinder_tip", "capsule_tip", "mesh")
VISUAL_SEGMENTS = 64


def apply_contact(
    geom: mujoco.MjsGeom, contact: ContactParams | None, contype: int, conaffinity: int
) -> None:
    """Write the contact parameters (None: leave MuJoCo's defaults) and the collision bits
    on a collision geom, which adds no mass."""
    geom.contype = contype
    geom.conaffinity = conaffinity
    geom.density = 0.0
    if contact is None:
        return
    geom.condim = contact.condim
    geom.friction = list(contact.friction)
    geom.solref = list(contact.solref)
    geom.solimp = list(contact.solimp)
    geom.margin = contact.margin
