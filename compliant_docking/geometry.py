"""Parametric docking interface: a chamfered plug and a socket with an entry funnel.

Both parts are generated as MuJoCo ``MjSpec`` fragments that the scene assembler
attaches to a robot (the plug) and to the world (the socket).  Lengths are in
metres, angles in degrees, masses in kilograms, inertias in kg m^2.

Frames
------
Plug fragment: ``worldbody`` holds one root body ``dock``.  Its origin is the centre
of the plug's mounting face (where it bolts to the robot flange) and its +z axis is
the plug axis, pointing from the flange towards the tip.  Sites: ``sensor_site`` at
the origin with identity orientation (the force/torque sensor anchor) and ``tcp`` at
the tip centre ``(0, 0, length)``.  The body carries an explicit inertial equal to
:func:`plug_inertia`; every geom has zero density and adds no mass.

Socket fragment: ``worldbody`` holds one root body ``dock`` without a joint (the
assembler fixes it to the world; its geoms have zero density, so the body is
massless and must stay static).  Its origin is the SEAT, the centre of the bottom of
the cylindrical bore, where the plug tip rests when fully inserted.  +z points out of
the socket, towards the approaching plug, so the plug moves along -z of this frame
while inserting.  Sites: ``seat`` at the origin and ``mouth`` at
``(0, 0, insertion_depth + funnel_depth)``.

Socket collision model
----------------------
The socket cavity is an intersection of half-spaces.  Each of the ``sectors`` bore
pieces is a box whose inner face lies in a plane TANGENT to the bore cylinder (a
circumscribed polygon: inscribed radius = bore radius), and each funnel piece is a
tilted box whose inner face lies in the plane tangent to the funnel cone along one of
its generators.  Every box lies entirely behind its own tangent plane, so no piece
intrudes into the nominal free space: the radial clearance is never below
``radial_clearance``; it grows to ``bore_radius * (1 / cos(pi / sectors) - 1)`` more at
the polygon corners (0.20 mm extra for 16 sectors, 0.37 mm for 12 at the defaults).
Boxes overlap freely behind their faces.  Each funnel box starts exactly on the circle
where the cone meets the bore (its lower end face is perpendicular to the generator),
so funnel and bore meet without a lip or a gap.  A floor box closes the bore; its top
face is the seat plane z = 0.

Plug collision model
--------------------
``collision="cylinder_tip"`` (default): a cylinder primitive for the shaft, from the
mounting face to where the chamfer starts, plus a convex-mesh frustum for the chamfer
(``tip_segments`` vertices per ring, on the circle).  The cylinder is exactly round, so
the bore clearance is exact, and its lower edge is the chamfer edge.  Pairs are
filtered so that the shaft only meets the bore boxes and the chamfer only meets the
funnel boxes and the floor: with the plug tilted less than the funnel angle and the
chamfer angle relative to the socket axis (always the case while docking), the
excluded pairs cannot touch before an included one does, and skipping them halves
the collision cost in the bore (see ``benchmarks/contact_geometry.py``).
``collision="capsule_tip"``: capsule shaft ending one radius above the chamfer plus a
convex-mesh tip (short cylinder + chamfer) meeting everything; the capsule's end
cap, inside the tip, makes slightly tilted contact normals at the bore's top edge.
``collision="mesh"``: one convex mesh of the whole plug meeting everything (slowest).

Collision filtering
-------------------
Socket geoms have ``contype`` = :data:`SOCKET_BORE_BIT` (bore boxes) or
:data:`SOCKET_ENTRY_BIT` (funnel boxes, floor) and ``conaffinity = 0``; plug geoms
have ``contype = 0`` and a ``conaffinity`` naming the socket bits they meet.  So plug
and socket collide with each other and with nothing else: not with themselves, not
with geoms left at MuJoCo's default contype/conaffinity of 1, not with visual-only
geoms (contype = conaffinity = 0).  Geom groups: visual-only :data:`VISUAL_GROUP`,
plug collision :data:`PLUG_COLLISION_GROUP`, socket :data:`SOCKET_GROUP` (its boxes
are drawn semi-transparent so the insertion can be seen).

Contact parameters
------------------
:class:`ContactParams` is written on every plug and socket collision geom.  Note for
MuJoCo 4.0.0: a contact's margin is the SUM of both geoms' margins and acts as a
contact offset (the constraint pushes the surfaces apart to that distance), and the
geom ``gap`` attribute had no measurable effect, so any margin directly eats
clearance; the default margin is 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

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


# ------------------------------------------------------------------------ parameters
# Plain (mutable) dataclasses: they double as the typed config schemas of the tool and
# target groups (compliant_docking/config.py), which Hydra fills in at composition.
@dataclass
class ContactParams:
    """Contact parameters of every plug and socket collision geom.

    Both parts get the same values, so MuJoCo's mixing leaves them unchanged for a
    plug/socket contact.

    friction: (sliding, torsional, rolling) coefficients; torsional and rolling act
              only with condim 4 / 6.
    solref:   (timeconst [s], dampratio).  Keep timeconst >= 2 * timestep and
              dampratio at 1: 0.7 chattered on the seat at 20-30 N.  5 ms (five
              steps at 1 kHz) resolves an impact over several steps: at 2 ms (two
              steps) a grazing first contact of a heavy arm was stopped within one
              step, and the per-step force then measured the time step more than the
              contact (FR3: 90 N at 2 ms, 37-42 N at 5-6 ms).  Steady penetration
              stays far below the 0.4 mm clearance (tens of µm at 30 N).
    solimp:   (dmin, dmax, width [m], midpoint, power).  dmin/dmax of 0.95/0.99 keep
              the penetration at a few micrometres per 10 N; values closer to 1 made
              the seated contact oscillate.
    condim:   contact dimensionality, one of 1, 3, 4, 6.
    margin:   per-geom contact margin [m].  Contact pairs use the sum of both margins
              as an offset, which eats clearance; keep 0 unless you know why.
    """

    friction: tuple[float, float, float] = (0.3, 0.005, 0.0001)
    solref: tuple[float, float] = (0.005, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.95, 0.99, 0.0005, 0.5, 2.0)
    condim: int = 3
    margin: float = 0.0

    def __post_init__(self) -> None:
        for name in ("friction", "solref", "solimp"):  # accept lists (e.g. from YAML)
            value = getattr(self, name)
            try:
                setattr(self, name, tuple(float(v) for v in value))
            except (TypeError, ValueError):
                raise ValueError(f"ContactParams.{name} must be a sequence of numbers; "
                                 f"got {value!r}.") from None
        _check_contact(self)


@dataclass
class PlugGeometry:
    """The tool (male side): a cylinder with a conical chamfer at its tip.

    radius:            shaft radius [m].
    length:            mounting face to tip [m].
    chamfer_angle_deg: chamfer half-angle measured from the plug axis [deg]; the
                       chamfer reduces the radius by ``chamfer_length * tan(angle)``.
    chamfer_length:    axial length of the chamfer [m].
    mass:              plug mass [kg]; the inertia is that of a uniform solid of this
                       shape (see :func:`plug_inertia`).
    tip_segments:      polygon sides of the convex tip mesh (vertices on the circle).
    """

    radius: float = 0.010
    length: float = 0.060
    chamfer_angle_deg: float = 30.0
    chamfer_length: float = 0.003
    mass: float = 0.30
    tip_segments: int = 32

    def __post_init__(self) -> None:
        _check_plug(self)

    @property
    def tip_radius(self) -> float:
        """Radius of the flat tip face [m]."""
        return self.radius - self.chamfer_length * math.tan(math.radians(self.chamfer_angle_deg))

    @property
    def chamfer_start(self) -> float:
        """Height of the chamfer edge above the mounting face [m]."""
        return self.length - self.chamfer_length


@dataclass
class SocketGeometry:
    """The target (female side): a cylindrical bore below a conical entry funnel.

    plug_radius:       nominal radius of the plug this socket receives [m].
    radial_clearance:  bore radius minus plug radius [m], > 0.
    insertion_depth:   depth of the cylindrical bore [m].
    funnel_angle_deg:  funnel half-angle from the socket axis [deg].
    funnel_depth:      axial length of the funnel [m].
    sectors:           number of pieces around the circumference (bore and funnel).
    wall_thickness:    thickness of the bore and funnel boxes behind their faces [m].
    floor_thickness:   thickness of the box closing the bottom of the bore [m].
    """

    plug_radius: float = 0.010
    radial_clearance: float = 0.0004
    insertion_depth: float = 0.030
    funnel_angle_deg: float = 30.0
    funnel_depth: float = 0.015
    sectors: int = 16
    wall_thickness: float = 0.005
    floor_thickness: float = 0.005

    def __post_init__(self) -> None:
        _check_socket(self)

    @property
    def bore_radius(self) -> float:
        """Bore radius [m] = plug_radius + radial_clearance (inscribed radius of the boxes)."""
        return self.plug_radius + self.radial_clearance

    @property
    def mouth_radius(self) -> float:
        """Funnel radius at the mouth [m] = bore_radius + funnel_depth * tan(funnel angle)."""
        return self.bore_radius + self.funnel_depth * math.tan(math.radians(self.funnel_angle_deg))

    @property
    def mouth_height(self) -> float:
        """Height of the mouth above the seat [m] = insertion_depth + funnel_depth."""
        return self.insertion_depth + self.funnel_depth

    def free_radius(self, z: float) -> float:
        """Nominal radius of the free space at height ``z`` above the seat [m].

        This is the inscribed radius of the piece polygon: the distance from the axis
        to the face centres.  Valid for 0 <= z <= mouth_height.
        """
        rise = min(max(z - self.insertion_depth, 0.0), self.funnel_depth)
        return self.bore_radius + rise * math.tan(math.radians(self.funnel_angle_deg))


# ------------------------------------------------------------------------ validation
def _require(ok: bool, setting: str, allowed: str, value: object) -> None:
    """Raise a ValueError naming ``setting``, the allowed range and the given value."""
    if not ok:
        raise ValueError(f"{setting} must be {allowed}; got {value!r}.")


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) \
        and math.isfinite(value)


def _check_numbers(obj: object, names: tuple[str, ...]) -> None:
    """Every named field of ``obj`` must be a finite real number."""
    for name in names:
        value = getattr(obj, name)
        _require(_is_number(value), f"{type(obj).__name__}.{name}", "a finite number", value)


def _positive(setting: str, value: float) -> None:
    _require(value > 0.0, setting, "a finite number > 0", value)


def _check_contact(c: ContactParams) -> None:
    _require(len(c.friction) == 3 and all(f >= 0.0 for f in c.friction) and c.friction[0] > 0.0,
             "ContactParams.friction",
             "three numbers (sliding > 0, torsional >= 0, rolling >= 0)", c.friction)
    _require(len(c.solref) == 2 and c.solref[0] > 0.0 and c.solref[1] > 0.0,
             "ContactParams.solref",
             "two positive numbers (timeconst [s], >= 2 * timestep; dampratio, ~1)", c.solref)
    _require(len(c.solimp) == 5, "ContactParams.solimp",
             "five numbers (dmin, dmax, width, midpoint, power)", c.solimp)
    dmin, dmax, width, mid, power = c.solimp
    _require(0.0 < dmin <= dmax < 1.0 and width > 0.0 and 0.0 < mid < 1.0 and power >= 1.0,
             "ContactParams.solimp",
             "(dmin, dmax, width, midpoint, power) with 0 < dmin <= dmax < 1, width > 0 [m], "
             "0 < midpoint < 1 and power >= 1", c.solimp)
    _require(_is_int(c.condim) and c.condim in (1, 3, 4, 6), "ContactParams.condim",
             "one of 1, 3, 4, 6", c.condim)
    _check_numbers(c, ("margin",))
    _require(c.margin >= 0.0, "ContactParams.margin", "a finite number >= 0 [m]", c.margin)


def _check_plug(p: PlugGeometry) -> None:
    _check_numbers(p, ("radius", "length", "chamfer_angle_deg", "chamfer_length", "mass"))
    for name in ("radius", "length", "chamfer_length", "mass"):
        _positive(f"PlugGeometry.{name}", getattr(p, name))
    _require(0.0 < p.chamfer_angle_deg < 80.0, "PlugGeometry.chamfer_angle_deg",
             "in the open interval (0, 80) degrees", p.chamfer_angle_deg)
    _require(p.chamfer_length < p.length, "PlugGeometry.chamfer_length",
             f"shorter than PlugGeometry.length = {p.length} m", p.chamfer_length)
    max_chamfer = 0.9 * p.radius / math.tan(math.radians(p.chamfer_angle_deg))
    _require(p.chamfer_length <= max_chamfer, "PlugGeometry.chamfer_length",
             f"at most {max_chamfer:.6g} m for radius {p.radius} m and chamfer angle "
             f"{p.chamfer_angle_deg} deg (the chamfer, chamfer_length * tan(angle), may remove "
             "at most 90 % of the radius)", p.chamfer_length)
    _require(_is_int(p.tip_segments) and 12 <= p.tip_segments <= 128,
             "PlugGeometry.tip_segments", "an integer in [12, 128]", p.tip_segments)


def _check_socket(s: SocketGeometry) -> None:
    _check_numbers(s, ("plug_radius", "radial_clearance", "insertion_depth", "funnel_angle_deg",
                       "funnel_depth", "wall_thickness", "floor_thickness"))
    for name in ("plug_radius", "insertion_depth", "funnel_depth", "wall_thickness",
                 "floor_thickness"):
        _positive(f"SocketGeometry.{name}", getattr(s, name))
    _require(0.0 < s.radial_clearance < s.plug_radius,
             "SocketGeometry.radial_clearance",
             f"> 0 and < plug_radius = {s.plug_radius} m (the bore radius, plug_radius + "
             "radial_clearance, must exceed the plug radius: a plug as large as or larger "
             "than the bore cannot be inserted)", s.radial_clearance)
    _require(0.0 < s.funnel_angle_deg < 80.0, "SocketGeometry.funnel_angle_deg",
             "in the open interval (0, 80) degrees", s.funnel_angle_deg)
    _require(_is_int(s.sectors) and 8 <= s.sectors <= 64, "SocketGeometry.sectors",
             "an integer in [8, 64]", s.sectors)


def check_fit(plug: PlugGeometry, socket: SocketGeometry) -> None:
    """Raise ValueError unless ``plug`` can be inserted into ``socket``.

    The plug radius must be smaller than the bore radius, and the plug must be longer
    than the bore is deep (otherwise the flange would have to enter the bore).
    """
    _require(plug.radius < socket.bore_radius, "PlugGeometry.radius",
             f"smaller than the socket bore radius {socket.bore_radius:.6g} m "
             "(SocketGeometry.plug_radius + radial_clearance)", plug.radius)
    _require(plug.length > socket.insertion_depth, "PlugGeometry.length",
             f"longer than SocketGeometry.insertion_depth = {socket.insertion_depth} m",
             plug.length)


# --------------------------------------------------------------------- plug geometry
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
    principal because the plug is axisymmetric.  The integrals are exact: Gauss-
    Legendre quadrature of polynomial integrands.
    """
    nodes, weights = np.polynomial.legendre.leggauss(4)
    volume = first_moment = second_moment = radial_moment = 0.0
    for z0, z1, rho0, rho1 in _plug_profile(geom):
        half = 0.5 * (z1 - z0)
        z = z0 + half * (nodes + 1.0)
        rho = rho0 + (rho1 - rho0) * (z - z0) / (z1 - z0)
        slab = weights * half * math.pi * rho**2  # volume of each slice
        volume += float(np.sum(slab))
        first_moment += float(np.sum(slab * z))
        second_moment += float(np.sum(slab * z**2))
        radial_moment += float(np.sum(slab * rho**2))
    density = geom.mass / volume
    z_com = first_moment / volume
    axial = 0.5 * density * radial_moment                  # sum of disc inertias m rho^2 / 2
    transverse = density * (0.25 * radial_moment + second_moment - volume * z_com**2)
    return geom.mass, np.array([0.0, 0.0, z_com]), np.array([transverse, transverse, axial])


