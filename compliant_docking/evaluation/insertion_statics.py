"""The contact states of Whitney's planar quasi-static insertion, depth by depth.

:class:`~compliant_docking.evaluation.peg_in_hole.PegInHole` holds the peg, the hole and
the support; :func:`insertion_curve` finds, at each depth, the state in which the peg
rests: free, or touching the hole at one or two of its candidate contacts, each obeying
the equations of docs/peg_in_hole.md:

- the support: K_x (x_c − x_c0) = Σ f_i u_x,i and K_θ (θ − θ_0) = Σ f_i m_i, with x_c the
  compliance centre's lateral position (x_c0 = e_0 + L_g θ_0 at rest), f_i ≥ 0 a contact's
  normal force, u_i the force per unit normal force on the peg (normal plus sliding
  friction μ, resisting the insertion), m_i its moment about the compliance centre;
- the geometry: each touching contact's gap (linear in x_c and θ, small angles) is zero,
  and no other gap is negative.

The state is found by trying free, then each single contact, then each pair (Cramer's
rule on 2×2 and 3×3 linear systems); the force directions and moment arms, which depend
weakly on θ, are refined by fixed-point iteration.  The first state that is consistent
(no negative gap, no pulling contact) is the answer; with sliding friction it is unique.

Candidate contacts, on either side σ = ±1 (σ = +1 is +x): the tip face's corner (radius
r_t, the chamfer's lower end) and the chamfer edge (radius r, its upper end), each on the
funnel face above the lip or on the bore wall below it; and the bore's lip (its upper
edge) on the plug's chamfer or on its cylindrical side.  Whitney's phases are: chamfer
crossing (a corner on the funnel, or the lip on the chamfer), one-point contact (the
chamfer edge on the wall, or the lip on the side) and two-point contact (the chamfer edge
on one wall and the lip on the other side).  When two-point contact starts inside
Whitney's wedging condition (the line between the two contacts inside both friction
cones), the peg is wedged: it goes no deeper, whatever the force.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from itertools import combinations

import numpy as np

from compliant_docking.evaluation.peg_in_hole import PegInHole

#: a gap this far below zero [m] still counts as touching, not penetrating
GAP_TOLERANCE = 1e-9
#: fixed-point iterations on the tilt-dependent gaps, force directions and moment arms
#: (each contracts the error by about the tilt change); a state that has not converged to
#: 1e-12 rad by then is rejected
ITERATIONS = 12
#: a candidate state turning the peg further than this from its rest tilt [rad] is rejected
#: (small-angle contacts only; a far-off root of the linearised equations is not a state)
MAX_ROTATION = 0.3

#: phases of an insertion, as :attr:`InsertionCurve.phase` names them
FREE, CROSSING, ONE_POINT, TWO_POINT, WEDGED, OTHER = (
    "free",
    "chamfer crossing",
    "one-point",
    "two-point",
    "wedged",
    "other",
)


@dataclass(frozen=True)
class Contact:
    """One candidate contact, linearised about a tilt: gap ≈ g0 + a x_c + b θ [m] (exact in
    x_c; a = −σ); the touching point at axial height s above the tip and distance rho from
    the axis, on side σ; the touched surface inclined ``incline`` from the hole's axis
    (0: parallel to it; positive: leaning out of the hole going up)."""

    name: str
    side: int
    g0: float
    a: float
    b: float
    s: float
    rho: float
    incline: float
    on_wall: bool  # a plug corner on the bore wall (for two-point contact)
    lip_on_side: bool  # the bore's lip on the plug's cylinder

    def gap(self, x_c: float, theta: float) -> float:
        return self.g0 + self.a * x_c + self.b * theta

    def force(self, p: PegInHole) -> tuple[float, float]:
        """(u_x, u_z): the force on the peg per newton of normal force (friction included)."""
        g, mu = self.incline, p.friction
        return -self.side * (math.cos(g) - mu * math.sin(g)), math.sin(g) + mu * math.cos(g)

    def arm(self, p: PegInHole, theta: float) -> tuple[float, float]:
        """(X, Z): the touching point relative to the compliance centre [m]."""
        return _offset(p, theta, self.s, self.side * self.rho)

    def moment(self, p: PegInHole, theta: float) -> float:
        """m: the moment of :meth:`force` about the compliance centre, in the sense of θ."""
        u_x, u_z = self.force(p)
        x, z = self.arm(p, theta)
        return u_x * z - u_z * x


def _offset(p: PegInHole, theta: float, s: float, lateral: float) -> tuple[float, float]:
    """(X, Z) of the plug point at axial height s above the tip and signed distance
    ``lateral`` from the axis, relative to the compliance centre, at tilt θ (exact)."""
    along = s - p.compliance_height
    c, n = math.cos(theta), math.sin(theta)
    return along * n + lateral * c, along * c - lateral * n


def _gaps(
    p: PegInHole, centre_height: float, theta: float
) -> list[tuple[str, int, float, float, float, float, bool, bool]]:
    """Every candidate contact at compliance-centre height ``centre_height`` above the seat
    and tilt θ, with x_c = 0: (name, side, gap, s, rho, incline, on_wall, lip_on_side)."""
    r, r_t, h_c = p.plug_radius, p.tip_radius, p.chamfer_length
    big_r, big_h, lg = p.bore_radius, p.bore_depth, p.compliance_height
    tan_a, tan_b = math.tan(p.chamfer_angle), math.tan(p.funnel_angle)
    cos_t, sin_t = math.cos(theta), math.sin(theta)
    found = []
    for side in (1, -1):
        for corner, s, rho in (("tip corner", 0.0, r_t), ("chamfer edge", h_c, r)):
            x, z = _offset(p, theta, s, side * rho)
            height = centre_height + z - big_h  # above the lip
            if height > p.funnel_depth or height < -big_h:
                continue
            if height >= 0.0:  # on the funnel face
                gap = big_r + height * tan_b - side * x
                found.append((f"{corner} on funnel", side, gap, s, rho, p.funnel_angle, False, False))
            else:
                found.append((f"{corner} on wall", side, big_r - side * x, s, rho, 0.0, True, False))
        # the plug's axial height s level with the lip: centre_height + Z(s) = H, Z linear in s
        shaft = lg + (big_h - centre_height + side * r * sin_t) / cos_t
        if shaft >= h_c:  # the lip on the cylinder
            x, _ = _offset(p, theta, shaft, side * r)
            found.append(("lip on side", side, big_r - side * x, shaft, r, side * theta, False, True))
            continue
        slope = cos_t - side * tan_a * sin_t
        chamfer = (big_h - centre_height + lg * cos_t + side * r_t * sin_t) / slope
        if 0.0 <= chamfer < h_c:  # the lip on the chamfer
            rho = r_t + chamfer * tan_a
            x, _ = _offset(p, theta, chamfer, side * rho)
            incline = p.chamfer_angle + side * theta
            found.append(("lip on chamfer", side, big_r - side * x, chamfer, rho, incline, False, False))
    return found


#: step [rad] of the central difference giving a gap's derivative in θ
_DTHETA = 1e-7


@lru_cache(maxsize=4096)
def candidate_contacts(p: PegInHole, centre_height: float, theta: float) -> tuple[Contact, ...]:
    """Every candidate contact at compliance-centre height ``centre_height`` [m] above the
    seat, linearised about tilt ``theta``; a plug corner is on the funnel above the lip and
    on the wall below it, the lip on the chamfer or on the cylinder."""
    here = _gaps(p, centre_height, theta)
    ahead = {(g[0], g[1]): g[2] for g in _gaps(p, centre_height, theta + _DTHETA)}
    behind = {(g[0], g[1]): g[2] for g in _gaps(p, centre_height, theta - _DTHETA)}
    found = []
    for name, side, gap, s, rho, incline, on_wall, lip in here:
        key = (name, side)
        if key in ahead and key in behind:
            b = (ahead[key] - behind[key]) / (2.0 * _DTHETA)
        elif key in ahead or key in behind:  # at the end of its range: one-sided
            b = (ahead[key] - gap) / _DTHETA if key in ahead else (gap - behind[key]) / _DTHETA
        else:
            b = 0.0
        found.append(Contact(name, side, gap - b * theta, -float(side), b, s, rho, incline, on_wall, lip))
    return tuple(found)


@dataclass(frozen=True)
class State:
    """The peg at one drive position: compliance centre x_c [m], tilt θ [rad], and the
    touching contacts with their normal forces [N]."""

    x_c: float
    theta: float
    contacts: tuple[Contact, ...] = ()
    normal_forces: tuple[float, ...] = ()

    def forces(self, p: PegInHole) -> tuple[float, float]:
        """(F_x, F_z) [N]: the contact force on the peg; F_z > 0 resists the insertion."""
        f_x = f_z = 0.0
        for c, f in zip(self.contacts, self.normal_forces):
            u_x, u_z = c.force(p)
            f_x, f_z = f_x + f * u_x, f_z + f * u_z
        return f_x, f_z


def _key(c: Contact) -> tuple[str, int]:
    return c.name, c.side


def _consistent(p: PegInHole, height: float, state: State | None) -> bool:
    """A converged state without pulling contact whose touching contacts still exist at its
    tilt, and in which no other candidate penetrates."""
    if state is None or abs(state.theta - p.tilt) > MAX_ROTATION:
        return False
    if any(f < -1e-12 for f in state.normal_forces):
        return False
    touching = {_key(c) for c in state.contacts}
    candidates = candidate_contacts(p, height, state.theta)
    if not touching <= {_key(c) for c in candidates}:
        return False
    return all(c.gap(state.x_c, state.theta) >= -GAP_TOLERANCE for c in candidates if _key(c) not in touching)


def _find(p: PegInHole, height: float, theta: float, key: tuple[str, int]) -> Contact | None:
    return next((c for c in candidate_contacts(p, height, theta) if _key(c) == key), None)


def _solve2(
    a11: float, a12: float, a21: float, a22: float, b1: float, b2: float
) -> tuple[float, float] | None:
    """Cramer's rule for a 2×2 system (None when singular)."""
    det = a11 * a22 - a12 * a21
    if abs(det) < 1e-15:
        return None
    return (b1 * a22 - a12 * b2) / det, (a11 * b2 - b1 * a21) / det


