"""Integral action on the TCP position error, an option of every controller
(``integral_*``; docs/controllers/integral.md). Not in docs/control_laws.md."""

from __future__ import annotations

import math

import numpy as np


class PositionIntegral:
    """Integral action on the TCP position error, as a force the law adds to K e.

    Each step, while the measured contact force ‖f‖ is at most ``freeze_force`` (with
    ``latch``: until the first step it exceeds it; frozen from then on):
    I ← I + dt·P(x_d − x), P = I − u uᵀ (``lateral_only``: perpendicular to the docking
    axis u) or the identity; the force is F_i = gain·I, its norm clamped at ``limit``
    (the state is scaled back, so it never winds up past the clamp). In contact the
    integral is frozen: it keeps the joint-friction offset it learned in free space, and
    a socket that is not where the planner believed cannot wind it up against the bore.
    Latched, a contact lost again (the plug released from a stuck chamfer, falling onto
    the seat below the freeze force) cannot wind it up either.

    Why: joint friction the model lacks (the FR3's 1.14 N·m) holds the arm wherever the
    stiffness force at the TCP is below the friction's reflection there, so a compliant
    arm arrives off the axis (HQP on the FR3: 1.3 mm, three times the clearance). The
    research code's FR3 impedance used a position integral (ki = 150) for that reason.
    Every axis by default: the axial lag friction causes makes the plug reach the seat
    late and fast (docs/controllers/integral.md); the integral frozen at contact adds its
    axial part (≈1 N on the FR3) to the press force k × overshoot.
    """

    def __init__(
        self,
        gain: float,
        limit: float,
        axis: np.ndarray,
        dt: float,
        *,
        lateral_only: bool,
        freeze_force: float,
        latch: bool,
    ):
        if not gain > 0.0 or not limit > 0.0 or not freeze_force >= 0.0:
            raise ValueError(
                f"controller.integral_gain and controller.integral_limit must be > 0 and "
                f"controller.integral_freeze_force ≥ 0 (integral_gain 0 turns the integral "
                f"action off); got {gain}, {limit}, {freeze_force}"
            )
        self.gain, self.limit, self.dt = float(gain), float(limit), float(dt)
        u = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        self.axis = tuple(u.tolist()) if lateral_only else None  # error component removed
        self.freeze_sq = float(freeze_force) ** 2
        self.latch = bool(latch)  # frozen for good from the first step over freeze_force
        self.latched = False
        # 3-vectors as Python floats: a few float operations cost less than numpy calls
        self.state = (0.0, 0.0, 0.0)  # ∫P e dt [m·s]
        self.force = (0.0, 0.0, 0.0)  # F_i [N]
        self.frozen_steps = 0
        self.max_force = 0.0

    def update(self, error: np.ndarray, wrench: np.ndarray) -> tuple[float, float, float]:
        """F_i [N, world] after this step's error x_d − x [m] and measured wrench [f; m]."""
        f0, f1, f2, _, _, _ = wrench.tolist()
        if self.latched or f0 * f0 + f1 * f1 + f2 * f2 > self.freeze_sq:
            self.frozen_steps += 1
            self.latched = self.latch
            return self.force
        e0, e1, e2 = error.tolist()
        if self.axis is not None:  # drop the component along the docking axis
            u0, u1, u2 = self.axis
            along = e0 * u0 + e1 * u1 + e2 * u2
            e0, e1, e2 = e0 - along * u0, e1 - along * u1, e2 - along * u2
        dt, gain = self.dt, self.gain
        s0, s1, s2 = self.state
        s0, s1, s2 = s0 + dt * e0, s1 + dt * e1, s2 + dt * e2
        size = gain * math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        if size > self.limit:  # clamp the state with the force: no wind-up past the clamp
            shrink = self.limit / size
            s0, s1, s2 = s0 * shrink, s1 * shrink, s2 * shrink
            size = self.limit
        if size > self.max_force:
            self.max_force = size
        self.state = (s0, s1, s2)
        self.force = (gain * s0, gain * s1, gain * s2)
        return self.force

    def diagnostics(self) -> dict:
        return {
            "integral_frozen_steps": self.frozen_steps,
            "integral_max_force_N": self.max_force,
            "integral_final_force_N": math.sqrt(sum(f * f for f in self.force)),
        }
