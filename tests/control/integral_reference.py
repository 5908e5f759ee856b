"""The integral action in plain Python floats: the reference the one compiled step
(control/integral.py, ``integral_step``) is tested against, bit for bit (the same float
operations in the same order; numba compiles without fastmath, so LLVM neither contracts
a·b + c into an FMA nor reorders a sum)."""

from __future__ import annotations

import math


class ReferenceIntegral:
    """PoseIntegral's law (its docstring) on Python floats."""

    def __init__(
        self, gain, limit, axis, dt, *, lateral_only, freeze_force, latch, rot_gain=0.0, rot_limit=1.0
    ):
        self.gain, self.limit, self.dt = float(gain), float(limit), float(dt)
        self.rot_gain, self.rot_limit = float(rot_gain), float(rot_limit)
        norm = math.sqrt(sum(float(a) * float(a) for a in axis))
        self.axis = tuple(float(a) / norm for a in axis) if lateral_only else None
        self.freeze_sq = float(freeze_force) ** 2
        self.latch = bool(latch)
        self.latched = False
        self.state = self.force = self.rot_state = self.torque = (0.0, 0.0, 0.0)
        self.frozen_steps = 0
        self.max_force = self.max_torque = 0.0

    def step(self, error, wrench, rot_error) -> tuple:
        """[F_i; M_i] after this step (PoseIntegral.step)."""
        f0, f1, f2 = (float(x) for x in wrench[:3])
        if self.latched or f0 * f0 + f1 * f1 + f2 * f2 > self.freeze_sq:
            self.frozen_steps += 1
            self.latched = self.latch
            return self.force + self.torque
        e0, e1, e2 = (float(x) for x in error)
        if self.axis is not None:  # drop the component along the docking axis
            u0, u1, u2 = self.axis
            along = e0 * u0 + e1 * u1 + e2 * u2
            e0, e1, e2 = e0 - along * u0, e1 - along * u1, e2 - along * u2
        self.state, self.force, size = clamped_step(self.state, e0, e1, e2, self.dt, self.gain, self.limit)
        self.max_force = max(self.max_force, size)
        if self.rot_gain != 0.0:
            r0, r1, r2 = (float(x) for x in rot_error)
            self.rot_state, self.torque, size = clamped_step(
                self.rot_state, r0, r1, r2, self.dt, self.rot_gain, self.rot_limit
            )
            self.max_torque = max(self.max_torque, size)
        return self.force + self.torque


def clamped_step(state, e0, e1, e2, dt, gain, limit):
    """(state + dt·e, gain·state, its norm), the state scaled back so the norm is at most
    ``limit``."""
    s0, s1, s2 = state
    s0, s1, s2 = s0 + dt * e0, s1 + dt * e1, s2 + dt * e2
    size = gain * math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    if size > limit:  # clamp the state with the output
        shrink = limit / size
        s0, s1, s2 = s0 * shrink, s1 * shrink, s2 * shrink
        size = limit
    return (s0, s1, s2), (gain * s0, gain * s1, gain * s2), size