def _ring(radius: float, z: float, segments: int) -> np.ndarray:
    """(segments, 3) vertices of a regular polygon on a circle of ``radius`` at height z."""
    angle = 2.0 * np.pi * np.arange(segments) / segments
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle),
                            np.full(segments, z)])


def plug_hull_vertices(geom: PlugGeometry, z_start: float = 0.0,
                       segments: int | None = None) -> np.ndarray:
    """(n, 3) vertices, plug frame, of the plug's convex hull from ``z_start`` to the tip.

    Rings of ``segments`` (default ``geom.tip_segments``) vertices on the circle at
    z_start (if below the chamfer edge), at the chamfer edge and at the tip face.
    """
    n = geom.tip_segments if segments is None else segments
    rings = [_ring(geom.radius, geom.chamfer_start, n), _ring(geom.tip_radius, geom.length, n)]
    if z_start < geom.chamfer_start:
        rings.insert(0, _ring(geom.radius, z_start, n))
    return np.vstack(rings)


def _apply_contact(geom: mujoco.MjsGeom, contact: ContactParams, contype: int,
                   conaffinity: int) -> None:
    geom.contype = contype
    geom.conaffinity = conaffinity
    geom.condim = contact.condim
    geom.friction = list(contact.friction)
    geom.solref = list(contact.solref)
    geom.solimp = list(contact.solimp)
    geom.margin = contact.margin
    geom.density = 0.0


