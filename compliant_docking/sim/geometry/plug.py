"""The parametric plug: a cylinder with a conical chamfer at its tip, as an MjSpec fragment.

Frame: ``worldbody`` holds one root body ``dock``.  Its origin is the centre of the
plug's mounting face (where it bolts to the robot flange) and its +z axis is the plug
axis, pointing from the flange towards the tip.  Sites: ``sensor_site`` at the origin
with identity orientation (the force/torque sensor anchor) and ``tcp`` at the tip centre
``(0, 0, length)``.  The body carries an explicit inertial equal to :func:`plug_inertia`;
every geom has zero density and adds no mass.

Collision model: ONE convex mesh, the plug's convex hull (rings of ``segments``
vertices on the circle at the mounting face, the chamfer edge and the tip face), which
meets every socket piece.  The chamfer edge is a convex edge of the solid plug, so it
lies inside one piece and no buried face can be touched.  The polygon's faces lie up to
``radius * (1 - cos(pi / segments))`` inside the circle (21 µm at 48 segments), so the
clearance is never below nominal, and its face normals turn at most 180°/segments from
the round plug's (3.75° at 48).  Two earlier models were dropped after a contact audit
(docs/contact.md): a cylinder primitive for the shaft (MuJoCo's cylinder–convex contacts
came back with normals reversed inside the bore) with a pair filter that hid the funnel
from the shaft (which then rested on buried faces), and a capsule shaft (its end cap
tilted the normals at the bore's mouth).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from compliant_docking.config.geometry import ContactParams, PlugGeometry
from compliant_docking.sim.geometry.collision import (
    PLUG_COLLISION_GROUP,
    PLUG_RGBA,
    VISUAL_GROUP,
    VISUAL_SEGMENTS,
    make_plug_collider,
)


def _plug_profile(geom: PlugGeometry) -> list[tuple[float, float, float, float]]:
    """The plug as (z0, z1, rho0, rho1) segments of linearly varying radius, plug frame."""
    return [
        (0.0, geom.chamfer_start, geom.radius, geom.radius),
        (geom.chamfer_start, geom.length, geom.radius, geom.tip_radius),
    ]


def plug_inertia(geom: PlugGeometry) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass [m] and principal inertia [kg m^2] of the plug.

    The plug is a uniform solid (cylinder plus conical chamfer) scaled to
    ``geom.mass``.  The centre of mass lies on the axis, in the ``dock`` frame; the
    inertia is about the centre of mass along the ``dock`` axes (x, y, z), which are
    principal because the plug is axisymmetric.  See :func:`stacked_inertia`.
    """
    return stacked_inertia(_plug_profile(geom), math.pi, 0.5 * math.pi, geom.mass)


