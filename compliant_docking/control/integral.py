"""Integral action on the TCP pose error, an option of every controller (``integral_*``;
docs/controllers/integral.md, docs/control_laws.md "Integral action"): a force from the
position error and a moment from the orientation error, frozen by one latch.

One implementation: :func:`integral_step` (compiled) advances the state held in a numpy
record (:data:`RECORD`: the parameters, then the state) that :class:`PoseIntegral` owns.
The numpy laws call it through :meth:`PoseIntegral.update`; the HQP step kernel calls it
on the same record (``PoseIntegral.record``), so the controller reads its diagnostics from
the record whichever law advanced it. tests/control/integral_reference.py keeps the law in
plain Python floats as the reference the compiled step is tested against, bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import ControllerConfig
from compliant_docking.control.jit import kernel

#: the integral's record: its parameters (set once), then its state (advanced each step)
RECORD = np.dtype(
    [
        ("on", np.bool_),  # False: the record of a controller without the integral action
        ("gain", np.float64),  # [N/(m·s)] on the position error
        ("limit", np.float64),  # [N] clamp of ‖F_i‖
        ("rot_gain", np.float64),  # [N·m/(rad·s)] on the orientation error; 0: off
        ("rot_limit", np.float64),  # [N·m] clamp of ‖M_i‖
        ("dt", np.float64),  # [s] the control step
        ("freeze_sq", np.float64),  # [N²] freeze_force²
        ("lateral", np.bool_),  # drop the error's component along ``axis``
        ("latch", np.bool_),  # frozen for good from the first step over freeze_force
        ("axis", np.float64, (3,)),  # the docking axis (unit)
        ("state", np.float64, (3,)),  # ∫P e dt [m·s]
        ("force", np.float64, (3,)),  # F_i [N]
        ("rot_state", np.float64, (3,)),  # ∫e_R dt [rad·s]
        ("torque", np.float64, (3,)),  # M_i [N·m]
        ("latched", np.bool_),  # frozen for good
        ("frozen_steps", np.int64),
        ("max_force", np.float64),  # [N] the largest ‖F_i‖
        ("max_torque", np.float64),  # [N·m] the largest ‖M_i‖
    ]
)


def off_record() -> np.ndarray:
    """The record (one element) of a controller without the integral action: F_i = M_i = 0."""
    return np.zeros(1, dtype=RECORD)


@kernel
def clamped_step(state, out, e0, e1, e2, dt, gain, limit):
    """state ← state + dt·e, scaled back so that gain·‖state‖ ≤ limit (no wind-up past the
    clamp); out ← gain·state; returns gain·‖state‖."""
    s0, s1, s2 = state[0] + dt * e0, state[1] + dt * e1, state[2] + dt * e2
    size = gain * math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    if size > limit:  # clamp the state with the output
        shrink = limit / size
        s0, s1, s2 = s0 * shrink, s1 * shrink, s2 * shrink
        size = limit
    state[0], state[1], state[2] = s0, s1, s2
    out[0], out[1], out[2] = gain * s0, gain * s1, gain * s2
    return size


@kernel
def integral_step(it, e0, e1, e2, wrench, rot_err):
    """One step of the integral action on the record ``it`` (:data:`RECORD`; the law:
    :class:`PoseIntegral`): e = x_d − x, ``wrench`` the measured [f; m], ``rot_err`` the
    orientation error log3(R_d Rᵀ) (read only when ``rot_gain`` ≠ 0)."""
    f0, f1, f2 = wrench[0], wrench[1], wrench[2]
    if it.latched or f0 * f0 + f1 * f1 + f2 * f2 > it.freeze_sq:
        it.frozen_steps += 1
        it.latched = it.latch
        return
    if it.lateral:  # drop the component along the docking axis
        u = it.axis
        u0, u1, u2 = u[0], u[1], u[2]
        along = e0 * u0 + e1 * u1 + e2 * u2
        e0, e1, e2 = e0 - along * u0, e1 - along * u1, e2 - along * u2
    size = clamped_step(it.state, it.force, e0, e1, e2, it.dt, it.gain, it.limit)
    if size > it.max_force:
        it.max_force = size
    if it.rot_gain != 0.0:
        r0, r1, r2 = rot_err[0], rot_err[1], rot_err[2]
        size = clamped_step(it.rot_state, it.torque, r0, r1, r2, it.dt, it.rot_gain, it.rot_limit)
        if size > it.max_torque:
            it.max_torque = size


@kernel
def _update(record, error, wrench, rot_err):
    """:func:`integral_step` on ``record[0]``; returns (F_i, M_i) as 6 floats."""
    it = record[0]
    integral_step(it, error[0], error[1], error[2], wrench, rot_err)
    f, m = it.force, it.torque
    return f[0], f[1], f[2], m[0], m[1], m[2]


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

    The parameters and the state live in :attr:`record` (:data:`RECORD`), advanced by the
    compiled :func:`integral_step`; the attributes below read it.
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
        self.record = np.zeros(1, dtype=RECORD)
        it = self.record[0]
        it["on"], it["gain"], it["limit"], it["dt"] = True, gain, limit, dt
        it["rot_gain"], it["rot_limit"] = rot_gain, rot_limit
        it["freeze_sq"] = float(freeze_force) ** 2
        it["lateral"], it["latch"] = bool(lateral_only), bool(latch)
        it["axis"] = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        self.rot_gain = float(rot_gain)  # read every step by the laws
        self._no_rot_error = np.zeros(3)
        # load the compiled step now rather than in the loop's first step (a scratch record)
        _update(self.record.copy(), self._no_rot_error, np.zeros(6), self._no_rot_error)

    @classmethod
    def from_settings(cls, axis: np.ndarray, dt: float, **settings) -> PoseIntegral | None:
        """The integral of a controller's ``integral_*`` settings (``integral_gain`` →
        ``gain``, …), or None when both gains are 0 (the action is off)."""
        kwargs = {key.removeprefix("integral_"): value for key, value in settings.items()}
        if not (kwargs["gain"] or kwargs["rot_gain"]):
            return None
        return cls(kwargs.pop("gain"), kwargs.pop("limit"), axis, dt, **kwargs)

    def _vector(self, name: str) -> tuple[float, float, float]:
        return tuple(self.record[name][0].tolist())

    state = property(lambda self: self._vector("state"), doc="∫P e dt [m·s]")
    force = property(lambda self: self._vector("force"), doc="F_i [N, world]")
    rot_state = property(lambda self: self._vector("rot_state"), doc="∫e_R dt [rad·s]")
    torque = property(lambda self: self._vector("torque"), doc="M_i [N·m, world]")
    latched = property(lambda self: bool(self.record["latched"][0]), doc="frozen for good")
    frozen_steps = property(lambda self: int(self.record["frozen_steps"][0]), doc="steps frozen")

    def step(self, error: np.ndarray, wrench: np.ndarray, rot_error: np.ndarray | None = None) -> tuple:
        """[F_i; M_i] (6 floats, world) after this step's error x_d − x [m], measured wrench
        [f; m] and, with the orientation part, orientation error e_R [rad, world]."""
        return _update(self.record, error, wrench, self._no_rot_error if rot_error is None else rot_error)

    def update(self, error: np.ndarray, wrench: np.ndarray, rot_error=None) -> tuple[float, float, float]:
        """F_i [N, world] after this step (:meth:`step`); M_i is ``torque``."""
        return self.step(error, wrench, rot_error)[:3]

    def update_pose(
        self, error: np.ndarray, wrench: np.ndarray, rot_d: np.ndarray, rot_T: np.ndarray
    ) -> tuple:
        """[F_i; M_i] (6 floats, world) after this step, for the laws that do not form e_R
        themselves: e_R = log3(R_d Rᵀ) from R_d and Rᵀ, only while the orientation part
        still integrates."""
        integrates = self.rot_gain != 0.0 and not self.record["latched"][0]
        rot_error = pin.log3(rot_d.dot(rot_T)) if integrates else self._no_rot_error
        return _update(self.record, error, wrench, rot_error)

    def diagnostics(self) -> dict:
        it = self.record[0]
        out = {
            "integral_frozen_steps": int(it["frozen_steps"]),
            "integral_max_force_N": float(it["max_force"]),
            "integral_final_force_N": math.sqrt(sum(f * f for f in self.force)),
        }
        if self.rot_gain != 0.0:
            out["integral_max_torque_Nm"] = float(it["max_torque"])
            out["integral_final_torque_Nm"] = math.sqrt(sum(m * m for m in self.torque))
        return out
