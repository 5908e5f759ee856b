"""Whitney's boundaries over the plane of the jamming map (conf/experiment/jamming_map.yaml).

The map's plane: the seat is off by ``x`` along the socket's x axis and the socket's axis
is tilted by θ about the seat, leaning towards +x; the plug arrives upright, its tip on the
believed axis (x = 0). θ is then the plug's tilt relative to the socket (Whitney's θ₀)
and, in the socket's frame, the plug's axis crosses the height s above the seat at

    u(s) = −(x / cos θ + s tan θ)

from the socket's axis (a world point (X, Z) from the seat is u = (X − x) cos θ − Z sin θ,
s = (X − x) sin θ + Z cos θ; put X = 0). The boundaries, in this module's names, with the
closed forms of :mod:`compliant_docking.evaluation.peg_in_hole` for our geometry:

- **funnel capture** (the funnel's mouth): the tip lands inside the mouth, at height
  s_m = H + h_f, when |u(s_m)| ≤ R_m − r_t (:attr:`PegInHole.funnel_capture`), i.e.
  x ∈ [−c_f cos θ − s_m sin θ, c_f cos θ − s_m sin θ];
- **chamfer capture**: the plug's chamfer meets the bore's lip (height H) without the
  funnel, |u(H)| ≤ δ + h_c tan α (:attr:`PegInHole.chamfer_capture`); outside it (but
  inside the mouth) the tip lands on the funnel and must slide across it first;
- **two-point contact before the seat**: a rigid plug tilted θ touches both sides of the
  bore once l sin θ + d cos θ = D, at an engaged length l shorter than the H − h_c of
  cylinder the bore holds when the tip is on the seat, for θ above
  :func:`~compliant_docking.evaluation.peg_in_hole.two_point_tilt` at l = H − h_c;
- **wedging**: two-point contact starting with l < μ d, for θ above the exact
  :func:`~compliant_docking.evaluation.peg_in_hole.wedging_tilt`; Whitney's small-angle
  c/μ, c = (D − d)/D, is given beside it.

The plug's own corners move by r sin θ with its tilt (0.87 mm at 5°); the capture lines
follow its axis, as Whitney's do. A compliant support lets the plug turn, so two-point
contact starts a little deeper than the rigid line says (docs/peg_in_hole.md: 0.1–0.6 mm),
and in two-point contact the insertion needs force (≈ 2 μ K_θ (θ₀ − θ)/l) rather than stops.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from compliant_docking.config.geometry import PlugGeometry, SocketGeometry
from compliant_docking.evaluation.peg_in_hole import PegInHole, two_point_tilt


@dataclass(frozen=True)
class MapBoundaries:
    """The theory's boundaries over (x [m], tilt [deg]) for one plug and socket."""

    funnel_capture_m: float  # c_f = R_m − r_t
    chamfer_capture_m: float  # c_c = δ + h_c tan α
    mouth_height_m: float  # s_m = H + h_f, the mouth above the seat
    lip_height_m: float  # H, the bore's lip above the seat
    two_point_tilt_deg: float  # rigid two-point contact before the seat above this tilt
    wedging_tilt_deg: float  # exact; inf when no tilt wedges
    wedging_tilt_small_angle_deg: float  # Whitney's c/μ

    @classmethod
    def of(cls, peg: PegInHole) -> MapBoundaries:
        """The boundaries of ``peg``'s plug, socket and friction (its support and its own
        errors do not enter)."""
        r, big_r = peg.plug_radius, peg.bore_radius
        return cls(
            funnel_capture_m=peg.funnel_capture,
            chamfer_capture_m=peg.chamfer_capture,
            mouth_height_m=peg.bore_depth + peg.funnel_depth,
            lip_height_m=peg.bore_depth,
            two_point_tilt_deg=math.degrees(two_point_tilt(big_r, r, peg.bore_depth - peg.chamfer_length)),
            wedging_tilt_deg=math.degrees(peg.wedging_tilt),
            wedging_tilt_small_angle_deg=(
                math.degrees((big_r - r) / big_r / peg.friction) if peg.friction > 0 else math.inf
            ),
        )

    @classmethod
    def for_interface(cls, plug: PlugGeometry, socket: SocketGeometry, friction: float) -> MapBoundaries:
        """The boundaries of our plug and socket (errors in the plane through face 0's centre,
        where the polygonal clearance is the nominal one) at sliding friction ``friction``."""
        unit = 1.0  # the support's stiffnesses and compliance centre: they do not enter
        peg = PegInHole.for_interface(plug, socket, lateral_stiffness=unit, angular_stiffness=unit,
                                      compliance_height=0.0, friction=friction)  # fmt: skip
        return cls.of(peg)

    def funnel_limits(self, tilt_deg: float) -> tuple[float, float]:
        """The x [m] whose tip lands inside the funnel's mouth at this tilt: [low, high]."""
        return _limits(self.funnel_capture_m, self.mouth_height_m, tilt_deg)

    def chamfer_limits(self, tilt_deg: float) -> tuple[float, float]:
        """The x [m] whose chamfer meets the bore's lip without the funnel: [low, high]."""
        return _limits(self.chamfer_capture_m, self.lip_height_m, tilt_deg)

    def region(self, x: float, tilt_deg: float) -> str:
        """What the theory says of one error: "missed" (outside the mouth), "wedged",
        "two-point" (two-point contact before the seat), "funnel" (lands on the funnel,
        then one-point) or "chamfer" (the chamfer meets the lip, then one-point)."""
        low, high = self.funnel_limits(tilt_deg)
        if not low <= x <= high:
            return "missed"
        if tilt_deg > self.wedging_tilt_deg:
            return "wedged"
        if tilt_deg > self.two_point_tilt_deg:
            return "two-point"
        low, high = self.chamfer_limits(tilt_deg)
        return "chamfer" if low <= x <= high else "funnel"


def _limits(capture: float, height: float, tilt_deg: float) -> tuple[float, float]:
    """|x / cos θ + height tan θ| ≤ capture, solved for x."""
    theta = math.radians(tilt_deg)
    centre, half = -height * math.sin(theta), capture * math.cos(theta)
    return centre - half, centre + half
