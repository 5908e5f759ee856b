"""Contact-normal audit of a docking interface: do the contacts MuJoCo finds between the
plug and the socket point the way the solid socket's surface does?

A collision model built from pieces can invent contact features the solid does not have:
a face of one piece buried inside another (a "ledge" under the funnel), or a collider
that returns a reversed normal. Forces and success flags hide them; contact normals do
not. The audit poses the plug (free, no dynamics) over a grid of poses at the mouth, on
the funnel and in the bore, finds the pose where it just touches, presses it a few
micrometres deeper (a soft contact's penetration), and compares every contact normal
(socket → plug) with the **normal cone** of the reference solid at the contact point:
the normals of every face of the solid's surface within ``radius`` of the point (one
normal on a face, the fan between two faces at an edge). A contact is sound when its
normal lies within a few degrees of that cone; a normal with more upward component than
the cone allows is a ledge the solid does not have.

Two approaches are swept, because they find different defects: **lateral** (at a fixed
height, the plug moves sideways until it touches a wall) and **vertical** (at a fixed
lateral offset, it descends until it touches the funnel, the lip or the floor).

The reference solid is the cavity's surface: :func:`cavity_surface` for the parametric
sockets (the polygonal bore and pyramid their pieces bound, not the round design: a
16-gon face is 11° off the round bore at its edges), :func:`mesh_surface` for a socket
from CAD (the part's own triangles). Frames: the socket frame (seat at the origin, +z out
of the opening), plug axis nominally along −z.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.optimize import nnls

#: how deep the plug is pressed past first touch: a soft contact's penetration [m]
PENETRATIONS = (20e-6, 60e-6)
#: faces of the reference within this distance of a contact point (+ its depth) span
#: the point's normal cone [m]
CONE_RADIUS = 0.2e-3


@dataclass(frozen=True)
class Surface:
    """The reference solid's surface: triangles ``(n, 3, 3)`` [m] and their unit normals
    ``(n, 3)`` pointing out of the solid (into the free space), socket frame."""

    triangles: np.ndarray
    normals: np.ndarray

    def normal_cone(self, point: np.ndarray, radius: float) -> np.ndarray:
        """The normals of the faces within ``radius`` of ``point`` (at least the nearest)."""
        distance = _point_triangle_distances(np.asarray(point, float), self.triangles)
        near = distance <= radius
        if not near.any():
            near = distance == distance.min()
        return self.normals[near]


def mesh_surface(
    vertices: np.ndarray, faces: np.ndarray, offset: Sequence[float] = (0.0, 0.0, 0.0)
) -> Surface:
    """A closed triangle mesh (outward-wound faces) as a reference surface, moved by
    ``offset`` (e.g. minus the seat, to put it in the socket frame)."""
    triangles = np.asarray(vertices, float)[np.asarray(faces)] + np.asarray(offset, float)
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    area = np.linalg.norm(normals, axis=1)
    keep = area > 1e-18
    return Surface(triangles[keep], normals[keep] / area[keep, None])


def cavity_surface(
    sides: int, bore_inradius: float, depth: float, funnel_angle_deg: float, funnel_depth: float
) -> Surface:
    """The surface of a ``sides``-gon bore (face k's normal at azimuth 2πk/sides, inradius
    ``bore_inradius``, from the seat z = 0 to ``depth``) below a pyramidal funnel leaning
    out by ``funnel_angle_deg`` up to ``depth + funnel_depth``, and the seat: the
    cavity the parametric sockets' pieces bound (:func:`~.socket.cavity_pieces`)."""
    alpha = math.radians(funnel_angle_deg)
    mouth = depth + funnel_depth
    rm = bore_inradius + funnel_depth * math.tan(alpha)
    half = math.tan(math.pi / sides)
    up = np.array([0.0, 0.0, 1.0])
    triangles, normals = [], []
    for k in range(sides):
        phi = 2.0 * math.pi * k / sides
        radial = np.array([math.cos(phi), math.sin(phi), 0.0])
        along = np.array([-math.sin(phi), math.cos(phi), 0.0])

        def corner(r: float, z: float, side: float) -> np.ndarray:
            return r * radial + side * r * half * along + z * up

        b0, b1 = corner(bore_inradius, 0.0, -1.0), corner(bore_inradius, 0.0, 1.0)
        l0, l1 = corner(bore_inradius, depth, -1.0), corner(bore_inradius, depth, 1.0)
        m0, m1 = corner(rm, mouth, -1.0), corner(rm, mouth, 1.0)
        bore, funnel = -radial, -math.cos(alpha) * radial + math.sin(alpha) * up
        for triangle, normal in (
            ((b0, b1, l1), bore),
            ((b0, l1, l0), bore),
            ((l0, l1, m1), funnel),
            ((l0, m1, m0), funnel),
            ((np.zeros(3), b1, b0), up),
        ):
            triangles.append(triangle)
            normals.append(normal)
    return Surface(np.array(triangles, float), np.array(normals, float))