def _rest_centre(p: PegInHole) -> float:
    """x_c0: the compliance centre's lateral position at rest [m]."""
    return p.lateral_error + p.compliance_height * math.sin(p.tilt)


def _fixed_point(p: PegInHole, theta: float, step: Callable[[float], State | None]) -> State | None:
    """Iterate ``step`` (the state solved with the tilt-dependent terms taken at θ) until its
    tilt reproduces θ to 1e-12 rad; None if it fails, turns past MAX_ROTATION or has not
    converged after ITERATIONS."""
    for _ in range(ITERATIONS):
        state = step(theta)
        if state is None or abs(state.theta - p.tilt) > MAX_ROTATION:
            return None
        if abs(state.theta - theta) < 1e-12:
            return state
        theta = state.theta
    return None


def _one_contact(p: PegInHole, height: float, key: tuple[str, int], theta: float) -> State | None:
    """Solve K_x (x_c − x_c0) = f u_x, K_θ (θ − θ_0) = f m, gap = 0 for (x_c, θ, f)."""
    k_x, k_t, x_c0 = p.lateral_stiffness, p.angular_stiffness, _rest_centre(p)

    def step(theta: float) -> State | None:
        c = _find(p, height, theta, key)
        if c is None:
            return None
        # x_c = x_c0 + f u_x / K_x and θ = θ_0 + f m / K_θ into a x_c + b θ = −g0
        u_x, _ = c.force(p)
        m = c.moment(p, theta)
        slope = c.a * u_x / k_x + c.b * m / k_t
        if abs(slope) < 1e-15:
            return None
        f = -(c.g0 + c.a * x_c0 + c.b * p.tilt) / slope
        return State(x_c0 + f * u_x / k_x, p.tilt + f * m / k_t, (c,), (f,))

    return _fixed_point(p, theta, step)