def _capsule_end(geom: PlugGeometry) -> float:
    """Tip-side end of the capsule segment: its end cap reaches exactly the chamfer edge."""
    return geom.chamfer_start - geom.radius


def _add_plug_collision(spec: mujoco.MjSpec, body: mujoco.MjsBody, geom: PlugGeometry,
                        contact: ContactParams, collision: str) -> None:
    """Add the collision geoms of the chosen model to ``body`` (plug frame)."""
    def add(name: str, conaffinity: int, **kwargs) -> None:
        g = body.add_geom(name=name, group=PLUG_COLLISION_GROUP, rgba=list(PLUG_RGBA), **kwargs)
        _apply_contact(g, contact, 0, conaffinity)

    def add_hull(name: str, z_start: float, conaffinity: int) -> None:
        spec.add_mesh(name=name, uservert=plug_hull_vertices(geom, z_start).ravel().tolist())
        add(name, conaffinity, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)

    z_edge = geom.chamfer_start
    if collision == "cylinder_tip":
        add("plug_shaft", SHAFT_CONAFFINITY, type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[geom.radius, 0.5 * z_edge, 0.0], pos=[0.0, 0.0, 0.5 * z_edge])
        add_hull("plug_tip", z_edge, TIP_CONAFFINITY)
    elif collision == "capsule_tip":
        z0, z1 = geom.radius, _capsule_end(geom)
        add("plug_shaft", SHAFT_CONAFFINITY, type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            size=[geom.radius, 0.5 * (z1 - z0), 0.0], pos=[0.0, 0.0, 0.5 * (z0 + z1)])
        add_hull("plug_tip", z1, ALL_SOCKET_BITS)
    else:
        add_hull("plug_hull", 0.0, ALL_SOCKET_BITS)


