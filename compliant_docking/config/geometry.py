"""Parameters of the parametric docking interface (plug, socket, contact) and their checks.

Plain (mutable) dataclasses: they are the typed config schemas of ``tool.geometry``,
``target.geometry`` and ``target.contact`` (Hydra fills them in at composition) and the
parameter objects the builders in :mod:`compliant_docking.sim.geometry` take. Lengths in
metres, angles in degrees, masses in kilograms. Frames and the collision model are
described in :mod:`compliant_docking.sim.geometry`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from omegaconf import MISSING


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

    friction: tuple[float, float, float] = MISSING
    solref: tuple[float, float] = MISSING
    solimp: tuple[float, float, float, float, float] = MISSING
    condim: int = MISSING
    margin: float = MISSING

    def __post_init__(self) -> None:
        for name in ("friction", "solref", "solimp"):  # accept lists (e.g. from YAML)
            value = getattr(self, name)
            try:
                setattr(self, name, tuple(float(v) for v in value))
            except (TypeError, ValueError):
                raise ValueError(
                    f"ContactParams.{name} must be a sequence of numbers; got {value!r}."
                ) from None
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

    radius: float = MISSING
    length: float = MISSING
    chamfer_angle_deg: float = MISSING
    chamfer_length: float = MISSING
    mass: float = MISSING
    tip_segments: int = MISSING

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

    plug_radius: float = MISSING
    radial_clearance: float = MISSING
    insertion_depth: float = MISSING
    funnel_angle_deg: float = MISSING
    funnel_depth: float = MISSING
    sectors: int = MISSING
    wall_thickness: float = MISSING
    floor_thickness: float = MISSING

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
def require(ok: bool, setting: str, allowed: str, value: object) -> None:
    """Raise a ValueError naming ``setting``, the allowed range and the given value."""
    if not ok:
        raise ValueError(f"{setting} must be {allowed}; got {value!r}.")


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _check_numbers(obj: object, names: tuple[str, ...]) -> None:
    """Every named field of ``obj`` must be a finite real number."""
    for name in names:
        value = getattr(obj, name)
        require(_is_number(value), f"{type(obj).__name__}.{name}", "a finite number", value)


def _positive(setting: str, value: float) -> None:
    require(value > 0.0, setting, "a finite number > 0", value)


def _check_contact(c: ContactParams) -> None:
    require(
        len(c.friction) == 3 and all(f >= 0.0 for f in c.friction) and c.friction[0] > 0.0,
        "ContactParams.friction",
        "three numbers (sliding > 0, torsional >= 0, rolling >= 0)",
        c.friction,
    )
    require(
        len(c.solref) == 2 and c.solref[0] > 0.0 and c.solref[1] > 0.0,
        "ContactParams.solref",
        "two positive numbers (timeconst [s], >= 2 * timestep; dampratio, ~1)",
        c.solref,
    )
    require(
        len(c.solimp) == 5,
        "ContactParams.solimp",
        "five numbers (dmin, dmax, width, midpoint, power)",
        c.solimp,
    )
    dmin, dmax, width, mid, power = c.solimp
    require(
        0.0 < dmin <= dmax < 1.0 and width > 0.0 and 0.0 < mid < 1.0 and power >= 1.0,
        "ContactParams.solimp",
        "(dmin, dmax, width, midpoint, power) with 0 < dmin <= dmax < 1, width > 0 [m], "
        "0 < midpoint < 1 and power >= 1",
        c.solimp,
    )
    require(
        _is_int(c.condim) and c.condim in (1, 3, 4, 6), "ContactParams.condim", "one of 1, 3, 4, 6", c.condim
    )
    _check_numbers(c, ("margin",))
    require(c.margin >= 0.0, "ContactParams.margin", "a finite number >= 0 [m]", c.margin)


def _check_plug(p: PlugGeometry) -> None:
    _check_numbers(p, ("radius", "length", "chamfer_angle_deg", "chamfer_length", "mass"))
    for name in ("radius", "length", "chamfer_length", "mass"):
        _positive(f"PlugGeometry.{name}", getattr(p, name))
    require(
        0.0 < p.chamfer_angle_deg < 80.0,
        "PlugGeometry.chamfer_angle_deg",
        "in the open interval (0, 80) degrees",
        p.chamfer_angle_deg,
    )
    require(
        p.chamfer_length < p.length,
        "PlugGeometry.chamfer_length",
        f"shorter than PlugGeometry.length = {p.length} m",
        p.chamfer_length,
    )
    max_chamfer = 0.9 * p.radius / math.tan(math.radians(p.chamfer_angle_deg))
    require(
        p.chamfer_length <= max_chamfer,
        "PlugGeometry.chamfer_length",
        f"at most {max_chamfer:.6g} m for radius {p.radius} m and chamfer angle "
        f"{p.chamfer_angle_deg} deg (the chamfer, chamfer_length * tan(angle), may remove "
        "at most 90 % of the radius)",
        p.chamfer_length,
    )
    require(
        _is_int(p.tip_segments) and 12 <= p.tip_segments <= 128,
        "PlugGeometry.tip_segments",
        "an integer in [12, 128]",
        p.tip_segments,
    )


def _check_socket(s: SocketGeometry) -> None:
    _check_numbers(
        s,
        (
            "plug_radius",
            "radial_clearance",
            "insertion_depth",
            "funnel_angle_deg",
            "funnel_depth",
            "wall_thickness",
            "floor_thickness",
        ),
    )
    for name in ("plug_radius", "insertion_depth", "funnel_depth", "wall_thickness", "floor_thickness"):
        _positive(f"SocketGeometry.{name}", getattr(s, name))
    require(
        0.0 < s.radial_clearance < s.plug_radius,
        "SocketGeometry.radial_clearance",
        f"> 0 and < plug_radius = {s.plug_radius} m (the bore radius, plug_radius + "
        "radial_clearance, must exceed the plug radius: a plug as large as or larger "
        "than the bore cannot be inserted)",
        s.radial_clearance,
    )
    require(
        0.0 < s.funnel_angle_deg < 80.0,
        "SocketGeometry.funnel_angle_deg",
        "in the open interval (0, 80) degrees",
        s.funnel_angle_deg,
    )
    require(
        _is_int(s.sectors) and 8 <= s.sectors <= 64,
        "SocketGeometry.sectors",
        "an integer in [8, 64]",
        s.sectors,
    )


def check_fit(plug: PlugGeometry, socket: SocketGeometry) -> None:
    """Raise ValueError unless ``plug`` can be inserted into ``socket``.

    The plug radius must be smaller than the bore radius, and the plug must be longer
    than the bore is deep (otherwise the flange would have to enter the bore).
    """
    require(
        plug.radius < socket.bore_radius,
        "PlugGeometry.radius",
        f"smaller than the socket bore radius {socket.bore_radius:.6g} m "
        "(SocketGeometry.plug_radius + radial_clearance)",
        plug.radius,
    )
    require(
        plug.length > socket.insertion_depth,
        "PlugGeometry.length",
        f"longer than SocketGeometry.insertion_depth = {socket.insertion_depth} m",
        plug.length,
    )
