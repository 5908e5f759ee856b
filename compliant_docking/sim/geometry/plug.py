"""The parametric plug: a cylinder with a conical chamfer at its tip, as an MjSpec fragment.

Frame: ``worldbody`` holds one root body ``dock``.  Its origin is the centre of the
plug's mounting face (where it bolts to the robot flange) and its +z axis is the plug
axis, pointing from the flange towards the tip.  Sites: ``sensor_site`` at the origin
with identity orientation (the force/torque sensor anchor) and ``tcp`` at the tip centre
``(0, 0, length)``.  The body carries an explicit inertial equal to :func:`plug_inertia`;
every geom has zero density and adds no mass.

Collision models (``collision=``):
``"cylinder_tip"`` (default): a cylinder primitive for the shaft, from the mounting face
to where the chamfer starts, plus a convex-mesh frustum for the chamfer (``tip_segments``
vertices per ring, on the circle).  The cylinder is exactly round, so the bore clearance
is exact, and its lower edge is the chamfer edge.  Pairs are filtered so that the shaft
only meets the bore boxes and the chamfer only meets the funnel boxes and the floor: with
the plug tilted less than the funnel angle and the chamfer angle relative to the socket
axis (always the case while docking), the excluded pairs cannot touch before an included
one does, and skipping them halves the collision cost in the bore (see
``benchmarks/contact_geometry.py``).
``"capsule_tip"``: capsule shaft ending one radius above the chamfer plus a convex-mesh
tip (short cylinder + chamfer) meeting everything; the capsule's end cap, inside the tip,
makes slightly tilted contact normals at the bore's top edge.
``"mesh"``: one convex mesh of the whole plug meeting everything (slowest).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from compliant_docking.config.geometry import ContactParams, PlugGeometry, require
from compliant_docking.sim.geometry.collision import (
    ALL_SOCKET_BITS,
    PLUG_COLLISION_GROUP,
    PLUG_COLLISION_MODELS,
    PLUG_RGBA,
    SHAFT_CONAFFINITY,
    TIP_CONAFFINITY,
    VISUAL_GROUP,
    VISUAL_SEGMENTS,
    apply_contact,
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


def plug_hull_vertices(geom: PlugGeometry, z_start: float = 0.0, segments: int | None = None) -> np.ndarray:
    """(n, 3) vertices, plug frame, of the plug's convex hull from ``z_start`` to the tip.

    Rings of ``segments`` (default ``geom.tip_segments``) vertices on the circle at
    z_start (if below the chamfer edge), at the chamfer edge and at the tip face.
    """
    n = geom.tip_segments if segments is None else segments
    rings = [_ring(geom.radius, geom.chamfer_start, n), _ring(geom.tip_radius, geom.length, n)]
    if z_start < geom.chamfer_start:
        rings.insert(0, _ring(geom.radius, z_start, n))
    return np.vstack(rings)


def _capsule_end(geom: PlugGeometry) -> float:
    """Tip-side end of the capsule segment: its end cap reaches exactly the chamfer edge."""
    return geom.chamfer_start - geom.radius


def _add_plug_collision(
    spec: mujoco.MjSpec,
    body: mujoco.MjsBody,
    geom: PlugGeometry,
    contact: ContactParams | None,
    collision: str,
) -> None:
    """Add the collision geoms of the chosen model to ``body`` (plug frame)."""

    def add(name: str, conaffinity: int, **kwargs) -> None:
        g = body.add_geom(name=name, group=PLUG_COLLISION_GROUP, rgba=list(PLUG_RGBA), **kwargs)
        apply_contact(g, contact, 0, conaffinity)

    def add_hull(name: str, z_start: float, conaffinity: int) -> None:
        spec.add_mesh(name=name, uservert=plug_hull_vertices(geom, z_start).ravel().tolist())
        add(name, conaffinity, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)

    z_edge = geom.chamfer_start
    if collision == "cylinder_tip":
        add(
            "plug_shaft",
            SHAFT_CONAFFINITY,
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[geom.radius, 0.5 * z_edge, 0.0],
            pos=[0.0, 0.0, 0.5 * z_edge],
        )
        add_hull("plug_tip", z_edge, TIP_CONAFFINITY)
    elif collision == "capsule_tip":
        z0, z1 = geom.radius, _capsule_end(geom)
        add(
            "plug_shaft",
            SHAFT_CONAFFINITY,
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            size=[geom.radius, 0.5 * (z1 - z0), 0.0],
            pos=[0.0, 0.0, 0.5 * (z0 + z1)],
        )
        add_hull("plug_tip", z1, ALL_SOCKET_BITS)
    else:
        add_hull("plug_hull", 0.0, ALL_SOCKET_BITS)


def build_plug(
    geom: PlugGeometry, contact: ContactParams | None, *, collision: str = "cylinder_tip"
) -> mujoco.MjSpec:
    """Plug fragment: root body ``dock``, origin at the mounting face, +z towards the tip.

    ``collision`` selects the collision model (see the module docstring):
    ``"cylinder_tip"`` (default), ``"capsule_tip"`` or ``"mesh"``.  A visual-only mesh
    of the whole plug is always added.  Sites ``sensor_site`` (origin, identity) and
    ``tcp`` (0, 0, length).  Explicit inertial from :func:`plug_inertia`.  ``contact``
    only matters against geoms of equal priority: the socket's pieces have a higher
    priority, so against them the socket's values apply (None: MuJoCo's defaults).
    """
    require(collision in PLUG_COLLISION_MODELS, "collision", f"one of {PLUG_COLLISION_MODELS}", collision)
    if collision == "capsule_tip":
        require(
            _capsule_end(geom) > geom.radius,
            "PlugGeometry.length",
            f"greater than 2 * radius + chamfer_length = "
            f"{2 * geom.radius + geom.chamfer_length:.6g} m for collision='capsule_tip'",
            geom.length,
        )
    spec = mujoco.MjSpec()
    spec.modelname = "plug"
    body = dock_body(spec, *plug_inertia(geom))

    _add_plug_collision(spec, body, geom, contact, collision)
    segments = max(VISUAL_SEGMENTS, geom.tip_segments)
    add_visual_and_sites(spec, body, plug_hull_vertices(geom, 0.0, segments), geom.length)
    return spec


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
