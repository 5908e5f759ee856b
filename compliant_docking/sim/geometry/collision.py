"""Collision bits, geom groups and colours shared by the plug and the socket builders.

Socket geoms have ``contype`` = :data:`SOCKET_BIT` and ``conaffinity = 0``; plug geoms
have ``contype = 0`` and ``conaffinity`` = :data:`SOCKET_BIT`.  So every plug piece may
touch every socket piece, and plug and socket collide with nothing else: not with
themselves, not with geoms left at MuJoCo's default contype/conaffinity of 1, not with
visual-only geoms (contype = conaffinity = 0).  There is deliberately no finer pair
filter: a filter that hides some socket pieces from some plug pieces exposes faces that
lie inside the solid socket (docs/contact.md).  Geom groups: visual-only
:data:`VISUAL_GROUP`, plug collision :data:`PLUG_COLLISION_GROUP`, socket
:data:`SOCKET_GROUP` (its pieces are drawn semi-transparent so the insertion can be seen).
"""

from __future__ import annotations

import mujoco

from compliant_docking.config.geometry import ContactParams

SOCKET_BIT = 1 << 1
"""contype of every socket collision geom, and conaffinity of every plug collision geom."""

VISUAL_GROUP = 2
PLUG_COLLISION_GROUP = 3
SOCKET_GROUP = 0

#: geom priority of the socket pieces (the plug's geoms keep 0)
SOCKET_PRIORITY = 1

PLUG_RGBA = (0.45, 0.55, 0.70, 1.0)
SOCKET_RGBA = (0.90, 0.55, 0.20, 0.35)

VISUAL_SEGMENTS = 64


def make_plug_collider(geom: mujoco.MjsGeom, contact: ContactParams | None) -> None:
    """A plug collision geom: meets every socket piece, adds no mass; ``contact`` as for
    :func:`apply_contact`."""
    apply_contact(geom, contact, 0, SOCKET_BIT)


def make_socket_collider(geom: mujoco.MjsGeom, contact: ContactParams | None) -> None:
    """A socket collision geom: meets every plug piece, adds no mass, and its contact
    parameters govern every plug/socket contact (MuJoCo uses the parameters of the geom
    with the higher priority instead of mixing them)."""
    apply_contact(geom, contact, SOCKET_BIT, 0)
    geom.priority = SOCKET_PRIORITY


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