def build_plug(geom: PlugGeometry, contact: ContactParams | None = None, *,
               collision: str = "cylinder_tip") -> mujoco.MjSpec:
    """Plug fragment: root body ``dock``, origin at the mounting face, +z towards the tip.

    ``collision`` selects the collision model (see the module docstring):
    ``"cylinder_tip"`` (default), ``"capsule_tip"`` or ``"mesh"``.  A visual-only mesh
    of the whole plug is always added.  Sites ``sensor_site`` (origin, identity) and
    ``tcp`` (0, 0, length).  Explicit inertial from :func:`plug_inertia`.  ``contact``
    (default: ``ContactParams()``) only matters against geoms of equal priority: the
    socket's pieces have a higher priority, so against them the socket's values apply.
    """
    contact = ContactParams() if contact is None else contact
    _require(collision in PLUG_COLLISION_MODELS, "collision",
             f"one of {PLUG_COLLISION_MODELS}", collision)
    if collision == "capsule_tip":
        _require(_capsule_end(geom) > geom.radius, "PlugGeometry.length",
                 f"greater than 2 * radius + chamfer_length = "
                 f"{2 * geom.radius + geom.chamfer_length:.6g} m for collision='capsule_tip'",
                 geom.length)
    spec = mujoco.MjSpec()
    spec.modelname = "plug"
    body = spec.worldbody.add_body(name="dock")
    mass, com, inertia = plug_inertia(geom)
    body.explicitinertial = True
    body.mass = mass
    body.ipos = com.tolist()
    body.iquat = [1.0, 0.0, 0.0, 0.0]
    body.inertia = inertia.tolist()

    _add_plug_collision(spec, body, geom, contact, collision)
    segments = max(VISUAL_SEGMENTS, geom.tip_segments)
    spec.add_mesh(name="plug_visual",
                  uservert=plug_hull_vertices(geom, 0.0, segments).ravel().tolist())
    body.add_geom(name="plug_visual", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="plug_visual",
                  contype=0, conaffinity=0, density=0.0, group=VISUAL_GROUP,
                  rgba=list(PLUG_RGBA))
    body.add_site(name="sensor_site", pos=[0.0, 0.0, 0.0], quat=[1.0, 0.0, 0.0, 0.0])
    body.add_site(name="tcp", pos=[0.0, 0.0, geom.length])
    return spec


