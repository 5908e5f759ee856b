"""Whitney's quasi-static theory of a compliantly supported rigid peg entering a hole.

D. E. Whitney, "Quasi-static assembly of compliantly supported rigid parts", J. Dyn. Sys.
Meas. Control 104(1):65-77, 1982.  docs/peg_in_hole.md derives every formula here in this
module's notation and says where our interface departs from Whitney's.

The model is planar (the plane holding the lateral error and the tilt), rigid and slow:
the peg (our plug: radius r, a conical chamfer of angle α from its axis and axial length
h_c at the tip) hangs on a support that is a lateral spring K_x and an angular spring K_θ
about a compliance centre on the peg's axis, L_g above the tip (the tip face's centre, the
TCP).  The support is driven down the hole's axis; the axial direction is rigid.  At rest
(no contact) the tip is ``lateral_error`` off the axis and the peg is tilted by ``tilt``
(positive: the peg's upper end towards +x, so the tip leans back towards -x).  The hole
(our socket) is a bore of radius R and depth H under a conical funnel of half-angle β and
axial length h_f; every contact has Coulomb friction μ and slides (the peg always moves
down relative to the hole).

The closed forms below are Whitney's results in this notation (small angles):

- chamfer (funnel) crossing: F_z / F_x = tan(γ + atan μ) for a contact on a surface
  inclined γ from the axis (:func:`crossing_force_ratio`);
- one-point contact: normal force f = K_x K_θ (ε − δ) / (K_θ + K_x L (L − μ r)), with ε the
  rest lateral position of the touching point, δ = R − r and L the compliance centre's
  height above that point (:func:`one_point_force`);
- two-point contact at engaged length l when l sin θ + d cos θ = D (d = 2r, D = 2R)
  (:func:`two_point_tilt`, :func:`two_point_engaged_length`);
- wedging when two-point contact starts with l < μ d (:func:`wedged`), i.e. for a tilt
  above :func:`wedging_tilt` (≈ (R − r)/(μ r), Whitney's c/μ);
- a compliance centre L above a point stiffens rotations about that point to
  K_θ + K_x L² (:func:`rotational_stiffness_about`).

:mod:`compliant_docking.evaluation.insertion_statics` follows the contact states along the
whole insertion with the same equations (the curve that is compared with simulation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from compliant_docking.config.geometry import PlugGeometry, SocketGeometry, require


def crossing_force_ratio(wall_angle: float, friction: float) -> float:
    """F_z / F_x while the peg slides down one surface inclined ``wall_angle`` [rad] from the
    hole's axis (a funnel or chamfer; 0 is a bore wall): tan(γ + atan μ).

    Whitney's chamfer-crossing ratio.  It is infinite (the chamfer locks) once γ + atan μ
    reaches 90°; for γ = 0 it is μ (one-point sliding on the wall).
    """
    total = wall_angle + math.atan(friction)
    return math.inf if total >= 0.5 * math.pi else math.tan(total)


def one_point_force(
    rest_offset: float,
    clearance: float,
    lateral_stiffness: float,
    angular_stiffness: float,
    lever: float,
    friction: float,
    radius: float,
) -> float:
    """Normal force [N] of one-point contact against a wall parallel to the axis (Whitney).

    ``rest_offset``: ε, where the touching point of the peg's side would be (off the hole's
    axis, towards the wall) without contact; ``clearance``: δ = R − r; ``lever``: L, the
    compliance centre's height above the touching point; ``radius``: r, the touching
    point's distance from the peg's axis.  f = K_x K_θ (ε − δ) / (K_θ + K_x L (L − μ r)),
    the lateral spring force the wall must supply, less what the tilt takes up.  Zero when
    the point would not reach the wall.  The insertion force is μ f (plus f times the
    tilt when the wall is the bore's edge pressing on the peg's side).
    """
    k_x, k_t = lateral_stiffness, angular_stiffness
    denominator = k_t + k_x * lever * (lever - friction * radius)
    require(
        denominator > 0.0, "K_θ + K_x L (L − μ r)", "> 0 (else the touching point rolls off)", denominator
    )
    return max(0.0, k_x * k_t * (rest_offset - clearance) / denominator)


def two_point_tilt(bore_radius: float, plug_radius: float, engaged_length: float) -> float:
    """Tilt [rad] at which a peg of radius r touches both sides of a bore of radius R with
    ``engaged_length`` l of its cylinder inside: l sin θ + d cos θ = D (d = 2r, D = 2R), so
    θ = asin(D / √(l² + d²)) − atan2(d, l) (≈ 2(R − r)/l), the smaller root: the first tilt
    at which the peg touches both sides (the other root lies past tan θ = l / d)."""
    d, big_d, l = 2.0 * plug_radius, 2.0 * bore_radius, engaged_length
    hypot = math.hypot(l, d)
    require(hypot >= big_d, "engaged_length", f"at least {math.sqrt(big_d**2 - d**2):.6g} m", l)
    return math.asin(big_d / hypot) - math.atan2(d, l)


def two_point_engaged_length(bore_radius: float, plug_radius: float, tilt: float) -> float:
    """Engaged length [m] at which a peg tilted by ``tilt`` [rad] touches both sides of the
    bore: l = (D − d cos θ) / sin θ (infinite at θ = 0: an upright peg never does)."""
    if tilt <= 0.0:
        return math.inf
    return (2.0 * bore_radius - 2.0 * plug_radius * math.cos(tilt)) / math.sin(tilt)


def wedged(engaged_length: float, plug_radius: float, friction: float) -> bool:
    """Whitney's wedging condition: two-point contact with l < μ d.  The line joining the
    two contacts then lies inside both friction cones, so the contact forces can hold each
    other without any applied force, and no insertion force frees the peg."""
    return engaged_length < friction * 2.0 * plug_radius


def wedging_tilt(bore_radius: float, plug_radius: float, friction: float) -> float:
    """Smallest tilt [rad] at which two-point contact starts inside the wedging length
    (l = μ d): D = d (cos θ + μ sin θ), so θ = atan μ − acos(D / (d √(1 + μ²))); for small
    clearance ≈ (R − r)/(μ r), Whitney's c/μ.  Infinite when no tilt can wedge."""
    ratio = bore_radius / (plug_radius * math.hypot(1.0, friction))
    return math.inf if ratio >= 1.0 else math.atan(friction) - math.acos(ratio)