def _two_contacts(
    p: PegInHole, height: float, keys: tuple[tuple[str, int], ...], theta: float
) -> State | None:
    """Both gaps zero fix (x_c, θ); the support's force and moment then fix both normal forces."""
    k_x, k_t, x_c0 = p.lateral_stiffness, p.angular_stiffness, _rest_centre(p)

    def step(theta: float) -> State | None:
        c1, c2 = _find(p, height, theta, keys[0]), _find(p, height, theta, keys[1])
        if c1 is None or c2 is None:
            return None
        position = _solve2(c1.a, c1.b, c2.a, c2.b, -c1.g0, -c2.g0)
        if position is None:
            return None
        x_c, new_theta = position
        (u1, _), (u2, _) = c1.force(p), c2.force(p)
        m1, m2 = c1.moment(p, new_theta), c2.moment(p, new_theta)
        forces = _solve2(u1, u2, m1, m2, k_x * (x_c - x_c0), k_t * (new_theta - p.tilt))
        return None if forces is None else State(x_c, new_theta, (c1, c2), forces)

    return _fixed_point(p, theta, step)


def solve_state(
    p: PegInHole,
    centre_height: float,
    theta_guess: float | None = None,
    hint: tuple[tuple[str, int], ...] = (),
) -> State | None:
    """The quasi-static state with the compliance centre ``centre_height`` [m] above the
    seat, or None when no state with at most two contacts is consistent.  ``hint``: the
    contacts of a neighbouring state, tried first (the answer does not depend on it, but
    where two descriptions of one contact meet, e.g. the chamfer edge level with the lip)."""
    theta = p.tilt if theta_guess is None else theta_guess
    free = State(_rest_centre(p), p.tilt)
    if _consistent(p, centre_height, free):
        return free
    keys = [_key(c) for c in candidate_contacts(p, centre_height, theta)]
    sets: list[tuple[tuple[str, int], ...]] = [hint] if hint else []
    sets += [(key,) for key in keys] + list(combinations(keys, 2))
    for contacts in sets:
        if len(contacts) == 1:
            state = _one_contact(p, centre_height, contacts[0], theta)
        else:
            state = _two_contacts(p, centre_height, contacts, theta)
        if _consistent(p, centre_height, state):
            return state
    return None