# ------------------------------------------------------------------- socket geometry
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
    n = geom.sectors
    rb, t, depth = geom.bore_radius, geom.wall_thickness, geom.insertion_depth
    alpha = math.radians(geom.funnel_angle_deg)
    generator_length = geom.funnel_depth / math.cos(alpha)
    half_width_bore = (rb + t) * math.tan(math.pi / n)
    half_width_funnel = (geom.mouth_radius + t) * math.tan(math.pi / n)
    up = np.array([0.0, 0.0, 1.0])
    bores, funnels = [], []
    for k in range(n):
        phi = 2.0 * math.pi * k / n
        radial = np.array([math.cos(phi), math.sin(phi), 0.0])
        tangent = np.array([-math.sin(phi), math.cos(phi), 0.0])
        bores.append(Box(
            name=f"bore_{k}",
            pos=_as_tuple((rb + 0.5 * t) * radial + 0.5 * depth * up),
            quat=_frame_quat(radial, tangent, up),
            half_size=(0.5 * t, half_width_bore, 0.5 * depth)))
        normal = math.cos(alpha) * radial - math.sin(alpha) * up       # out of the cavity
        generator = math.sin(alpha) * radial + math.cos(alpha) * up    # up the funnel wall
        base = rb * radial + depth * up                                # on the bore circle
        funnels.append(Box(
            name=f"funnel_{k}",
            pos=_as_tuple(base + 0.5 * generator_length * generator + 0.5 * t * normal),
            quat=_frame_quat(normal, tangent, generator),
            half_size=(0.5 * t, half_width_funnel, 0.5 * generator_length)))
    floor_half = rb + t
    floor = Box(name="floor", pos=(0.0, 0.0, -0.5 * geom.floor_thickness),
                quat=(1.0, 0.0, 0.0, 0.0),
                half_size=(floor_half, floor_half, 0.5 * geom.floor_thickness))
    return bores + funnels + [floor]


