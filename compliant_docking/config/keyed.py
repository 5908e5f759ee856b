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

from omegaconf import MISSING

from compliant_docking.config.geometry import _check_numbers, _is_int, _positive, require

#: allowed numbers of polygon sides (a triangle to a dodecagon)
SIDES_RANGE = (3, 12)


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

    sides: int = MISSING
    inradius: float = MISSING
    length: float = MISSING
    chamfer_angle_deg: float = MISSING
    chamfer_length: float = MISSING
    mass: float = MISSING

    def __post_init__(self) -> None:
        _check_keyed_plug(self)

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
    wall_thickness:    thickness of the bore and funnel boxes behind their faces [m].
    floor_thickness:   thickness of the box closing the bottom of the bore [m].
    """

    sides: int = MISSING
    plug_inradius: float = MISSING
    clearance: float = MISSING
    insertion_depth: float = MISSING
    funnel_angle_deg: float = MISSING
    funnel_depth: float = MISSING
    wall_thickness: float = MISSING
    floor_thickness: float = MISSING

    def __post_init__(self) -> None:
        _check_keyed_socket(self)

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


def _check_keyed_plug(p: KeyedPlugGeometry) -> None:
    _check_numbers(p, ("inradius", "length", "chamfer_angle_deg", "chamfer_length", "mass"))
    _check_sides("KeyedPlugGeometry.sides", p.sides)
    for name in ("inradius", "length", "chamfer_length", "mass"):
        _positive(f"KeyedPlugGeometry.{name}", getattr(p, name))
    require(
        0.0 < p.chamfer_angle_deg < 80.0,
        "KeyedPlugGeometry.chamfer_angle_deg",
        "in the open interval (0, 80) degrees",
        p.chamfer_angle_deg,
    )
    require(
        p.chamfer_length < p.length,
        "KeyedPlugGeometry.chamfer_length",
        f"shorter than KeyedPlugGeometry.length = {p.length} m",
        p.chamfer_length,
    )
    max_chamfer = 0.9 * p.inradius / math.tan(math.radians(p.chamfer_angle_deg))
    require(
        p.chamfer_length <= max_chamfer,
        "KeyedPlugGeometry.chamfer_length",
        f"at most {max_chamfer:.6g} m for inradius {p.inradius} m and chamfer angle "
        f"{p.chamfer_angle_deg} deg (the chamfer may remove at most 90 % of the inradius)",
        p.chamfer_length,
    )


def _check_keyed_socket(s: KeyedSocketGeometry) -> None:
    _check_numbers(
        s,
        (
            "plug_inradius",
            "clearance",
            "insertion_depth",
            "funnel_angle_deg",
            "funnel_depth",
            "wall_thickness",
            "floor_thickness",
        ),
    )
    _check_sides("KeyedSocketGeometry.sides", s.sides)
    for name in ("plug_inradius", "insertion_depth", "funnel_depth", "wall_thickness", "floor_thickness"):
        _positive(f"KeyedSocketGeometry.{name}", getattr(s, name))
    require(
        0.0 < s.clearance < s.plug_inradius,
        "KeyedSocketGeometry.clearance",
        f"> 0 and < plug_inradius = {s.plug_inradius} m (the gap between parallel plug and bore faces)",
        s.clearance,
    )
    require(
        0.0 < s.funnel_angle_deg < 80.0,
        "KeyedSocketGeometry.funnel_angle_deg",
        "in the open interval (0, 80) degrees",
        s.funnel_angle_deg,
    )


def _check_sides(setting: str, sides: object) -> None:
    low, high = SIDES_RANGE
    require(_is_int(sides) and low <= sides <= high, setting, f"an integer in [{low}, {high}]", sides)  # type: ignore[operator]


def check_keyed_fit(plug: KeyedPlugGeometry, socket: KeyedSocketGeometry) -> None:
    """Raise ValueError unless ``plug`` can be inserted into ``socket``: same number of
    sides, a smaller inradius than the bore's, longer than the bore is deep."""
    require(
        plug.sides == socket.sides,
        "KeyedSocketGeometry.sides",
        f"equal to KeyedPlugGeometry.sides = {plug.sides} (the key)",
        socket.sides,
    )
    require(
        plug.inradius < socket.bore_inradius,
        "KeyedPlugGeometry.inradius",
        f"smaller than the socket's bore inradius {socket.bore_inradius:.6g} m "
        "(KeyedSocketGeometry.plug_inradius + clearance)",
        plug.inradius,
    )
    require(
        plug.length > socket.insertion_depth,
        "KeyedPlugGeometry.length",
        f"longer than KeyedSocketGeometry.insertion_depth = {socket.insertion_depth} m",
        plug.length,
    )
