r"""``trajectory=se3topp``: constant-screw geodesics, timed optimally under speed/acceleration limits.

Same waypoints as ``twophase`` (start → pre-dock point ``standoff`` before the goal →
goal; see :func:`~compliant_docking.planning.twophase.docking_waypoints`). Segment
a → b is the SE(3) geodesic

    T(s) = T_a·Exp(ξ s),  ξ = log6(T_a⁻¹ T_b) = [ξ_v; ξ_ω] (body frame), s ∈ [0, 1],

run rest to rest in the shortest time the limits allow along that path.

Reference (world axes at the TCP, the project's convention; R = R(s), R_a = R(0)):

    ẋ = R ξ_v ṡ,                       ω = R_a ξ_ω ṡ,
    ẍ = R (ξ_v s̈ + (ξ_ω × ξ_v) ṡ²),    ω̇ = R_a ξ_ω s̈,

and the body twist is simply V_b = ξ ṡ, V̇_b = ξ s̈.

Limits. They bound the Euclidean norms of the TCP's linear velocity ẋ and acceleration
ẍ (the derivatives of its position) and of its angular velocity ω and acceleration ω̇:
‖ẋ‖ ≤ v, ‖ẍ‖ ≤ a, ‖ω‖ ≤ ω_max, ‖ω̇‖ ≤ α_max, hence every component in world (or any)
axes too; norms do not depend on the axes. With b = ‖ξ_v‖ [m], w = ‖ξ_ω‖ [rad] and
c = ‖ξ_ω × ξ_v‖ [m], and since ξ_v ⟂ ξ_ω × ξ_v,

    ‖ẋ‖ = b ṡ,  ‖ω‖ = w ṡ,  ‖ω̇‖ = w |s̈|,  ‖ẍ‖² = b² s̈² + c² ṡ⁴   (exactly).

So the admissible set of the phase plane (s, ṡ) is

    ṡ ≤ V = min(v/b, ω_max/w),   |s̈| ≤ A(ṡ) = min(α_max/w, √(a² − c² ṡ⁴)/b),

with ṡ ≤ u₀ = √(a/c) for A to exist: the linear-acceleration bound shrinks with speed
(the centripetal part c ṡ² of ẍ) but none of it depends on s.

Time-optimal parameterisation (TOPP in the phase plane, solved in closed form). The
maximal-acceleration curve from rest, d(ṡ²/2)/ds = A(ṡ), gives ṡ = F(s); by
comparison every admissible profile stays below F(s), below its mirror image F(1 − s)
(maximal deceleration into rest at s = 1: the bounds are symmetric in s̈), and below
the maximum-velocity curve ṡ = V* = min(V, u₀), which is flat. The profile
ṡ(s) = min(F(s), V*, F(1 − s)) is admissible (on the flat MVC s̈ = 0 is allowed, also
at u₀ where A = 0) and pointwise the largest, so it minimises T = ∫ ds/ṡ: accelerate
at the bound, cruise on the MVC if F reaches it before s = ½, decelerate at the bound.
The switching points are s = ½ or the ends of the cruise; a flat MVC has no other.
F has a closed form:

- while √(a² − c²ṡ⁴)/b ≥ α_max/w: s̈ = a₁ = min(α_max/w, a/b), the classic ramp, up to
  ṡ = u₁ at t₁, s₁;
- then the linear bound holds with equality. Writing c ṡ² = a sin θ, b s̈ = a cos θ
  (θ: the angle of ẍ from the path tangent, θ₁ at u₁), ds = ṡ dṡ/s̈ gives
  s = s₁ + b (θ − θ₁)/(2c), and dt = dṡ/s̈ a lemniscatic integral:
  t = t₁ + (G(θ) − G(θ₁))/κ with κ = √(ac)/b, G(θ) = F(φ | ½)/√2 (incomplete elliptic
  integral of the first kind, parameter m = ½), tan φ = √(sin θ)/sin(π/4 − θ/2).
  Sampling inverts it with Jacobi's functions of √2·(G(θ₁) + κ(t − t₁)) at m = ½:
  tan θ = sn²/(2 cn), ṡ = u₀ sn/(√2 dn).

Durations and samples are therefore exact up to rounding (no discretisation of the
path or of the phase plane). Without a centripetal term (c = 0: pure translation, pure
rotation, translation along the rotation axis) A is constant and this is the classic
bang-bang profile, v_s = V, a_s = min(a/b, α_max/w), lasting in s-units

    T = 2/√a_s         if √a_s ≤ v_s (triangle),
    T = 1/v_s + v_s/a_s otherwise (trapezoid).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.special import ellipj, ellipkinc

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import SE3ToppConfig
from compliant_docking.planning.base import Planner, ReferenceTable, Waypoints
from compliant_docking.planning.twophase import MIN_LENGTH, docking_waypoints, rotation_path, segment_index

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Limits:
    """Per-segment limits: linear speed [m/s] and acceleration [m/s²], angular speed [rad/s]
    and acceleration [rad/s²] (bounds on the Euclidean norms)."""

    v: float
    a: float
    omega: float
    alpha: float


def bang_bang_time(v_s: float, a_s: float) -> float:
    """Duration [s] of the bang-bang profile over s ∈ [0, 1] with peak ṡ ≤ v_s [1/s] and
    |s̈| = a_s [1/s²]: 2/√a_s if √a_s ≤ v_s (triangle), else 1/v_s + v_s/a_s (trapezoid)."""
    if not (v_s > 0.0 and a_s > 0.0):
        raise ValueError(f"bang-bang limits must be > 0, got v_s={v_s}, a_s={a_s}")
    root = math.sqrt(a_s)
    return 2.0 / root if root <= v_s else 1.0 / v_s + v_s / a_s


@dataclass(frozen=True)
class ScrewTiming:
    """Rest-to-rest time law s(u), u ∈ [0, T], of one screw segment (see the module doc).

    ``T`` duration [s]; ``v_p`` peak ṡ [1/s]; ``a_s`` s̈ from rest [1/s²] (constant on the
    first ramp); ``t_ramp`` end of the acceleration phase (start of the cruise, or the
    switching instant of a triangle) [s] and ``s_ramp`` the s reached then. The
    centripetal part of the ramp (the linear bound active, s̈ < a_s) starts at ``t_c``
    (∞ when it never binds), where s = ``s_c`` and θ = ``theta_c``; ``kappa`` = √(ac)/b
    [1/s], ``g_c`` = G(θ_c), ``u0`` = √(a/c) [1/s], ``half_b_c`` = b/(2c), ``a_b`` = a/b.
    """

    T: float
    v_p: float
    a_s: float
    t_ramp: float
    s_ramp: float
    t_c: float = math.inf
    s_c: float = 0.0
    theta_c: float = 0.0
    g_c: float = 0.0
    kappa: float = 0.0
    u0: float = 0.0
    half_b_c: float = 0.0
    a_b: float = 0.0

    @property
    def centripetal(self) -> bool:
        """Whether the speed-dependent linear-acceleration bound shapes the ramps."""
        return self.t_c < self.t_ramp

    @property
    def shape(self) -> str:
        """ "triangle" (no cruise) or "trapezoid"."""
        return "triangle" if self.T - 2.0 * self.t_ramp <= 1e-12 * self.T else "trapezoid"

    def switch_times(self) -> list[float]:
        """Local instants [s] where s̈ or its derivative jumps: 0, t_c, t_ramp, T − t_ramp,
        T − t_c, T (t_c only when the centripetal bound binds)."""
        inner = [self.t_c, self.T - self.t_c] if self.centripetal else []
        return sorted([0.0, self.t_ramp, self.T - self.t_ramp, self.T, *inner])

    def _ramp(self, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """s, ṡ, s̈ at times r ∈ [0, t_ramp] of the maximal-acceleration curve from rest."""
        s, ds, dds = 0.5 * self.a_s * r**2, self.a_s * r, np.full_like(r, self.a_s)
        late = r >= self.t_c
        if late.any():
            x = self.g_c + self.kappa * (r[late] - self.t_c)  # G(θ) at these times
            sn, cn, dn, _ = ellipj(math.sqrt(2.0) * x, 0.5)
            cn = np.maximum(cn, 0.0)  # ≤ K by construction; rounding may cross it
            sn2 = sn * sn
            theta = np.arctan2(sn2, 2.0 * cn)
            s[late] = self.s_c + self.half_b_c * (theta - self.theta_c)
            ds[late] = self.u0 * sn / (math.sqrt(2.0) * dn)
            dds[late] = self.a_b * 2.0 * cn / (2.0 - sn2)
        return s, ds, dds

    def __call__(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """s, ṡ [1/s], s̈ [1/s²] at local times u [s] (clamped to [0, T]). Ramp boundaries
        belong to the cruise (or, for a triangle, the switching instant to the
        deceleration); exactly at rest at u ≥ T."""
        if math.isinf(self.t_c):  # the classic profile, as before
            return bang_bang(u, self.v_p, self.a_s, self.T)
        u = np.clip(np.asarray(u, dtype=float), 0.0, self.T)
        s, ds, dds = np.empty_like(u), np.empty_like(u), np.empty_like(u)
        up = u < self.t_ramp
        down = u >= self.T - self.t_ramp if self.shape == "triangle" else u > self.T - self.t_ramp
        cruise = ~(up | down)
        s[up], ds[up], dds[up] = self._ramp(u[up])
        s_d, ds[down], dds_d = self._ramp(self.T - u[down])
        s[down], dds[down] = 1.0 - s_d, -dds_d
        s[cruise] = self.s_ramp + self.v_p * (u[cruise] - self.t_ramp)
        ds[cruise], dds[cruise] = self.v_p, 0.0
        end = u >= self.T
        s[end], ds[end], dds[end] = 1.0, 0.0, 0.0
        return s, ds, dds


def _lemniscate_g(theta: float) -> float:
    """G(θ) = ∫₀^y dy'/√(1 − y'⁴) with y² = sin θ (θ ∈ [0, π/2]), as F(φ | ½)/√2 with
    tan φ = √(sin θ)/sin(π/4 − θ/2) (well conditioned up to θ = π/2)."""
    phi = math.atan2(math.sqrt(math.sin(theta)), math.sin(0.25 * math.pi - 0.5 * theta))
    return float(ellipkinc(phi, 0.5)) / math.sqrt(2.0)


def screw_timing(xi: np.ndarray, limits: Limits) -> ScrewTiming:
    """The time-optimal rest-to-rest timing of s ∈ [0, 1] along the screw ``xi`` under
    ‖ẋ‖ ≤ v, ‖ẍ‖ ≤ a, ‖ω‖ ≤ ω_max, ‖ω̇‖ ≤ α_max (see the module doc)."""
    xi_v, xi_w = np.asarray(xi[:3], float), np.asarray(xi[3:], float)
    b, w = float(np.linalg.norm(xi_v)), float(np.linalg.norm(xi_w))
    c = float(np.linalg.norm(np.cross(xi_w, xi_v)))
    inf = math.inf
    v_cap = min(limits.v / b if b > 0 else inf, limits.omega / w if w > 0 else inf)
    a_rot = limits.alpha / w if w > 0 else inf
    a_s = min(limits.a / b if b > 0 else inf, a_rot)
    if c <= 1e-12 * b:  # no centripetal term (b = 0 gives c = 0): the classic profile
        v_p = min(v_cap, math.sqrt(a_s))
        T = bang_bang_time(v_p, a_s)
        return ScrewTiming(T=T, v_p=v_p, a_s=a_s, t_ramp=v_p / a_s, s_ramp=0.5 * v_p * v_p / a_s)
    # first ramp at a_s until the linear bound binds: b a_s = a cos θ_c, c u_c² = a sin θ_c
    r = b * a_s / limits.a  # ≤ 1
    theta_c = math.atan2(math.sqrt(max((1.0 - r) * (1.0 + r), 0.0)), r)
    u_c = math.sqrt(limits.a * math.sin(theta_c) / c)
    peak = min(v_cap, math.sqrt(a_s))  # the classic profile's peak
    if peak <= u_c:  # the classic profile never reaches the centripetal bound
        T = bang_bang_time(peak, a_s)
        return ScrewTiming(T=T, v_p=peak, a_s=a_s, t_ramp=peak / a_s, s_ramp=0.5 * peak * peak / a_s)
    t_c, s_c = u_c / a_s, 0.5 * u_c * u_c / a_s
    u0, half_b_c, kappa = math.sqrt(limits.a / c), 0.5 * b / c, math.sqrt(limits.a * c) / b
    g_c = _lemniscate_g(theta_c)
    theta_half = theta_c + (0.5 - s_c) / half_b_c  # where the ramp reaches s = ½
    theta_v = 0.5 * math.pi if v_cap >= u0 else math.asin(c * v_cap * v_cap / limits.a)
    if theta_v < theta_half:  # trapezoid: cruise on the flat MVC ṡ = min(V, u₀)
        theta_p, v_p = theta_v, min(v_cap, u0)
        s_ramp = s_c + half_b_c * (theta_v - theta_c)
    else:  # triangle: switch at s = ½
        theta_p, s_ramp = theta_half, 0.5
        v_p = math.sqrt(limits.a * math.sin(theta_half) / c)
    t_ramp = t_c + (_lemniscate_g(theta_p) - g_c) / kappa
    T = 2.0 * t_ramp + (1.0 - 2.0 * s_ramp) / v_p
    return ScrewTiming(
        T=T,
        v_p=v_p,
        a_s=a_s,
        t_ramp=t_ramp,
        s_ramp=s_ramp,
        t_c=t_c,
        s_c=s_c,
        theta_c=theta_c,
        g_c=g_c,
        kappa=kappa,
        u0=u0,
        half_b_c=half_b_c,
        a_b=limits.a / b,
    )


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
    timing: ScrewTiming  # s(t − t0)


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
    """Constant-screw segments, each timed optimally under its limits; see the module doc.
    Limits in SI units."""

    def __init__(
        self,
        waypoints: Waypoints,
        *,
        standoff: float,
        v_max_approach: float,
        a_max_approach: float,
        omega_max_approach: float,
        alpha_max_approach: float,
        v_max_docking: float,
        a_max_docking: float,
        omega_max_docking: float,
        alpha_max_docking: float,
        name: str,
        lead_limit: float | None,
    ):
        require(  # the schema's ranges
            SE3ToppConfig, "trajectory", standoff=standoff, v_max_approach=v_max_approach,
            a_max_approach=a_max_approach, omega_max_approach=omega_max_approach,
            alpha_max_approach=alpha_max_approach, v_max_docking=v_max_docking, a_max_docking=a_max_docking,
            omega_max_docking=omega_max_docking, alpha_max_docking=alpha_max_docking, lead_limit=lead_limit,
        )  # fmt: skip
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
        pieces, self.notes = docking_waypoints(waypoints, float(standoff), "se3topp")
        self.lead_limit = None if lead_limit is None else float(lead_limit)
        for note in self.notes:
            log.info(note)
        self._screws: list[_Screw] = []
        t0 = 0.0
        for seg, a, b in pieces:
            xi = pin.log6(a.actInv(b)).vector  # T_a⁻¹ T_b
            if np.linalg.norm(xi) < MIN_LENGTH:
                continue
            if np.linalg.norm(xi[3:]) >= math.pi - 1e-6:
                raise ValueError(
                    f"se3topp: the {seg} segment rotates by ~180°; the geodesic is not unique there"
                )
            timing = screw_timing(xi, self.limits[seg])
            T = timing.T
            self._screws.append(
                _Screw(seg, t0, T, a.rotation.copy(), a.translation.copy(), np.asarray(xi, float), timing)
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
                    ScrewTiming(T=1.0, v_p=1.0, a_s=1.0, t_ramp=1.0, s_ramp=0.5),
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

    @property
    def screws(self) -> tuple:
        """The constant-screw segments (start time, duration, start pose, ξ, timing)."""
        return tuple(self._screws)

    def profiles(self) -> list[dict]:
        """Per segment: name, duration T [s], screw ξ, peak ṡ v_p [1/s], s̈ from rest a_s
        [1/s²], end of the acceleration t_ramp [s], shape ("triangle" or "trapezoid"),
        centripetal (whether the speed-dependent linear-acceleration bound shapes the
        ramps) and switch_times (segment-local instants where s̈ or its rate jumps) [s]."""
        return [
            dict(
                name=sc.name,
                T=sc.T,
                xi=sc.xi.copy(),
                v_p=sc.timing.v_p,
                a_s=sc.timing.a_s,
                t_ramp=sc.timing.t_ramp,
                shape=sc.timing.shape,
                centripetal=sc.timing.centripetal,
                switch_times=sc.timing.switch_times(),
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
            s, ds, dds = sc.timing(t[k] - sc.t0)
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
