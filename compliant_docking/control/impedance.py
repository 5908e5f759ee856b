"""``controller=impedance``: operational-space impedance with force feedback.

docs/control_laws.md §1. With e = [x_d − x; log3(R_d Rᵀ)] and ν the TCP twist (world axes),
the commanded task acceleration is

    a = ν̇_d + W⁻¹(w_ext + K e + D (ν_d − ν)),  W = diag(m,m,m,m_rot,m_rot,m_rot),

and τ = Jᵀ(Λ(a − J̇v) − w_ext) + h − Nᵀ(b·v) + friction feed-forward, with
Nᵀ(b v) = b v − JᵀΛJM⁻¹(b v). Exact force feedback cancels the contact wrench in the
arm's dynamics, so the closed loop is W ë + D ė + K e = w_ext: a constant push F
settles at a displacement F/k. Without force feedback the w_ext terms vanish.

Options (docs/controllers/impedance.md, integral.md): ``apparent_inertia_floor`` replaces
W by W_eff ⪰ ratio·Λ (a deviation from §1 that keeps the one-step-old force feedback
stable; null: the law of §1), and the integral action adds a wrench [F_i; M_i] to K e:
a = ν̇_d + W_eff⁻¹(w_ext + K e + [F_i; M_i] + D (ν_d − ν)).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import ImpedanceConfig
from compliant_docking.control.base import Controller, TaskInertia
from compliant_docking.control.shaping import inertia_floor
from compliant_docking.planning.base import Reference
from compliant_docking.sim.context import ControlContext
from compliant_docking.sim.models import ArmModel


class ImpedanceController(Controller):
    def __init__(
        self,
        context: ControlContext,
        *,
        m: float,
        d: float,
        k: float,
        m_rot: float,
        d_rot: float,
        k_rot: float,
        null_damping: float,
        condition_threshold: float,
        apparent_inertia_floor: float | None,
        **common,
    ):
        super().__init__(context, **common)
        require(  # the schema's ranges: the config check's refusals, word for word
            ImpedanceConfig, "controller", m=m, d=d, k=k, m_rot=m_rot, d_rot=d_rot, k_rot=k_rot,
            null_damping=null_damping, condition_threshold=condition_threshold,
            apparent_inertia_floor=apparent_inertia_floor,
        )  # fmt: skip
        W_inv = 1.0 / np.array([m] * 3 + [m_rot] * 3, dtype=float)
        K = np.array([k] * 3 + [k_rot] * 3, dtype=float)
        D = np.array([d] * 3 + [d_rot] * 3, dtype=float)
        # a = ν̇_d − J̇v + G z with z = [e; ν_d − ν; w] and G = W⁻¹[K, D, I] (one product)
        self.G = np.hstack(
            [
                np.diag(W_inv * K),
                np.diag(W_inv * D),
                np.diag(W_inv) if self.use_force_feedback else np.zeros((6, 6)),
            ]
        )
        self._G_config = self.G.copy()  # the config's gains (set_stiffness_scales(1, 1, 1))
        self._gains = (W_inv, K, D)
        self._w_inv_m, self._w_inv_rot = 1.0 / float(m), 1.0 / float(m_rot)
        self._z = np.zeros(18)
        self._z_pos, self._z_rot = self._z[0:3], self._z[3:6]
        self._z_twist, self._z_wrench = self._z[6:12], self._z[12:18]
        self.null_damping = float(null_damping)
        self.task_inertia = TaskInertia(condition_threshold)
        # the deviation from §1 that keeps the delayed force feedback stable (None: off, or
        # no force feedback: no such loop, the law stays §1's)
        self.inertia_floor = inertia_floor(1.0 / W_inv, apparent_inertia_floor, self.use_force_feedback)

    def set_stiffness_scales(self, lateral: float, axial: float, rotational: float) -> None:
        """Scale the config's stiffness across and along the docking axis and about every axis
        (the damping by the square roots: each direction keeps its damping ratio), from the
        next step on; (1, 1, 1) restores the config's gains bit for bit. The Gymnasium
        environment's gain action (docs/env.md).

        Translation: K = k·(s_lat (I − a aᵀ) + s_ax a aᵀ), D likewise with √s, a the docking
        axis; rotation: k_rot·s_rot, d_rot·√s_rot.
        """
        scales = (float(lateral), float(axial), float(rotational))
        if not all(np.isfinite(scales)) or min(scales) <= 0.0:
            raise ValueError(f"stiffness scales must be finite and > 0, got {scales}")
        if scales == (1.0, 1.0, 1.0):
            self.G[:] = self._G_config
            return
        W_inv, K, D = self._gains
        a = np.asarray(self.ctx.axis, dtype=float)
        along = np.outer(a, a)
        across = np.eye(3) - along
        lat, ax, rot = scales
        self.G[:3, :3] = W_inv[0] * K[0] * (lat * across + ax * along)
        self.G[:3, 6:9] = W_inv[0] * D[0] * (np.sqrt(lat) * across + np.sqrt(ax) * along)
        self.G[3:6, 3:6] = np.diag(W_inv[3:] * K[3:] * rot)
        self.G[3:6, 9:12] = np.diag(W_inv[3:] * D[3:] * np.sqrt(rot))

    def compute(self, t: float, state: ArmModel, ref: Reference, wrench: np.ndarray) -> np.ndarray:
        arm = state
        np.subtract(ref.pos, arm.pos, out=self._z_pos)
        # ndarray.dot rather than `@`: a third of the call overhead on arrays this small
        self._z_rot[:] = pin.log3(ref.rot.dot(arm.rot_T))
        np.subtract(ref.twist, arm.twist, out=self._z_twist)
        self._z_wrench[:] = wrench
        a = self.G.dot(self._z)  # W⁻¹(K e + D ė + w)
        integral = self.integral
        if integral is not None:  # + W⁻¹[F_i; M_i]
            i0, i1, i2, i3, i4, i5 = integral.step(self._z_pos, wrench, self._z_rot)
            w_inv = self._w_inv_m
            a[0] += w_inv * i0
            a[1] += w_inv * i1
            a[2] += w_inv * i2
            if integral.rot_gain != 0.0:
                w_inv = self._w_inv_rot
                a[3] += w_inv * i3
                a[4] += w_inv * i4
                a[5] += w_inv * i5
        J, v = arm.J, arm.v
        JMinv = J.dot(arm.Minv)
        if self.inertia_floor is not None:
            P = self.inertia_floor.current(J, JMinv)
            if P is not None:  # W⁻¹(…) → W_eff⁻¹(…); inactive: a untouched, bit for bit
                a = P.dot(a)
        a += ref.accel
        a -= arm.Jdot_v

        bv = self.null_damping * v
        a += JMinv.dot(bv)
        force = self.task_inertia.solve(J, JMinv, a)
        if self.use_force_feedback:
            force -= wrench
        tau = force.dot(J)  # Jᵀ force
        tau += arm.h
        tau -= bv
        if self.friction.active:
            tau += self.friction(tau, v, arm.h)
        return tau

    def diagnostics(self) -> dict:
        out = self.task_inertia.diagnostics()
        out.update(self.integral_diagnostics())
        if self.inertia_floor is not None:
            out.update(self.inertia_floor.diagnostics())
        return out