def build_socket(geom: SocketGeometry, contact: ContactParams) -> mujoco.MjSpec:
    """Socket fragment: static root body ``dock``, origin at the seat, +z out of the socket.

    Geoms: ``bore_<k>`` and ``funnel_<k>`` for k < sectors and ``floor`` (see
    :func:`socket_boxes`), drawn semi-transparent.  Sites ``seat`` (origin) and
    ``mouth`` (0, 0, insertion_depth + funnel_depth).
    """
    spec = mujoco.MjSpec()
    spec.modelname = "socket"
    body = spec.worldbody.add_body(name="dock")
    for box in socket_boxes(geom):
        g = body.add_geom(name=box.name, type=mujoco.mjtGeom.mjGEOM_BOX, pos=list(box.pos),
                          quat=list(box.quat), size=list(box.half_size), group=SOCKET_GROUP,
                          rgba=list(SOCKET_RGBA))
        bit = SOCKET_BORE_BIT if box.name.startswith("bore_") else SOCKET_ENTRY_BIT
        _apply_contact(g, contact, bit, 0)
        # The socket's contact parameters govern every plug/socket contact (MuJoCo uses
        # the parameters of the geom with the higher priority instead of mixing them).
        g.priority = SOCKET_PRIORITY
    body.add_site(name="seat", pos=[0.0, 0.0, 0.0])
    body.add_site(name="mouth", pos=[0.0, 0.0, geom.mouth_height])
    return spec