def rotational_stiffness_about(
    height_below_centre: float, lateral_stiffness: float, angular_stiffness: float
) -> float:
    """Stiffness [N·m/rad] of the support against a rotation of the peg about a point
    ``height_below_centre`` L under the compliance centre: K_θ + K_x L².  At the
    compliance centre a force only translates the peg and a moment only rotates it."""
    return angular_stiffness + lateral_stiffness * height_below_centre**2


@dataclass(frozen=True)
class PegInHole:
    """One insertion of the planar model (SI units, angles in radians; see the module doc).

    ``bore_radius`` is the EFFECTIVE one in the plane of the errors: the plug radius plus
    the clearance the polygonal socket leaves along that plane (:meth:`for_interface`).
    """

    plug_radius: float  # r
    chamfer_angle: float  # α, from the plug's axis
    chamfer_length: float  # h_c, axial
    bore_radius: float  # R
    bore_depth: float  # H
    funnel_angle: float  # β, from the socket's axis
    funnel_depth: float  # h_f, axial
    lateral_stiffness: float  # K_x [N/m]
    angular_stiffness: float  # K_θ [N·m/rad]
    compliance_height: float  # L_g, above the tip along the plug's axis
    friction: float  # μ
    lateral_error: float = 0.0  # e_0, the tip's rest offset along +x
    tilt: float = 0.0  # θ_0

    def __post_init__(self) -> None:
        for name in ("plug_radius", "chamfer_length", "bore_depth", "funnel_depth"):
            require(getattr(self, name) > 0.0, f"PegInHole.{name}", "> 0 [m]", getattr(self, name))
        for name in ("chamfer_angle", "funnel_angle"):
            value = getattr(self, name)
            require(0.0 < value < 0.5 * math.pi, f"PegInHole.{name}", "in (0, π/2) [rad]", value)
        require(
            self.bore_radius > self.plug_radius, "PegInHole.bore_radius", "> plug_radius", self.bore_radius
        )
        require(
            self.tip_radius > 0.0,
            "PegInHole.chamfer_length",
            "short enough to leave a tip face",
            self.chamfer_length,
        )
        for name in ("lateral_stiffness", "angular_stiffness"):
            require(getattr(self, name) > 0.0, f"PegInHole.{name}", "> 0", getattr(self, name))
        require(self.friction >= 0.0, "PegInHole.friction", ">= 0", self.friction)
        require(
            abs(self.tilt) < 0.25 * math.pi, "PegInHole.tilt", "a small angle, |tilt| < π/4 [rad]", self.tilt
        )
        for f in fields(self):
            require(
                math.isfinite(getattr(self, f.name)), f"PegInHole.{f.name}", "finite", getattr(self, f.name)
            )

    @classmethod
    def for_interface(
        cls,
        plug: PlugGeometry,
        socket: SocketGeometry,
        *,
        lateral_stiffness: float,
        angular_stiffness: float,
        compliance_height: float,
        friction: float,
        lateral_error: float = 0.0,
        tilt_deg: float = 0.0,
        azimuth_deg: float = 0.0,
    ) -> PegInHole:
        """Our plug and socket, the errors in the plane at ``azimuth_deg`` from the socket's
        first face (0: through face 0's centre and a vertex of the plug's polygon, where the
        polygonal clearance is the nominal one)."""
        return cls(
            plug_radius=plug.radius,
            chamfer_angle=math.radians(plug.chamfer_angle_deg),
            chamfer_length=plug.chamfer_length,
            bore_radius=plug.radius + effective_clearance(plug, socket, math.radians(azimuth_deg)),
            bore_depth=socket.insertion_depth,
            funnel_angle=math.radians(socket.funnel_angle_deg),
            funnel_depth=socket.funnel_depth,
            lateral_stiffness=lateral_stiffness,
            angular_stiffness=angular_stiffness,
            compliance_height=compliance_height,
            friction=friction,
            lateral_error=lateral_error,
            tilt=math.radians(tilt_deg),
        )

    @property
    def clearance(self) -> float:
        """δ = R − r [m]."""
        return self.bore_radius - self.plug_radius

    @property
    def tip_radius(self) -> float:
        """r_t = r − h_c tan α, the radius of the flat tip face [m]."""
        return self.plug_radius - self.chamfer_length * math.tan(self.chamfer_angle)

    @property
    def mouth_radius(self) -> float:
        """R_m = R + h_f tan β [m]."""
        return self.bore_radius + self.funnel_depth * math.tan(self.funnel_angle)

    @property
    def chamfer_capture(self) -> float:
        """Largest lateral error [m] the plug's chamfer alone takes (its edge lands on the
        bore's lip): δ + h_c tan α."""
        return self.clearance + self.chamfer_length * math.tan(self.chamfer_angle)

    @property
    def funnel_capture(self) -> float:
        """Largest lateral error [m] the funnel takes (the tip face lands inside the mouth):
        R_m − r_t."""
        return self.mouth_radius - self.tip_radius

    @property
    def wedging_tilt(self) -> float:
        """:func:`wedging_tilt` of this peg and hole [rad]."""
        return wedging_tilt(self.bore_radius, self.plug_radius, self.friction)


def effective_clearance(plug: PlugGeometry, socket: SocketGeometry, azimuth: float) -> float:
    """Clearance [m] along the direction ``azimuth`` [rad] between our polygonal plug and
    socket: how far the plug's axis moves from the socket's axis in that direction before
    the plug's polygon (``segments`` vertices on the circle, one at azimuth 0) meets a bore
    face (``sectors`` faces tangent to the bore circle, face 0's normal at azimuth 0).

    Face k (normal at ψ_k) is met when the plug's support along ψ_k, r cos(angle from ψ_k
    to the nearest vertex), plus the offset's component along ψ_k reaches the bore radius.
    At azimuth 0 it is the nominal clearance; towards a polygon corner the plug wedges
    into the two faces there a little later.
    """
    n, m = socket.sectors, plug.segments
    best = math.inf
    for k in range(n):
        psi = 2.0 * math.pi * k / n
        along = math.cos(azimuth - psi)
        if along <= 1e-12:
            continue
        to_vertex = abs(math.remainder(psi, 2.0 * math.pi / m))
        support = plug.radius * math.cos(to_vertex)
        best = min(best, (socket.bore_radius - support) / along)
    return best
