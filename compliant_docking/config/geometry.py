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
from typing import Any

from compliant_docking.config.ranges import (
    at_least,
    each,
    inside,
    integers,
    object_problems,
    one_of,
    positive,
    within,
)

#: a number strictly between 0 and 1 (solimp's dmin, dmax and midpoint)
_OPEN_UNIT = inside(0.0, 1.0)


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

    friction: tuple[float, float, float] = each(positive(), at_least(0.0), at_least(0.0))
    solref: tuple[float, float] = each(positive(unit="s"), positive())
    solimp: tuple[float, float, float, float, float] = each(
        _OPEN_UNIT, _OPEN_UNIT, positive(unit="m"), _OPEN_UNIT, at_least(1.0)
    )  # dmin, dmax, width, midpoint, power
    condim: int = one_of(1, 3, 4, 6)
    margin: float = at_least(0.0, unit="m")

    def __post_init__(self) -> None:
        for name in ("friction", "solref", "solimp"):  # accept lists (e.g. from YAML)
            value = getattr(self, name)
            try:
                setattr(self, name, tuple(float(v) for v in value))
            except (TypeError, ValueError):
                raise ValueError(
                    f"ContactParams.{name} must be a sequence of numbers; got {value!r}."
                ) from None
        raise_first(object_problems(self, "ContactParams") or contact_problems(self, "ContactParams"))


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
    segments:          polygon sides of the plug's convex collision hull (vertices on
                       the circle; see :mod:`compliant_docking.sim.geometry.plug`).
    """

    radius: float = positive(unit="m")
    length: float = positive(unit="m")
    chamfer_angle_deg: float = within(0.0, 80.0, low_open=True, high_open=True, unit="deg")
    chamfer_length: float = positive(unit="m")
    mass: float = positive(unit="kg")
    segments: int = integers(12, 128)

    def __post_init__(self) -> None:
        raise_first(object_problems(self, "PlugGeometry") or plug_problems(self, "PlugGeometry"))

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
    wall_thickness:    thickness of the socket block beyond the funnel's mouth [m].
    floor_thickness:   thickness of the slab closing the bottom of the bore [m].
    """

    plug_radius: float = positive(unit="m")
    radial_clearance: float = positive(unit="m")
    insertion_depth: float = positive(unit="m")
    funnel_angle_deg: float = within(0.0, 80.0, low_open=True, high_open=True, unit="deg")
    funnel_depth: float = positive(unit="m")
    sectors: int = integers(8, 64)
    wall_thickness: float = positive(unit="m")
    floor_thickness: float = positive(unit="m")

    def __post_init__(self) -> None:
        raise_first(object_problems(self, "SocketGeometry") or socket_problems(self, "SocketGeometry"))

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
# The range of each number is declared on its field (compliant_docking/config/ranges.py);
# the functions below check what involves several fields. They take the dataclass or the
# composed config node alike (attribute access) and name the fields ``<where>.<field>``:
# the config key (``target.geometry``) when the config is validated before a run
# (compliant_docking/config/validate.py), the class name for objects built in Python.


def require(ok: bool, setting: str, allowed: str, value: object) -> None:
    """Raise a ValueError naming ``setting``, the allowed range and the given value."""
    if not ok:
        raise ValueError(f"{setting} must be {allowed}; got {value!r}.")


def raise_first(problems: list[str]) -> None:
    """Raise a ValueError with the first of ``problems``, if any."""
    if problems:
        raise ValueError(problems[0])


def contact_problems(c: Any, where: str) -> list[str]:
    """ContactParams: solimp's dmin <= dmax."""
    if len(c.solimp) == 5 and not c.solimp[0] <= c.solimp[1]:
        return [f"{where}.solimp must have dmin <= dmax (its first two values); got {list(c.solimp)}."]
    return []


def plug_problems(p: Any, where: str) -> list[str]:
    """PlugGeometry: the chamfer must fit the plug."""
    found = []
    if not p.chamfer_length < p.length:
        found.append(
            f"{where}.chamfer_length must be shorter than {where}.length = {p.length} m; "
            f"got {p.chamfer_length!r}."
        )
    max_chamfer = 0.9 * p.radius / math.tan(math.radians(p.chamfer_angle_deg))
    if not p.chamfer_length <= max_chamfer:
        found.append(
            f"{where}.chamfer_length must be at most {max_chamfer:.6g} m for radius {p.radius} m "
            f"and chamfer angle {p.chamfer_angle_deg} deg (the chamfer, chamfer_length * "
            f"tan(angle), may remove at most 90 % of the radius); got {p.chamfer_length!r}."
        )
    return found


def socket_problems(s: Any, where: str) -> list[str]:
    """SocketGeometry: the bore must be larger than the plug it receives."""
    if s.radial_clearance < s.plug_radius:
        return []
    return [
        f"{where}.radial_clearance must be > 0 and < {where}.plug_radius = {s.plug_radius} m "
        "(the bore radius, plug_radius + radial_clearance, must exceed the plug radius: a plug "
        f"as large as or larger than the bore cannot be inserted); got {s.radial_clearance!r}."
    ]


def fit_problems(plug: Any, socket: Any, plug_where: str, socket_where: str) -> list[str]:
    """The plug must enter the socket's bore and be longer than the bore is deep
    (otherwise the flange would have to enter the bore)."""
    found = []
    bore = socket.plug_radius + socket.radial_clearance
    if not plug.radius < bore:
        found.append(
            f"{plug_where}.radius must be smaller than the socket bore radius {bore:.6g} m "
            f"({socket_where}.plug_radius + radial_clearance); got {plug.radius!r}."
        )
    if not plug.length > socket.insertion_depth:
        found.append(
            f"{plug_where}.length must be longer than {socket_where}.insertion_depth = "
            f"{socket.insertion_depth} m; got {plug.length!r}."
        )
    return found


def check_fit(plug: PlugGeometry, socket: SocketGeometry) -> None:
    """Raise ValueError unless ``plug`` can be inserted into ``socket`` (:func:`fit_problems`)."""
    raise_first(fit_problems(plug, socket, "PlugGeometry", "SocketGeometry"))