def stacked_inertia(
    profile: list[tuple[float, float, float, float]], area_coeff: float, polar_coeff: float, mass: float
) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre of mass and principal inertia of a uniform solid stacked along z.

    ``profile``: (z0, z1, rho0, rho1) segments in which the section's size rho varies
    linearly with z; each section is a similar shape of area ``area_coeff * rho**2``
    and polar moment about the axis ``polar_coeff * rho**4`` (a disc of radius rho:
    pi and pi/2; a regular n-gon of inradius rho: n*tan(pi/n) and
    n*(tan(pi/n)/2 + tan(pi/n)**3/6)).  The sections must be isotropic in their plane
    (discs, regular polygons), so x, y and z are principal axes.  The integrals are
    exact: 4-point Gauss-Legendre quadrature of polynomials of degree <= 4 per segment.
    """
    nodes, weights = np.polynomial.legendre.leggauss(4)
    volume = first_moment = second_moment = polar_moment = 0.0
    for z0, z1, rho0, rho1 in profile:
        half = 0.5 * (z1 - z0)
        z = z0 + half * (nodes + 1.0)
        rho = rho0 + (rho1 - rho0) * (z - z0) / (z1 - z0)
        slab = weights * half * area_coeff * rho**2  # volume of each slice
        volume += float(np.sum(slab))
        first_moment += float(np.sum(slab * z))
        second_moment += float(np.sum(slab * z**2))
        polar_moment += float(np.sum(weights * half * polar_coeff * rho**4))
    density = mass / volume
    z_com = first_moment / volume
    axial = density * polar_moment
    transverse = density * (0.5 * polar_moment + second_moment - volume * z_com**2)
    return mass, np.array([0.0, 0.0, z_com]), np.array([transverse, transverse, axial])


def _ring(radius: float, z: float, segments: int) -> np.ndarray:
    """(segments, 3) vertices of a regular polygon on a circle of ``radius`` at height z."""
    angle = 2.0 * np.pi * np.arange(segments) / segments
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.full(segments, z)])


def plug_hull_vertices(geom: PlugGeometry, segments: int | None = None) -> np.ndarray:
    """(3 n, 3) vertices, plug frame, of the plug's convex hull: rings of n = ``segments``
    (default ``geom.segments``) vertices on the circle at the mounting face, at the
    chamfer edge and at the tip face."""
    n = geom.segments if segments is None else segments
    return np.vstack(
        [
            _ring(geom.radius, 0.0, n),
            _ring(geom.radius, geom.chamfer_start, n),
            _ring(geom.tip_radius, geom.length, n),
        ]
    )


def build_plug(geom: PlugGeometry, contact: ContactParams | None) -> mujoco.MjSpec:
    """Plug fragment: root body ``dock``, origin at the mounting face, +z towards the tip.

    One collision geom ``plug_hull`` (the convex hull, see the module docstring) and a
    visual-only mesh of the whole plug.  Sites ``sensor_site`` (origin, identity) and
    ``tcp`` (0, 0, length).  Explicit inertial from :func:`plug_inertia`.  ``contact``
    only matters against geoms of equal priority: the socket's pieces have a higher
    priority, so against them the socket's values apply (None: MuJoCo's defaults).
    """
    spec = mujoco.MjSpec()
    spec.modelname = "plug"
    body = dock_body(spec, *plug_inertia(geom))
    add_hull_collider(spec, body, "plug_hull", plug_hull_vertices(geom), contact)
    segments = max(VISUAL_SEGMENTS, geom.segments)
    add_visual_and_sites(spec, body, plug_hull_vertices(geom, segments), geom.length)
    return spec


def add_hull_collider(
    spec: mujoco.MjSpec, body, name: str, vertices: np.ndarray, contact: ContactParams | None
) -> None:
    """A plug's collision geom: the convex hull of ``vertices`` (body frame), meeting every
    socket piece."""
    spec.add_mesh(name=name, uservert=np.ravel(vertices).tolist())
    g = body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=name,
        group=PLUG_COLLISION_GROUP,
        rgba=list(PLUG_RGBA),
    )
    make_plug_collider(g, contact)


def dock_body(spec: mujoco.MjSpec, mass: float, com: np.ndarray, inertia: np.ndarray):
    """The tool fragment's root body ``dock`` with its explicit inertia (mass [kg], centre
    of mass and diagonal inertia [kg·m²] in the body frame)."""
    body = spec.worldbody.add_body(name="dock")
    body.explicitinertial = True
    body.mass = mass
    body.ipos = com.tolist()
    body.iquat = [1.0, 0.0, 0.0, 0.0]
    body.inertia = inertia.tolist()
    return body


def add_visual_and_sites(spec: mujoco.MjSpec, body, vertices: np.ndarray, length: float) -> None:
    """A plug's visual mesh (no contact, no mass) and its ``sensor_site`` (the mounting
    face) and ``tcp`` (the tip, ``length`` along +z)."""
    spec.add_mesh(name="plug_visual", uservert=vertices.ravel().tolist())
    body.add_geom(
        name="plug_visual",
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname="plug_visual",
        contype=0,
        conaffinity=0,
        density=0.0,
        group=VISUAL_GROUP,
        rgba=list(PLUG_RGBA),
    )
    body.add_site(name="sensor_site", pos=[0.0, 0.0, 0.0], quat=[1.0, 0.0, 0.0, 0.0])
    body.add_site(name="tcp", pos=[0.0, 0.0, length])
