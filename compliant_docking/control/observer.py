"""Generalised-momentum observer: the external wrench on the tool without a force sensor.

docs/control_laws.md §2, last bullet. The arm's dynamics with an external torque τ_ext and
the joint friction τ_f that Pinocchio does not model are

    M(q) q̈ + h(q, v) = τ_applied + τ_f + τ_ext,   h = C(q, v) v + g(q).

With the generalised momentum p = M v and Ṁ = C + Cᵀ this reads
ṗ = τ_applied − β + τ_f + τ_ext with β = g − Cᵀv = h − Ṁ v. The observer integrates a
model of p driven by the known torques plus a PI correction r:

    p̂ ← p̂ + dt (τ_applied − h + r) + ΔM v,        (ΔM v ≈ Ṁ v dt: no Coriolis matrix needed)
    e = p − p̂,   r = K_p e + K_i ∫e dt              (the integral clamped, see below),

so that the observer error obeys ë + K_p ė + K_i e = d/dt(τ_f + τ_ext): for a constant
disturbance r → τ_f + τ_ext with the poles of s² + K_p s + K_i (defaults 20 and 40 [1/s, 1/s²]:
−2.25 and −17.75 s⁻¹; settled to 1 % in about 2 s). The friction estimate is a model of
the friction acting on the joints (MuJoCo's frictionloss f and damping b),

    τ̂_f = −(f·tanh(v/v_s) + b·v),   v_s = 0.01 rad/s,

exact while a joint slides and at rest once MuJoCo's soft frictionloss constraint has
crept to zero force; while a joint sticks it holds an unknown torque within ±f, which no
momentum signal reveals (the observer's blind spot). Then

    τ̂_ext = r − τ̂_f,    ŵ = (J Jᵀ)⁻¹ J τ̂_ext   [f; m] at the TCP, world axes [N, N·m].

The friction model is deliberately not the controller's feed-forward: the torque-mode
feed-forward follows the command, not the motion, and at rest it would be counted as
friction that is not there.

Timing: :meth:`update` at step k uses the state of step k and the torque applied during
step k−1, so ŵ_k estimates the wrench of step k−1 — the same one-step delay as the
force/torque sensor reading the simulation hands the controller.

Usage from any controller (the torque it returns is clipped by the motors; the observer
applies the same clip, ``context.torque_limits``, to know what was actually applied)::

    w_hat = observer.update(state, sensor_wrench)   # first thing in compute()
    ...
    observer.command(tau)                     # last thing, with the returned torque
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from compliant_docking.config import FrictionComp
from compliant_docking.control.base import FrictionFeedForward
from compliant_docking.sim.context import ControlContext
from compliant_docking.sim.models import ArmModel

_dposv = lapack.dposv

#: default clamp of the integral term K_i ∫e per joint, as a multiple of the torque clip
INTEGRAL_LIMIT_FACTOR = 10.0
#: default window at the end of the run for the steady-state error (the metrics' default) [s]
STEADY_WINDOW = 2.0
#: column names of the estimate in the run's time series
WRENCH_COLUMNS = ("obs_fx", "obs_fy", "obs_fz", "obs_mx", "obs_my", "obs_mz")


class MomentumObserver:
    """PI momentum observer with a per-step record of its estimate (see the module doc).

    Args:
        context: the controller's context (arm, dt, n_steps, torque_limits).
        kp: proportional gain K_p > 0 [1/s].
        ki: integral gain K_i ≥ 0 [1/s²] (both: the ranges of ``controller.observer_kp``
            and ``controller.observer_ki``, which the controller checks).
        integral_limit: clamp of |K_i ∫e| per joint [N·m]; None: INTEGRAL_LIMIT_FACTOR ×
            the torque clip (the integral carries the whole steady estimate, so the clamp
            bounds the external torque it can report; it only acts against wind-up).
    """

    def __init__(
        self,
        context: ControlContext,
        kp: float,
        ki: float,
        *,
        integral_limit: float | np.ndarray | None = None,
    ):
        self.arm = context.arm
        self.dt = float(context.dt)
        self.kp, self.ki = float(kp), float(ki)
        n = self.arm.nv
        self.torque_limits = np.asarray(context.torque_limits, dtype=float).copy()
        limit = (
            INTEGRAL_LIMIT_FACTOR * self.torque_limits
            if integral_limit is None
            else np.broadcast_to(np.asarray(integral_limit, dtype=float), (n,))
        )
        if np.any(limit <= 0.0):
            raise ValueError(f"observer integral_limit must be > 0, got {integral_limit}")
        # clamp on ∫e such that |K_i ∫e| ≤ limit (no clamp when K_i = 0)
        self._int_max = limit / self.ki if self.ki > 0.0 else np.full(n, np.inf)
        self._int_min = -self._int_max
        self.p_hat = np.zeros(n)
        self.integral = np.zeros(n)
        self.r = np.zeros(n)  # momentum residual: estimate of τ_f + τ_ext [N·m]
        self.tau_ext = np.zeros(n)  # estimate of τ_ext [N·m]
        self.wrench = np.zeros(6)  # the estimate ŵ [f; m] [N, N·m]
        self._p = np.zeros(n)
        self._e = np.zeros(n)
        self._M_prev = np.zeros((n, n))
        self._h_prev = np.zeros(n)
        self._tau_applied = np.zeros(n)  # clipped command of the previous step
        # the friction acting on the joints, f·tanh(v/0.01) + b·v: the shared model in
        # velocity mode (whatever mode the host controller's feed-forward uses)
        self._joint_friction = FrictionFeedForward(
            context.joint_friction, context.joint_damping, FrictionComp.velocity
        )
        self._started = False
        n_steps = int(context.n_steps)
        self.estimates = np.zeros((n_steps, 6))
        self.measured = np.full((n_steps, 6), np.nan)  # the sensor wrench given to update()
        self.count = 0

    # ------------------------------------------------------------------ per step
    def update(self, state: ArmModel, measured: np.ndarray | None = None) -> np.ndarray:
        """Advance one step with the arm's state of this step (``arm.update`` already done).

        ``measured``: the sensor wrench of this step, recorded only for comparison.
        Returns ŵ (a buffer refreshed in place by every call).
        """
        arm = state
        M, v = arm.M, arm.v
        M.dot(v, out=self._p)
        if self._started:
            p_hat = self.p_hat
            # p̂ += dt (τ_applied − h_prev + r) + (M − M_prev) v
            drive = self._tau_applied - self._h_prev
            drive += self.r
            drive *= self.dt
            p_hat += drive
            p_hat += (M - self._M_prev).dot(v)
            np.subtract(self._p, p_hat, out=self._e)
            self.integral += self.dt * self._e
            np.clip(self.integral, self._int_min, self._int_max, out=self.integral)
            np.multiply(self.kp, self._e, out=self.r)
            self.r += self.ki * self.integral
        else:  # start from the measured momentum: no initial transient
            self.p_hat[:] = self._p
            self._started = True
        self._M_prev[:] = M
        self._h_prev[:] = arm.h
        if self._joint_friction.active:  # τ̂_ext = r − τ̂_f = r + f·tanh(v/v_s) + b·v
            np.add(self.r, self._joint_friction(v, v), out=self.tau_ext)
        else:
            self.tau_ext[:] = self.r
        self._joint_to_wrench(arm.J)
        k = self.count
        if k < len(self.estimates):
            self.estimates[k] = self.wrench
            if measured is not None:
                self.measured[k] = measured
            self.count = k + 1
        return self.wrench

    def command(self, tau: np.ndarray) -> None:
        """Record the torque command just returned (clipped here as the motors clip it)."""
        np.clip(tau, -self.torque_limits, self.torque_limits, out=self._tau_applied)

    def _joint_to_wrench(self, J: np.ndarray) -> None:
        """ŵ = (J Jᵀ)⁻¹ J τ̂_ext, the least-squares wrench with Jᵀŵ ≈ τ̂_ext."""
        _, x, info = _dposv(J.dot(J.T).T, J.dot(self.tau_ext), 0, 1, 1)  # lower=0, overwrite a, b
        if info == 0:
            self.wrench[:] = x
        else:  # singular J Jᵀ: the minimum-norm least-squares wrench
            self.wrench[:] = np.linalg.lstsq(J.T, self.tau_ext, rcond=None)[0]

    # ------------------------------------------------------------------ after the run
    def timeseries(self) -> dict[str, np.ndarray]:
        """The estimate per step, columns ``obs_fx … obs_mz``."""
        n = self.count
        return {name: self.estimates[:n, i] for i, name in enumerate(WRENCH_COLUMNS)}

    def errors(self, steady_window: float = STEADY_WINDOW) -> dict:
        """Estimate against the sensor: RMS over the run and mean over the last
        ``steady_window`` seconds of ‖f̂ − f‖ [N] and ‖m̂ − m‖ [N·m]; None without data."""
        n = self.count
        valid = np.isfinite(self.measured[:n]).all(axis=1)
        out: dict[str, float | None] = {
            "observer_force_err_rms_N": None,
            "observer_force_err_steady_N": None,
            "observer_moment_err_rms_Nm": None,
            "observer_moment_err_steady_Nm": None,
        }
        if not valid.any():
            return out
        diff = self.estimates[:n] - self.measured[:n]
        force_err = np.linalg.norm(diff[:, :3], axis=1)
        moment_err = np.linalg.norm(diff[:, 3:], axis=1)
        steady = np.zeros(n, dtype=bool)
        steady[max(n - int(round(steady_window / self.dt)), 0) :] = True
        steady &= valid
        out["observer_force_err_rms_N"] = float(np.sqrt(np.mean(force_err[valid] ** 2)))
        out["observer_moment_err_rms_Nm"] = float(np.sqrt(np.mean(moment_err[valid] ** 2)))
        if steady.any():
            out["observer_force_err_steady_N"] = float(force_err[steady].mean())
            out["observer_moment_err_steady_Nm"] = float(moment_err[steady].mean())
        return out