def _point_triangle_distances(p: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distance from ``p`` to each triangle (closest point by barycentric regions)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    ab, ac = b - a, c - a
    # project onto each triangle's plane, then clamp to the triangle through its edges
    normal = np.cross(ab, ac)
    n2 = np.einsum("ij,ij->i", normal, normal)
    ap = p - a
    v = np.einsum("ij,ij->i", np.cross(ap, ac), normal) / n2
    w = np.einsum("ij,ij->i", np.cross(ab, ap), normal) / n2
    inside = (v >= 0) & (w >= 0) & (v + w <= 1)
    plane = np.abs(np.einsum("ij,ij->i", ap, normal)) / np.sqrt(n2)
    edges = np.stack(
        [_segment_distance(p, a, b), _segment_distance(p, b, c), _segment_distance(p, c, a)], axis=1
    ).min(axis=1)
    return np.where(inside, plane, edges)


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def angle_to_cone_deg(normal: np.ndarray, cone: np.ndarray) -> float:
    """Angle [deg] between the unit ``normal`` and the convex cone spanned by the rows of
    ``cone`` (0 inside it): the angle to the nearest non-negative combination."""
    weights, _ = nnls(np.asarray(cone, float).T, np.asarray(normal, float))
    nearest = np.asarray(cone, float).T @ weights
    size = np.linalg.norm(nearest)
    if size < 1e-12:
        return 180.0
    return math.degrees(math.acos(float(np.clip(nearest @ normal / size, -1.0, 1.0))))


@dataclass(frozen=True)
class ContactSample:
    """One contact at one audited pose (socket frame)."""

    approach: str  # "lateral" or "vertical"
    tip: tuple[float, float, float]  # the plug tip's position [m]
    tilt_deg: float  # plug axis from −z
    socket_geom: str
    point: tuple[float, float, float]  # MuJoCo's contact point [m]
    normal: tuple[float, float, float]  # unit, from the socket into the plug
    depth: float  # penetration [m] (minus MuJoCo's contact distance)
    angle_deg: float  # from the solid's normal cone at the point
    excess_up: float  # normal's z minus the most upward normal of the cone (> 0: a ledge)


@dataclass(frozen=True)
class Tilt:
    """The plug axis turned ``angle_deg`` from −z, towards azimuth ``towards_deg`` for
    its tip (0: the tip moves towards +x)."""

    angle_deg: float
    towards_deg: float = 0.0

    def quaternion(self) -> np.ndarray:
        """World quaternion of the plug frame (+z from mounting face to tip)."""
        flip = np.array([0.0, 1.0, 0.0, 0.0])  # 180° about x: plug +z → world −z
        towards = math.radians(self.towards_deg)
        axis = np.array([-math.sin(towards), math.cos(towards), 0.0])  # tip towards `towards`
        half = 0.5 * math.radians(self.angle_deg)
        turn = np.r_[math.cos(half), -math.sin(half) * axis]
        out = np.zeros(4)
        mujoco.mju_mulQuat(out, turn, flip)
        return out


class Audit:
    """The plug (free) and the socket (fixed at the world origin) in one collision-only
    model, and the reference surface to judge the contacts by."""

    def __init__(self, tool: mujoco.MjSpec, target: mujoco.MjSpec, plug_length: float, surface: Surface):
        spec = mujoco.MjSpec()
        spec.worldbody.add_frame().attach_body(target.body("dock"), prefix="target_")
        carrier = spec.worldbody.add_body(name="carrier")
        carrier.add_freejoint()
        carrier.add_site(name="mount").attach_body(tool.body("dock"), prefix="tool_")
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.length = plug_length
        self.surface = surface
        names = [self.model.geom(i).name for i in range(self.model.ngeom)]
        self._socket = np.array([name.startswith("target_") for name in names])

    def _place(self, tip: np.ndarray, quat: np.ndarray) -> float:
        """Pose the plug; the deepest contact's distance (+inf without contact)."""
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, quat)
        self.data.qpos[:3] = tip - self.length * rot.reshape(3, 3)[:, 2]
        self.data.qpos[3:7] = quat
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_collision(self.model, self.data)
        n = self.data.ncon
        return float(self.data.contact.dist[:n].min()) if n else math.inf

    def _samples(self, approach: str, tip: np.ndarray, tilt: Tilt) -> list[ContactSample]:
        out = []
        for i in range(self.data.ncon):
            contact = self.data.contact[i]
            normal = np.array(contact.frame[:3])
            if self._socket[contact.geom1]:
                socket_geom, into_plug = contact.geom1, normal  # MuJoCo: normal from geom1 to geom2
            elif self._socket[contact.geom2]:
                socket_geom, into_plug = contact.geom2, -normal
            else:
                continue
            point = np.array(contact.pos)
            cone = self.surface.normal_cone(point, CONE_RADIUS + max(-contact.dist, 0.0))
            out.append(
                ContactSample(
                    approach=approach,
                    tip=_triple(tip),
                    tilt_deg=tilt.angle_deg,
                    socket_geom=self.model.geom(socket_geom).name,
                    point=_triple(point),
                    normal=_triple(into_plug),
                    depth=float(-contact.dist),
                    angle_deg=angle_to_cone_deg(into_plug, cone),
                    excess_up=float(into_plug[2] - cone[:, 2].max()),
                )
            )
        return out

    def _press(self, approach: str, pose, touch: float, step: float, tilt: Tilt) -> list[ContactSample]:
        """From the first-touch parameter ``touch`` move on by ``step`` direction until each
        penetration of :data:`PENETRATIONS` is reached; the contacts there."""
        quat = tilt.quaternion()
        found = []
        for depth in PENETRATIONS:
            free, deep = touch, touch + step
            while self._place(pose(deep), quat) > -depth:
                deep += step
                if abs(deep - touch) > 0.01:
                    break
            for _ in range(40):
                middle = 0.5 * (free + deep)
                if self._place(pose(middle), quat) > -depth:
                    free = middle
                else:
                    deep = middle
            self._place(pose(deep), quat)
            found += self._samples(approach, pose(deep), tilt)
        return found

    def _approach(self, approach: str, pose, reach: float, tilt: Tilt) -> list[ContactSample]:
        """Move the plug along ``pose(s)`` for s from 0 to ``reach`` until it first touches,
        then press (:meth:`_press`); nothing when it touches at s = 0 already or not within
        ``reach``."""
        quat = tilt.quaternion()
        if self._place(pose(0.0), quat) <= 0.0 or self._place(pose(reach), quat) > 0.0:
            return []
        touch = _first_touch(lambda s: self._place(pose(s), quat) <= 0.0, 0.0, reach)
        return self._press(approach, pose, touch, 1e-5, tilt)

    def lateral(
        self,
        heights: Iterable[float],
        azimuths_deg: Iterable[float],
        tilts: Iterable[Tilt],
        reach: float = 0.004,
    ) -> list[ContactSample]:
        """At each tip height, move the plug from the axis towards each azimuth until it
        touches (within ``reach``), then press; poses already touching on the axis are
        skipped (they are the vertical approach's)."""
        found: list[ContactSample] = []
        for h in heights:
            for azimuth in azimuths_deg:
                u = np.array([math.cos(math.radians(azimuth)), math.sin(math.radians(azimuth)), 0.0])
                for tilt in tilts:

                    def pose(e: float, h: float = h, u: np.ndarray = u) -> np.ndarray:
                        return np.array([0.0, 0.0, h]) + e * u

                    found += self._approach("lateral", pose, reach, tilt)
        return found

    def vertical(
        self, offsets: Iterable[float], azimuths_deg: Iterable[float], tilts: Iterable[Tilt], top: float
    ) -> list[ContactSample]:
        """At each lateral offset, lower the plug tip from height ``top`` until it touches,
        then press."""
        found: list[ContactSample] = []
        for e in offsets:
            for azimuth in azimuths_deg:
                u = np.array([math.cos(math.radians(azimuth)), math.sin(math.radians(azimuth)), 0.0])
                for tilt in tilts:

                    def pose(down: float, e: float = e, u: np.ndarray = u) -> np.ndarray:
                        return np.array([0.0, 0.0, top - down]) + e * u

                    found += self._approach("vertical", pose, top + 0.001, tilt)
        return found


def _triple(v: np.ndarray) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])


def _first_touch(touching, free: float, deep: float) -> float:
    """Bisection between a free parameter and a touching one: the first touching one."""
    for _ in range(45):
        middle = 0.5 * (free + deep)
        if touching(middle):
            deep = middle
        else:
            free = middle
    return deep