def phase_of(state: State | None) -> str:
    """Whitney's name for a state's contacts (see the module doc)."""
    if state is None:
        return OTHER
    contacts = state.contacts
    if not contacts:
        return FREE
    if len(contacts) == 1:
        return ONE_POINT if contacts[0].on_wall or contacts[0].lip_on_side else CROSSING
    first, second = contacts
    if first.side != second.side and {first.on_wall, second.on_wall} == {True, False}:
        if first.lip_on_side or second.lip_on_side:
            return TWO_POINT
    return OTHER


def wedges(p: PegInHole, state: State) -> bool:
    """Whitney's wedging condition for a two-contact state: the line joining the contacts
    lies inside both friction cones (for walls parallel to the axis: engaged length < μ d)."""
    if len(state.contacts) != 2:
        return False
    cone = math.cos(math.atan(p.friction))
    points = [np.array(c.arm(p, state.theta)) for c in state.contacts]
    normals = [np.array([-c.side * math.cos(c.incline), math.sin(c.incline)]) for c in state.contacts]
    for i, j in ((0, 1), (1, 0)):
        line = points[j] - points[i]
        if float(normals[i] @ line) / float(np.linalg.norm(line)) < cone - 1e-12:
            return False
    return True


@dataclass
class InsertionCurve:
    """Theory along an insertion, per drive position: the drive depth [m] (where the tip
    would be without contact, below the lip), the tip's depth below the lip and lateral
    position [m], the phase, the insertion force F_z [N] (> 0 resists), the lateral contact
    force F_x [N] (on the peg) and the tilt θ [rad].  Forces are inf once wedged."""

    drive_depth: np.ndarray
    depth: np.ndarray
    tip_offset: np.ndarray
    phase: list[str]
    insertion_force: np.ndarray
    lateral_force: np.ndarray
    tilt: np.ndarray
    contacts: list[tuple[str, ...]] = field(default_factory=list)

    def onset(self, phase: str) -> float:
        """Tip depth [m] where ``phase`` first holds (nan if never)."""
        hits = [d for d, ph in zip(self.depth, self.phase) if ph == phase]
        return float(hits[0]) if hits else math.nan

    def first_contact(self) -> float:
        """Tip depth [m] of the first contact (nan if none)."""
        hits = [d for d, ph in zip(self.depth, self.phase) if ph != FREE]
        return float(hits[0]) if hits else math.nan

    def stall_depth(self, push: float) -> float:
        """Jamming under a push limited to ``push`` [N]: the tip depth where the insertion
        first needs more (nan if it never does)."""
        over = np.flatnonzero(self.insertion_force > push)
        return float(self.depth[over[0]]) if over.size else math.nan


def insertion_curve(p: PegInHole, drive_depths: np.ndarray) -> InsertionCurve:
    """The quasi-static state at each of ``drive_depths`` (increasing) [m]: where the tip
    would be below the lip if nothing touched (the drive moves the compliance centre)."""
    drive = np.asarray(drive_depths, dtype=float)
    n = len(drive)
    force, lateral, tilt, tip, depth = (np.full(n, math.nan) for _ in range(5))
    phases: list[str] = []
    names: list[tuple[str, ...]] = []
    theta, wedged_at = p.tilt, None
    hint: tuple[tuple[str, int], ...] = ()
    for i, d in enumerate(drive):
        height = p.bore_depth - d + p.compliance_height * math.cos(p.tilt)
        state = None if wedged_at is not None else solve_state(p, height, theta, hint)
        hint = tuple(_key(c) for c in state.contacts) if state is not None else ()
        if (
            state is not None
            and phase_of(state) == TWO_POINT
            and TWO_POINT not in phases
            and wedges(p, state)
        ):
            wedged_at = i  # two-point contact starts inside the wedging condition
        if wedged_at is not None:
            phases.append(WEDGED)
            names.append(())
            force[i] = lateral[i] = math.inf
            depth[i], tilt[i], tip[i] = depth[wedged_at - 1], tilt[wedged_at - 1], tip[wedged_at - 1]
            continue
        phases.append(phase_of(state))
        if state is None:
            names.append(())
            theta = p.tilt
            continue
        theta = state.theta
        lateral[i], force[i] = state.forces(p)
        tilt[i] = state.theta
        tip[i] = state.x_c - p.compliance_height * math.sin(state.theta)
        depth[i] = p.bore_depth - (height - p.compliance_height * math.cos(state.theta))
        names.append(tuple(f"{c.name} {'+' if c.side > 0 else '-'}" for c in state.contacts))
    return InsertionCurve(drive, depth, tip, phases, force, lateral, tilt, names)
