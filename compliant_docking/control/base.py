"""Pieces every controller shares: the base class, the task-space inertia Λ with a
conditioning fallback, and joint friction feed-forward.

A controller maps (arm state, reference, measured wrench) to joint torques. It is built
once per run from its config's parameters and a :class:`~compliant_docking.sim.context.ControlContext`;
the simulation loop then calls, every step::

    arm.update(q, v); reference.row(k, ref)
    tau = controller.compute(t, arm, ref, wrench)   # the command; the motors clip it to
                                                    # ±context.torque_limits

``arm`` (the :class:`~compliant_docking.sim.models.ArmModel` just updated) is the state
the law reads: q, v, M, M⁻¹, h, J, J̇v and the TCP pose and twist of this step.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np
from scipy.linalg import lapack

from compliant_docking.config import FrictionComp
from compliant_docking.control.integral import PoseIntegral
from compliant_docking.control.kernel_blocks import YIELD_SPEED, friction_code, friction_feed_forward
from compliant_docking.planning.base import Reference
from compliant_docking.sim.context import ControlContext
from compliant_docking.sim.models import ArmModel

_dposv = lapack.dposv


class FrictionFeedForward:
    """Adds back MuJoCo's joint frictionloss f and damping b that Pinocchio does not model
    (docs/controllers/friction.md).

    ``torque`` mode: f·tanh(2·τ_pre/f) + b·v (follows the command, so there is no dead zone
    at zero speed); ``velocity`` mode: f·tanh(v/0.01) + b·v. Joints with f = b = 0 get 0.
    ``torque_unbiased`` mode: f·tanh(2·(τ_pre − h)/f) + b·v with h = C v + g the arm's bias
    torques of this step (the caller passes ``state.h``): the torque mode on the part of
    the command that is meant to move the arm. Under gravity the plain torque mode takes
    its sign from the gravity-holding torque, i.e. it pushes every loaded joint by ±f
    whatever the motion; in zero gravity the two differ only by C v.
    ``yielding`` mode: torque_unbiased, y = tanh(2(τ_pre − h)/f), scaled by
    1 − min(|v|/0.02 rad/s, 1) on a joint moving against it (v·y < 0): f·y' + b·v. A motion
    the contact drives against the command (the plug pushed sideways by the funnel) then
    meets the joint's own friction, not twice it; the feed-forward never opposes a motion.
    """

    VELOCITY_SCALE = 0.01  # [rad/s]
    YIELD_SPEED = YIELD_SPEED  # [rad/s]

    def __init__(self, friction: np.ndarray, damping: np.ndarray, mode: FrictionComp):
        self.mode = FrictionComp(mode)
        self.f = np.asarray(friction, dtype=float).copy()
        self.b = np.asarray(damping, dtype=float).copy()
        self.active = bool(np.any(self.f > 0.0) or np.any(self.b > 0.0))
        self._unbiased = self.mode in (FrictionComp.yielding, FrictionComp.torque_unbiased)
        # what the compiled block takes (the compiled laws copy them into their parameters):
        # the mode's code, and the argument of tanh per unit of its input, 2/f (torque modes)
        # or 1/0.01 (velocity)
        self.code = friction_code(self.mode)
        self.scale = (
            2.0 / np.where(self.f > 0.0, self.f, 1.0)
            if self.mode is not FrictionComp.velocity
            else np.full_like(self.f, 1.0 / self.VELOCITY_SCALE)
        )
        if self.active:  # load the compiled block now rather than in the loop's first step
            zero = np.zeros_like(self.f)
            self(zero, zero, zero)

    def __call__(self, tau_pre: np.ndarray, v: np.ndarray, bias: np.ndarray | None = None) -> np.ndarray:
        """The feed-forward torque (callers may skip the call when ``active`` is False).

        ``bias``: the arm's h = C v + g of this step; needed by ``torque_unbiased`` and
        ``yielding`` only. Every mode runs the compiled block
        (:func:`~.kernel_blocks.friction_feed_forward`, the one implementation the compiled
        laws call too): a dozen numpy calls on 7 numbers would cost several times more.
        """
        if self._unbiased and bias is None:
            raise ValueError(f"friction_comp={self.mode.value} needs the bias torques h of the step")
        out = np.empty_like(self.f)
        friction_feed_forward(
            tau_pre, v, v if bias is None else bias, self.f, self.b, self.scale, self.code, out
        )
        return out


class TaskInertia:
    """Applies Λ = (J M⁻¹ Jᵀ)⁻¹ by solving with Λ⁻¹ (LAPACK ``dposv``: Cholesky and
    solve in one call, no inverse formed).

    When Λ⁻¹ is not positive definite, or its condition number (1-norm estimate,
    LAPACK ``dpocon``) exceeds ``threshold``, a damped pseudo-inverse with the same
    eigenvectors is used instead, its smallest eigenvalues lifted so that the condition
    number stays at ``threshold``. Positive definiteness is checked every step; the
    condition number every ``check_every`` steps, and every step while it is above
    the threshold (it changes smoothly with the posture: at 1 kHz, ten steps are 10 ms).
    Steps using the fallback and the largest condition number seen are reported.
    ``threshold`` > 1: the range of ``controller.condition_threshold``
    (``config.schemas.CONDITION``), which the controllers check.

    The compiled laws solve with ``kernel_blocks.cholesky``/``cholesky_solve``: LAPACK's
    dposv in compiled form, not a second implementation of this law (kernel_blocks' doc says
    why the numpy laws keep LAPACK).
    """

    def __init__(self, threshold: float, check_every: int = 10):
        self.threshold = float(threshold)
        self.check_every = int(check_every)
        self.fallback_steps = 0
        self.max_condition = 0.0
        self._step = 0
        self._ill = False

    def due(self) -> bool:
        """Whether this step's solve checks the condition number (every ``check_every``
        steps, and every step while above the threshold)."""
        return self._ill or self._step % self.check_every == 0

    def count_unchecked(self) -> None:
        """Count a step that was not :meth:`due` and whose Λ solve ran elsewhere (a compiled
        step's own Cholesky), so that the check schedule stays the one :meth:`solve` keeps."""
        self._step += 1

    def solve(self, J: np.ndarray, JMinv: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """Λ·rhs for a vector (6) or a matrix (6×k), given J and J M⁻¹ of this step."""
        # The transpose of the symmetric product is Fortran-ordered: LAPACK works on it
        # in place, without a copy.
        lam_inv = JMinv.dot(J.T).T
        check = self.due()
        self._step += 1
        if check:
            anorm = lapack.dlange("1", lam_inv)
        chol, x, info = _dposv(lam_inv, rhs, 0, 1)  # positional: lower=0, overwrite_a=1
        if info == 0 and not check:
            return x
        if info == 0:
            rcond, _ = lapack.dpocon(chol, anorm)
            cond = 1.0 / rcond if rcond > 0.0 else np.inf
        else:
            cond = np.inf
        self.max_condition = max(self.max_condition, cond)
        self._ill = cond > self.threshold
        if not self._ill:
            return x
        self.fallback_steps += 1
        return self.damped(JMinv.dot(J.T)).dot(rhs)

    def damped(self, lam_inv: np.ndarray) -> np.ndarray:
        """The damped pseudo-inverse of Λ⁻¹ whose condition number is capped at the threshold."""
        eigval, eigvec = np.linalg.eigh(lam_inv)
        floor = max(eigval[-1], 1e-300) / self.threshold
        return (eigvec * (eigval / (eigval * eigval + floor * floor))) @ eigvec.T

    def diagnostics(self) -> dict:
        return {
            "lambda_fallback_steps": self.fallback_steps,
            "lambda_max_condition": float(self.max_condition),
        }


class Controller(ABC):
    """Base class: holds the context, the friction feed-forward and the optional integral
    action on the pose error (``integral`` is None when ``integral_gain`` and
    ``integral_rot_gain`` are 0)."""

    def __init__(
        self,
        context: ControlContext,
        friction_comp: FrictionComp,
        use_force_feedback: bool,
        name: str,
        **integral_settings: Any,
    ):
        """``integral_settings``: the ``integral_*`` fields of
        :class:`~compliant_docking.config.schemas.ControllerConfig`, passed on by name to
        :meth:`PoseIntegral.from_settings` (a new one needs no line here)."""
        self.ctx = context
        self.arm = context.arm
        self.name = name
        self.use_force_feedback = bool(use_force_feedback)
        self.friction = FrictionFeedForward(context.joint_friction, context.joint_damping, friction_comp)
        # a force and a moment the law adds to its stiffness wrench (docs/controllers/integral.md)
        self.integral = PoseIntegral.from_settings(context.axis, context.dt, **integral_settings)

    @abstractmethod
    def compute(self, t: float, state: ArmModel, ref: Reference, wrench: np.ndarray) -> np.ndarray:
        """Joint torque command (before clipping) at time t.

        ``state``: the arm after ``update(q, v)`` of this step (q, v, M, M⁻¹, h, J, J̇v,
        TCP pose and twist). ``ref``: the reference of this step. ``wrench``: measured
        external wrench [f; m] on the tool at the TCP, world axes (one step old).
        """

    def diagnostics(self) -> dict:
        """Scalars about the run for ``metrics.json`` (solver stats, fallbacks, …)."""
        return {}

    def integral_diagnostics(self) -> dict:
        """The integral action's, for the subclasses' ``diagnostics`` (empty when off)."""
        return {} if self.integral is None else self.integral.diagnostics()

    def timeseries(self) -> dict[str, np.ndarray]:
        """Per-step signals for the run's time series, one row per step (name → array
        of shape (n,) or (n, k); columns ``name`` or ``name_1 … name_k``)."""
        return {}


def vector_setting(values, size: int, key: str) -> np.ndarray:
    """A float vector of the given size (a scalar is broadcast) for the setting ``key``
    (its range is the schema's, checked by the constructor: ``config.ranges.require``)."""
    arr = np.asarray(values, dtype=float)
    if arr.ndim == 0:
        arr = np.full(size, float(arr))
    if arr.shape != (size,) or not np.isfinite(arr).all():
        raise ValueError(f"{key} must be {size} finite numbers, got {list(np.atleast_1d(values))}")
    return arr.copy()
