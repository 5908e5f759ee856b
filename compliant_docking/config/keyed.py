"""Parameters of the keyed docking interface: a regular polygonal plug with a chamfered tip
and the matching polygonal socket with a pyramidal entry funnel (``tool=keyed_plug``,
``target=keyed_socket``), and their checks.

The key is the polygon itself: a plug with ``sides`` flat faces enters the bore only
when its faces line up with the bore's, i.e. its roll about the docking axis is within
the bore's yaw play (:attr:`KeyedSocketGeometry.yaw_play_deg`) of a multiple of
360° / ``sides``. Lengths in metres, angles in degrees, masses in kilograms; frames and
the collision model are described in :mod:`compliant_docking.sim.geometry.keyed`. The
values live in conf/tool/keyed_plug.yaml and conf/target/keyed_socket.yaml (their one
home; :func:`compliant_docking.config.store.default_keyed` reads them for scripts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from compliant_docking.config.geometry import raise_first
from compliant_docking.config.ranges import inside, integers, object_problems, positive

#: allowed numbers of polygon sides (a triangle to a dodecagon)
SIDES_RANGE = (3, 12)


def _sides() -> Any:
    """The declared range of ``sides`` (:data:`SIDES_RANGE`; a new field each time: a
    dataclass field object belongs to one class attribute)."""
    return integers(*SIDES_RANGE)


def _angle() -> Any:
    """The range of the chamfer and funnel angles [deg]."""
    return inside(0.0, 80.0, unit="deg")


@dataclass
class KeyedPlugGeometry:
    """The keyed tool: a regular ``sides``-gon prism with a pyramidal chamfer at its tip.

    sides:             number of flat faces; face k's outward normal is at azimuth
                       360° · k / sides from the plug's x axis.
    inradius:          distance from the axis to each flat face (half the width across
                       flats) [m].
    length:            mounting face to tip [m].
    chamfer_angle_deg: angle of the chamfer faces from the plug axis [deg]; the chamfer
                       moves every face in by ``chamfer_length * tan(angle)``.
    chamfer_length:    axial length of the chamfer [m].
    mass:              plug mass [kg]; the inertia is that of a uniform solid of this shape.
    """

    sides: int = _sides()
    inradius: float = positive(unit="m")
    length: float = positive(unit="m")
    chamfer_angle_deg: float = _angle()
    chamfer_length: float = positive(unit="m")
    mass: float = positive(unit="kg")

    def __post_init__(self) -> None:
        where = "KeyedPlugGeometry"
        raise_first(object_problems(self, where) or keyed_plug_problems(self, where))

    @property
    def tip_inradius(self) -> float:
        """Inradius of the flat tip face [m]."""
        return self.inradius - self.chamfer_length * math.tan(math.radians(self.chamfer_angle_deg))

    @property
    def chamfer_start(self) -> float:
        """Height of the chamfer edge above the mounting face [m]."""
        return self.length - self.chamfer_length


@dataclass
class KeyedSocketGeometry:
    """The keyed target: a ``sides``-gon bore below a pyramidal entry funnel.

    sides:             number of bore faces (the plug's); face k's inward side faces
                       azimuth 360° · k / sides from the socket's x axis.
    plug_inradius:     inradius of the plug this socket receives [m].
    clearance:         bore inradius minus plug inradius: the gap between parallel
                       faces of plug and bore [m], > 0.
    insertion_depth:   depth of the prismatic bore [m].
    funnel_angle_deg:  angle of the funnel faces from the socket axis [deg].
    funnel_depth:      axial length of the funnel [m].
    wall_thickness:    thickness of the socket block beyond the funnel's mouth [m].
    floor_thickness:   thickness of the slab closing the bottom of the bore [m].
    """

    sides: int = _sides()
    plug_inradius: float = positive(unit="m")
    clearance: float = positive(unit="m")
    insertion_depth: float = positive(unit="m")
    funnel_angle_deg: float = _angle()
    funnel_depth: float = positive(unit="m")
    wall_thickness: float = positive(unit="m")
    floor_thickness: float = positive(unit="m")

    def __post_init__(self) -> None:
        where = "KeyedSocketGeometry"
        raise_first(object_problems(self, where) or keyed_socket_problems(self, where))

    @property
    def bore_inradius(self) -> float:
        """Distance from the axis to each bore face [m] = plug_inradius + clearance."""
        return self.plug_inradius + self.clearance

    @property
    def mouth_inradius(self) -> float:
        """Funnel inradius at the mouth [m] = bore_inradius + funnel_depth * tan(funnel angle)."""
        return self.bore_inradius + self.funnel_depth * math.tan(math.radians(self.funnel_angle_deg))

    @property
    def mouth_height(self) -> float:
        """Height of the mouth above the seat [m] = insertion_depth + funnel_depth."""
        return self.insertion_depth + self.funnel_depth

    def free_inradius(self, z: float) -> float:
        """Distance from the axis to each face of the free space at height ``z`` above
        the seat [m] (0 <= z <= mouth_height)."""
        rise = min(max(z - self.insertion_depth, 0.0), self.funnel_depth)
        return self.bore_inradius + rise * math.tan(math.radians(self.funnel_angle_deg))

    @property
    def yaw_play_deg(self) -> float:
        """How far [deg] the plug (its prism, centred) can turn about the axis inside the
        bore before its edges touch the bore faces.

        The centred plug turned by θ reaches ``plug_inradius * cos(π/n - θ) / cos(π/n)``
        along every face normal; it fits while that is at most the bore inradius. Centred
        is the best position: shifting the plug brings it closer to some faces by as much
        as it moves it away from the opposite ones.
        """
        n = self.sides
        ratio = self.bore_inradius * math.cos(math.pi / n) / self.plug_inradius
        return math.degrees(math.pi / n - math.acos(min(ratio, 1.0)))


# The range of each number is declared on its field (compliant_docking/config/ranges.py);
# the functions below check what involves several fields, on the dataclass or the composed
# config node alike, naming the fields ``<where>.<field>`` (config keys when the config is
# validated before a run: compliant_docking/config/validate.py).


def keyed_plug_problems(p: Any, where: str) -> list[str]:
    """The chamfer must fit the plug."""
    found = []
    if not p.chamfer_length < p.length:
        found.append(
            f"{where}.chamfer_length must be shorter than {where}.length = {p.length} m; "
            f"got {p.chamfer_length!r}."
        )
    max_chamfer = 0.9 * p.inradius / math.tan(math.radians(p.chamfer_angle_deg))
    if not p.chamfer_length <= max_chamfer:
        found.append(
            f"{where}.chamfer_length must be at most {max_chamfer:.6g} m for inradius {p.inradius} m "
            f"and chamfer angle {p.chamfer_angle_deg} deg (the chamfer may remove at most 90 % of "
            f"the inradius); got {p.chamfer_length!r}."
        )
    return found


def keyed_socket_problems(s: Any, where: str) -> list[str]:
    """The gap must be smaller than the plug it receives."""
    if s.clearance < s.plug_inradius:
        return []
    return [
        f"{where}.clearance must be > 0 and < {where}.plug_inradius = {s.plug_inradius} m (the gap "
        f"between parallel plug and bore faces); got {s.clearance!r}."
    ]


def keyed_fit_problems(plug: Any, socket: Any, plug_where: str, socket_where: str) -> list[str]:
    """The plug must have the socket's sides, a smaller inradius than the bore's, and be
    longer than the bore is deep."""
    found = []
    if plug.sides != socket.sides:
        found.append(
            f"{socket_where}.sides must equal {plug_where}.sides = {plug.sides} (the key); "
            f"got {socket.sides!r}."
        )
    bore = socket.plug_inradius + socket.clearance
    if not plug.inradius < bore:
        found.append(
            f"{plug_where}.inradius must be smaller than the socket's bore inradius {bore:.6g} m "
            f"({socket_where}.plug_inradius + clearance); got {plug.inradius!r}."
        )
    if not plug.length > socket.insertion_depth:
        found.append(
            f"{plug_where}.length must be longer than {socket_where}.insertion_depth = "
            f"{socket.insertion_depth} m; got {plug.length!r}."
        )
    return found


def check_keyed_fit(plug: KeyedPlugGeometry, socket: KeyedSocketGeometry) -> None:
    """Raise ValueError unless ``plug`` can be inserted into ``socket`` (:func:`keyed_fit_problems`)."""
    raise_first(keyed_fit_problems(plug, socket, "KeyedPlugGeometry", "KeyedSocketGeometry"))
