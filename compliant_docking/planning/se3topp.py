r"""``trajectory=se3topp``: constant-screw geodesics with time-optimal bang-bang timing.

Same waypoints as ``twophase`` (start → pre-dock point ``standoff`` before the goal →
goal; see :func:`~compliant_docking.planning.twophase.docking_waypoints`). Segment
a → b is the SE(3) geodesic

    T(s) = T_a·Exp(ξ s),  ξ = log6(T_a⁻¹ T_b) = [ξ_v; ξ_ω] (body frame), s ∈ [0, 1],

timed by a bang-bang profile in s: accelerate at ``a_s`` up to the peak ``v_s``, cruise,
decelerate at −a_s (triangle when the cruise vanishes). In s-units the segment lasts

    T = 2/√a_s         if √a_s ≤ v_s (triangle),
    T = 1/v_s + v_s/a_s otherwise (trapezoid).

Reference (world axes at the TCP, the project's convention; R = R(s), R_a = R(0)):

    ẋ = R ξ_v ṡ,                       ω = R_a ξ_ω ṡ,
    ẍ = R (ξ_v s̈ + (ξ_ω × ξ_v) ṡ²),    ω̇ = R_a ξ_ω s̈,

and the body twist is simply V_b = ξ ṡ, V̇_b = ξ s̈.

Limits. With b = ‖ξ_v‖ [m], w = ‖ξ_ω‖ [rad] and c = ‖ξ_ω × ξ_v‖ [m], the norms are
‖ẋ‖ = b ṡ, ‖ω‖ = w ṡ, ‖ω̇‖ = w |s̈| and, as ξ_v ⟂ ξ_ω × ξ_v, ‖ẍ‖² = b² s̈² + c² ṡ⁴
exactly. The limits bound these Euclidean norms of the linear and the angular part
(which bounds every world-axis component too). Without the centripetal term (c = 0:
pure translation, pure rotation or a pure screw) the profile is the classic one,
v_s = min(v/b, ω/w), a_s = min(a/b, α/w). With it, the peak ṡ also bounds the
acceleration during the ramps, ‖ẍ‖² ≤ b² a_s² + c² v_p⁴ with v_p = min(v_s, √a_s) the
speed actually reached; the planner then picks the peak v_p that minimises the time
under a_s(v_p) = min(α/w, √(a² − c² v_p⁴)/b) (a one-dimensional search).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize_scalar

from compliant_docking.planning.base import Planner, ReferenceTable, Waypoints
from compliant_docking.planning.twophase import (
    MIN_LENGTH,
    docking_waypoints,
    rotation_path,
    segment_index,
)

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Limits:
    """Per-segment limits: linear speed [m/s] and acceleration [m/s²], angular speed [rad/s]
    and acceleration [rad/s²] (bounds on the Euclidean norms)."""

    v: float
    a: float
    omega: float
    alpha: float

    def check(self, segment: str) -> None:
        for label, value in (
            ("v_max", self.v),
            ("a_max", self.a),
            ("omega_max", self.omega),
            ("alpha_max", self.alpha),
        ):
            if not value > 0.0:
                raise ValueError(f"trajectory.{label}_{segment} must be > 0, got {value}")


def bang_bang_time(v_s: float, a_s: float) -> float:
    """Duration [s] of the bang-bang profile over s ∈ [0, 1] with peak ṡ ≤ v_s [1/s] and
    |s̈| = a_s [1/s²]: 2/√a_s if √a_s ≤ v_s (triangle), else 1/v_s + v_s/a_s (trapezoid)."""
    if not (v_s > 0.0 and a_s > 0.0):
        raise ValueError(f"bang-bang limits must be > 0, got v_s={v_s}, a_s={a_s}")
    root = math.sqrt(a_s)
    return 2.0 / root if root <= v_s else 1.0 / v_s + v_s / a_s


def screw_profile(xi: np.ndarray, limits: Limits) -> tuple[float, float]:
    """The (peak ṡ [1/s], |s̈| [1/s²]) of the fastest bang-bang profile along the screw ``xi``
    that keeps ‖ẋ‖ ≤ v, ‖ẍ‖ ≤ a, ‖ω‖ ≤ ω_max, ‖ω̇‖ ≤ α_max along the whole segment.

    The peak returned is the one actually reached: for a triangle it is √a_s.
    """
    xi_v, xi_w = np.asarray(xi[:3], float), np.asarray(xi[3:], float)
    b, w = float(np.linalg.norm(xi_v)), float(np.linalg.norm(xi_w))
    c = float(np.linalg.norm(np.cross(xi_w, xi_v)))
    inf = math.inf
    v_cap = min(limits.v / b if b > 0 else inf, limits.omega / w if w > 0 else inf)
    a_rot = limits.alpha / w if w > 0 else inf
    if c <= 1e-12 * b:  # no centripetal term (b = 0 gives c = 0): the classic profile
        a_s = min(limits.a / b if b > 0 else inf, a_rot)
        return min(v_cap, math.sqrt(a_s)), a_s

    def accel_limit(v_p: float) -> float:
        """Largest |s̈| with the linear acceleration in bounds at peak speed v_p."""
        room = limits.a**2 - (c * v_p * v_p) ** 2
        return min(a_rot, math.sqrt(room) / b) if room > 0 else 0.0

    # feasible peaks: v_p ≤ v_cap, centripetal c v_p² < a, and v_p² ≤ a_s(v_p) (the peak is reached)
    hi = min(v_cap, math.sqrt(limits.a / c) * (1 - 1e-12))
    lo_a = accel_limit(0.0)
    # v² ≤ a_s(v): a_s decreases with v, so the feasible set is an interval [0, v*]
    lo, up = 0.0, hi
    if up * up > accel_limit(up):
        for _ in range(200):
            mid = 0.5 * (lo + up)
            if mid * mid <= accel_limit(mid):
                lo = mid
            else:
                up = mid
        hi = lo
    if not hi > 0.0 or lo_a <= 0.0:
        raise ValueError("se3topp: no feasible profile under the given limits")

    def duration(v_p: float) -> float:
        return 1.0 / v_p + v_p / accel_limit(v_p)

    res = minimize_scalar(duration, bounds=(hi * 1e-6, hi), method="bounded", options={"xatol": hi * 1e-12})
    v_p = float(res.x) if duration(float(res.x)) < duration(hi) else hi
    a_s = accel_limit(v_p)
    return min(v_p, math.sqrt(a_s)), a_s


def bang_bang(u: np.ndarray, v_p: float, a_s: float, T: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """s, ṡ [1/s], s̈ [1/s²] at local times u ∈ [0, T] [s] (clamped outside) of the profile
    with peak v_p and acceleration a_s. Ramp boundaries belong to the cruise (or, for a
    triangle, the switching instant to the deceleration)."""
    u = np.clip(np.asarray(u, dtype=float), 0.0, T)
    t_acc = v_p / a_s
    s, ds, dds = np.empty_like(u), np.empty_like(u), np.empty_like(u)
    up = u < t_acc
    down = u > T - t_acc
    cruise = ~(up | down)
    s[up], ds[up], dds[up] = 0.5 * a_s * u[up] ** 2, a_s * u[up], a_s
    r = T - u[down]
    s[down], ds[down], dds[down] = 1.0 - 0.5 * a_s * r**2, a_s * r, -a_s
    s[cruise] = 0.5 * a_s * t_acc**2 + v_p * (u[cruise] - t_acc)
    ds[cruise], dds[cruise] = v_p, 0.0
    end = u >= T  # exactly at rest at the end
    s[end], ds[end], dds[end] = 1.0, 0.0, 0.0
    return s, ds, dds


def world_to_body(rot: np.ndarray, twist: np.ndarray, accel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Body twist V_b = [Rᵀẋ; Rᵀω] and its derivative V̇_b = [Rᵀẍ − ω_b × v_b; Rᵀω̇] from the
    project's world-axes reference (one pose or arrays of poses)."""
    rot, twist, accel = np.asarray(rot, float), np.asarray(twist, float), np.asarray(accel, float)
    rt = np.swapaxes(rot, -1, -2)
    v_b = np.einsum("...ij,...j->...i", rt, twist[..., :3])
    w_b = np.einsum("...ij,...j->...i", rt, twist[..., 3:])
    dv_b = np.einsum("...ij,...j->...i", rt, accel[..., :3]) - np.cross(w_b, v_b)
    dw_b = np.einsum("...ij,...j->...i", rt, accel[..., 3:])
    return np.concatenate([v_b, w_b], axis=-1), np.concatenate([dv_b, dw_b], axis=-1)


