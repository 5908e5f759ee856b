"""Integral action on the TCP pose error, an option of every controller (``integral_*``;
docs/controllers/integral.md, docs/control_laws.md "Integral action"): a force from the
position error and a moment from the orientation error, frozen by one latch."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import ControllerConfig


class PoseIntegral:
    """Integral action on the TCP pose error: a force and a moment the law adds to K e.

    Each step, while the measured contact force ‖f‖ is at most ``freeze_force`` (with
    ``latch``: until the first step it exceeds it; frozen from then on):
    I ← I + dt·P(x_d − x), P = I − u uᵀ (``lateral_only``: perpendicular to the docking
    axis u) or the identity; the force is F_i = gain·I, its norm clamped at ``limit``
    (the state is scaled back, so it never winds up past the clamp). In contact the
    integral is frozen: it keeps the joint-friction offset it learned in free space, and
    a socket that is not where the planner believed cannot wind it up against the bore.
    Latched, a contact lost again (the plug released from a stuck chamfer, falling onto
    the seat below the freeze force) cannot wind it up either.

    The orientation part (``rot_gain`` > 0) does the same on the orientation error
    e_R = log3(R_d Rᵀ) (world axes, every axis) under the same freeze and latch:
    I_R ← I_R + dt·e_R, M_i = rot_gain·I_R, its norm clamped at ``rot_limit``.

    Why: joint friction the model lacks (the FR3's 1.14 N·m) holds the arm wherever the
    stiffness force at the TCP is below the friction's reflection there, so a compliant
    arm arrives off the axis (HQP on the FR3: 1.3 mm, three times the clearance). The
    research code's FR3 impedance used a position integral (ki = 150) for that reason.
    Every axis by default: the axial lag friction causes makes the plug reach the seat
    late and fast (docs/controllers/integral.md); the integral frozen at contact adds its
    axial part (≈1 N on the FR3) to the press force k × overshoot. Likewise the wrist's
    friction (0.25-0.76 N·m) against k_rot = 25 N·m/rad tilts the FR3's plug by ~1° at
    arrival; the orientation part takes it out in free space and keeps it frozen in contact.
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
        rot_gain: float = 0.0,
        rot_limit: float = 1.0,
    ):
        require(ControllerConfig, "controller", integral_gain=gain, integral_rot_gain=rot_gain,
                integral_limit=limit, integral_rot_limit=rot_limit, integral_freeze_force=freeze_force)  # fmt: skip
        if not gain + rot_gain > 0.0:
            raise ValueError(
                "controller.integral_gain and controller.integral_rot_gain are both 0: the integral "
                "action is off, so there is no integral to build (the controller builds none)"
            )
        self.gain, self.limit, self.dt = float(gain), float(limit), float(dt)
        self.rot_gain, self.rot_limit = float(rot_gain), float(rot_limit)
        u = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        self.axis = tuple(u.tolist()) if lateral_only else None  # error component removed
        self.freeze_sq = float(freeze_force) ** 2
        self.latch = bool(latch)  # frozen for good from the first step over freeze_force
        self.latched = False
        # 3-vectors as Python floats: a few float operations cost less than numpy calls
        self.state = (0.0, 0.0, 0.0)  # ∫P e dt [m·s]
        self.force = (0.0, 0.0, 0.0)  # F_i [N]
        self.rot_state = (0.0, 0.0, 0.0)  # ∫e_R dt [rad·s]
        self.torque = (0.0, 0.0, 0.0)  # M_i [N·m]
        self.frozen_steps = 0
        self.max_force = 0.0
        self.max_torque = 0.0

    def update(self, error: np.ndarray, wrench: np.ndarray, rot_error=None) -> tuple[float, float, float]:
        """F_i [N, world] after this step's error x_d − x [m], measured wrench [f; m] and,
        with the orientation part, orientation error e_R [rad, world]; M_i is ``torque``."""
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
        self.state, self.force, size = _clamped_step(self.state, e0, e1, e2, self.dt, self.gain, self.limit)
        if size > self.max_force:
            self.max_force = size
        if self.rot_gain != 0.0:
            r0, r1, r2 = rot_error.tolist()
            self.rot_state, self.torque, size = _clamped_step(
                self.rot_state, r0, r1, r2, self.dt, self.rot_gain, self.rot_limit
            )
            if size > self.max_torque:
                self.max_torque = size
        return self.force

    def update_pose(
        self, error: np.ndarray, wrench: np.ndarray, rot_d: np.ndarray, rot_T: np.ndarray
    ) -> tuple:
        """[F_i; M_i] (6 floats, world) after this step, for the laws that do not form e_R
        themselves: e_R = log3(R_d Rᵀ) from R_d and Rᵀ, only while the orientation part
        still integrates (then ``update``)."""
        rot_error = pin.log3(rot_d.dot(rot_T)) if self.rot_gain != 0.0 and not self.latched else None
        return self.update(error, wrench, rot_error) + self.torque

    def diagnostics(self) -> dict:
        out = {
            "integral_frozen_steps": self.frozen_steps,
            "integral_max_force_N": self.max_force,
            "integral_final_force_N": math.sqrt(sum(f * f for f in self.force)),
        }
        if self.rot_gain != 0.0:
            out["integral_max_torque_Nm"] = self.max_torque
            out["integral_final_torque_Nm"] = math.sqrt(sum(m * m for m in self.torque))
        return out


def _clamped_step(state, e0, e1, e2, dt, gain, limit):
    """(state + dt·e, gain·state, its norm), the state scaled back so the norm is at most
    ``limit`` (no wind-up past the clamp). The compiled twin is hqp.kernel.clamped_step."""
    s0, s1, s2 = state
    s0, s1, s2 = s0 + dt * e0, s1 + dt * e1, s2 + dt * e2
    size = gain * math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    if size > limit:  # clamp the state with the output
        shrink = limit / size
        s0, s1, s2 = s0 * shrink, s1 * shrink, s2 * shrink
        size = limit
    return (s0, s1, s2), (gain * s0, gain * s1, gain * s2), size