@dataclass(frozen=True)
class _Screw:
    name: str
    t0: float
    T: float
    rot_a: np.ndarray
    pos_a: np.ndarray
    xi: np.ndarray  # body twist of the whole segment, [v; ω]
    v_p: float  # peak ṡ reached [1/s]
    a_s: float  # |s̈| on the ramps [1/s²]


def screw_pose(
    rot_a: np.ndarray, pos_a: np.ndarray, xi: np.ndarray, s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """T_a·Exp(ξ s) for every s: rotations (N, 3, 3) and positions (N, 3), vectorised.

    Exp(ξ s) = (Exp3(ω s), J(ω s)·v s); with n = ‖ω‖ and θ = n s,
    J(ω s) v s = v s + (1 − cos θ)/n² ω × v + (θ − sin θ)/n³ ω × (ω × v).
    """
    s = np.asarray(s, dtype=float)
    v, w = xi[:3], xi[3:]
    n = float(np.linalg.norm(w))
    if n < 1e-12:
        return np.broadcast_to(rot_a, (len(s), 3, 3)).copy(), pos_a + np.outer(s, rot_a @ v)
    theta = n * s
    wxv = np.cross(w, v)
    local_p = (
        np.outer(s, v)
        + np.outer((2.0 * np.sin(0.5 * theta) ** 2) / n**2, wxv)
        + np.outer((theta - np.sin(theta)) / n**3, np.cross(w, wxv))
    )
    return rotation_path(rot_a, w / n, theta), pos_a + local_p @ rot_a.T


class SE3ToppPlanner(Planner):
    """Constant-screw segments with bang-bang timing; see the module doc. Limits in SI units."""

    def __init__(
        self,
        waypoints: Waypoints,
        standoff: float = 0.10,
        v_max_approach: float = 0.10,
        a_max_approach: float = 0.20,
        omega_max_approach: float = 0.20,
        alpha_max_approach: float = 0.20,
        v_max_docking: float = 0.02,
        a_max_docking: float = 0.05,
        omega_max_docking: float = 0.05,
        alpha_max_docking: float = 0.05,
        name: str = "se3topp",
    ):
        self.limits = {
            "approach": Limits(
                float(v_max_approach),
                float(a_max_approach),
                float(omega_max_approach),
                float(alpha_max_approach),
            ),
            "docking": Limits(
                float(v_max_docking), float(a_max_docking), float(omega_max_docking), float(alpha_max_docking)
            ),
        }
        for seg, lim in self.limits.items():
            lim.check(seg)
        pieces, self.notes = docking_waypoints(waypoints, float(standoff), "se3topp")
        for note in self.notes:
            log.info(note)
        self._screws: list[_Screw] = []
        t0 = 0.0
        for seg, a, b in pieces:
            xi = pin.log6(a.actInv(b)).vector  # the screw from a to b, in a's frame
            if np.linalg.norm(xi) < MIN_LENGTH:
                continue
            if np.linalg.norm(xi[3:]) >= math.pi - 1e-6:
                raise ValueError(
                    f"se3topp: the {seg} segment rotates by ~180°; the geodesic is not unique there"
                )
            v_p, a_s = screw_profile(xi, self.limits[seg])
            T = bang_bang_time(v_p, a_s)
            self._screws.append(
                _Screw(seg, t0, T, a.rotation.copy(), a.translation.copy(), np.asarray(xi, float), v_p, a_s)
            )
            t0 += T
        if not self._screws:  # start == goal: hold
            self._screws.append(
                _Screw(
                    "hold",
                    0.0,
                    1.0,
                    waypoints.start.rotation.copy(),
                    waypoints.start.translation.copy(),
                    np.zeros(6),
                    1.0,
                    1.0,
                )
            )
            self._segments = []
        else:
            self._segments = [(sc.name, sc.t0, sc.t0 + sc.T) for sc in self._screws]
        self._starts = np.array([sc.t0 for sc in self._screws])
        self.duration = t0

    @property
    def segments(self) -> list[tuple[str, float, float]]:
        """``(name, t_start, t_end)`` of "approach" (if any) and "docking" [s]."""
        return list(self._segments)

    def profiles(self) -> list[dict]:
        """Per segment: name, duration T [s], screw ξ, peak ṡ v_p [1/s], |s̈| a_s [1/s²],
        shape ("triangle" or "trapezoid")."""
        return [
            dict(
                name=sc.name,
                T=sc.T,
                xi=sc.xi.copy(),
                v_p=sc.v_p,
                a_s=sc.a_s,
                shape="triangle" if sc.v_p * sc.v_p >= sc.a_s * (1 - 1e-12) else "trapezoid",
            )
            for sc in self._screws
            if sc.name != "hold"
        ]

    def table(self, t: np.ndarray) -> ReferenceTable:
        out = ReferenceTable.zeros(t)
        t, pos, rot, twist, accel = out.t, out.pos, out.rot, out.twist, out.accel
        which = segment_index(t, self._starts)
        for i, sc in enumerate(self._screws):
            k = which == i
            if not k.any():
                continue
            s, ds, dds = bang_bang(t[k] - sc.t0, sc.v_p, sc.a_s, sc.T)
            rot[k], pos[k] = screw_pose(sc.rot_a, sc.pos_a, sc.xi, s)
            xi_v, xi_w = sc.xi[:3], sc.xi[3:]
            # ẋ = R ξ_v ṡ; ẍ = R (ξ_v s̈ + (ξ_ω × ξ_v) ṡ²); ω = R_a ξ_ω ṡ; ω̇ = R_a ξ_ω s̈
            local_v = np.outer(ds, xi_v)
            local_a = np.outer(dds, xi_v) + np.outer(ds * ds, np.cross(xi_w, xi_v))
            twist[k, :3] = np.einsum("nij,nj->ni", rot[k], local_v)
            accel[k, :3] = np.einsum("nij,nj->ni", rot[k], local_a)
            w_world = sc.rot_a @ xi_w
            twist[k, 3:] = np.outer(ds, w_world)
            accel[k, 3:] = np.outer(dds, w_world)
        return out
