r"""``controller=se3_lie``: impedance in exponential coordinates of SE(3).

Kim, Sung, Choi, Park, Chung 2025 (IEEE T-RO); docs/control_laws.md §3;
docs/controllers/se3_lie.md.

Conventions
-----------
Poses T = (R, p) of the TCP in the world; twists and wrenches are ``[linear; angular]``
(:mod:`compliant_docking.control.lie`). The law works in BODY (TCP-frame) coordinates:

* V = [Rᵀṗ; Rᵀω]: body twist of the TCP [m/s, rad/s]; V = J_b v with the body Jacobian
  J_b = diag(Rᵀ, Rᵀ)·J (J: the world-axes TCP Jacobian of
  :class:`~compliant_docking.sim.models.ArmModel`).
* V̇ = [Rᵀ(p̈ − ω×ṗ); Rᵀω̇] is its time derivative: NOT the rotated classical
  acceleration, the linear part loses ω×ṗ. So V̇ = J_b q̈ + J̇_b v with
  J̇_b v = [Rᵀ(a − ω×ṗ); Rᵀα], where [a; α] = J̇v is the classical (world-axes) bias
  acceleration of the TCP.
* The reference (world axes, classical accelerations) gives T_d = (R_d, p_d),
  V_d = [R_dᵀṗ_d; R_dᵀω_d] and V̇_d = [R_dᵀ(p̈_d − ω_d×ṗ_d); R_dᵀα_d] in the same way.
* F_body = [Rᵀf; Rᵀm]: the measured external wrench ON the tool at the TCP [N, N·m];
  F_d: a desired wrench in the desired TCP frame (``desired_wrench``, zero by default).

The law
-------
    T̃ = T⁻¹T_d,  λ = log6(T̃),  Ṽ = Ad(T̃)V_d − V,  λ̇ = dexp⁻¹(λ)Ṽ,
    F̃ = Ad(T̃)⁻ᵀF_d − F_body,   γ = dexp(λ)ᵀF̃,

dexp being the right-trivialised differential of exp (``lie.dexp``: d/dt T̃ = Ṽ^ T̃,
Ṽ = dexp(λ)λ̇). The closed loop asked for is the impedance

    A·(d/dt Ṽ) + D·Ṽ + dexp(λ)⁻ᵀ·K·λ = F̃,                                     (1)

written in λ-coordinates (Ṽ = dexp·λ̇, d/dt Ṽ = dexp·λ̈ + ḋexp·λ̇) as

    λ̈_ref = −K_V λ̇ − K_P λ + K_F γ,
    K_V = dexp⁻¹(A⁻¹D·dexp + ḋexp),  K_P = dexp⁻¹A⁻¹dexp⁻ᵀK,  K_F = dexp⁻¹A⁻¹dexp⁻ᵀ,

and, since d/dt Ṽ = Ad(T̃)V̇_d + ad(Ṽ)V − V̇, the body acceleration to realise is

    V̇_ref = Ad(T̃)V̇_d − dexp(λ)λ̈_ref + ad(Ṽ)V − ḋexp(λ, λ̇)λ̇.                   (2)

Two evaluations of (2), equal up to round-off (tests/control/test_se3_lie.py checks it):

* ``formulation=lambda_space``: literally as above. dexp, dexp⁻¹ (closed form) and
  ḋexp come from ``lie.dexp_inv`` / ``lie.dexp_all``; the gain matrices are never
  formed: λ̈_ref = dexp⁻¹[A⁻¹(dexp⁻ᵀ(γ − Kλ) − D·dexp·λ̇) − ḋexp·λ̇]. The shared prelude
  (body vectors, λ, Ṽ, F̃, base, J_b, the floor) is the compiled kernel's, staged; this
  λ-space finish (:meth:`SE3LieController._lambda_space`) is numpy.
* ``formulation=twist`` (default): substituting λ̈_ref into (2), dexp·dexp⁻¹ = I and
  the two ḋexp·λ̇ terms cancel exactly, leaving

      V̇_ref = Ad(T̃)V̇_d + ad(Ṽ)V − A⁻¹(F̃ − D·Ṽ − dexp(λ)⁻ᵀ·K·λ),

  which needs only dexp⁻ᵀ applied to one vector (closed form, the coefficients of
  λ's own log). The step runs compiled, one kernel call (:mod:`~.se3_kernel`, general
  symmetric A, D, K; speed: docs/controllers/se3_lie.md).

A is constant: A⁻¹ enters only through G = A⁻¹[I, D], obtained once at construction
by a Cholesky solve. The time-varying matrices are never inverted numerically (dexp⁻¹ is
the closed form; Λ is applied by a Cholesky solve every step).

Redundancy resolution, with Λ = (J_b M⁻¹ J_bᵀ)⁻¹ (a damped pseudo-inverse past
``condition_threshold``, with a diagnostic: :class:`~.base.TaskInertia`),
J̄ = M⁻¹J_bᵀΛ and N = I − J̄J_b:

    q̈ = J̄(V̇_ref − J̇_b v) + N(−b·v),     τ = M q̈ + h − J_bᵀF_body + friction feed-forward,

evaluated without forming J̄ or N (M N = M − J_bᵀΛJ_b, J_b v = V):

    τ = J_bᵀ[Λ(V̇_ref − J̇_b v + b·V) − F_body] − b·M v + h.

b = ``null_damping`` is a joint ACCELERATION gain [1/s] (null-space motion decays as
q̈ = −b v), as the spec writes it. With force feedback on, the contact wrench is
cancelled in the arm dynamics and the tool obeys (1): a constant push F settles where
dexp⁻ᵀKλ = −F, i.e. at a displacement F/k for small displacements. With
``use_force_feedback`` off, F_body is zero in both places.

Domain: λ is unique only for ‖λ_rot‖ < π; at ‖λ_rot‖ ≥ π − ``lie.PI_MARGIN`` the step
raises ``ValueError`` with lie's message (the run fails with that one line). A discrete
step rarely lands within the margin: log3 returns angles ≤ π, so an error that moves
through π shows as λ_rot flipping to the opposite axis between two steps (both angles
above π/2, negative dot product); that raises the same way.

Units: A [kg | kg·m²], D [N·s/m | N·m·s/rad], K [N/m | N·m/rad] (translational rows
first), null_damping [1/s].
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from compliant_docking.config import SE3Formulation as Formulation
from compliant_docking.config import ranges, schemas
from compliant_docking.control import lie
from compliant_docking.control.base import Controller, TaskInertia
from compliant_docking.control.se3_kernel import StepKernel
from compliant_docking.control.shaping import inertia_floor
from compliant_docking.planning.base import Reference
from compliant_docking.sim.context import ControlContext
from compliant_docking.sim.models import ArmModel

_sqrt = math.sqrt


def _matrix(value, label: str) -> np.ndarray:
    """A symmetric 6×6 matrix from a 6-vector (its diagonal) or a 6×6 array."""
    m = np.asarray(value, dtype=float)
    if m.shape == (6,):
        m = np.diag(m)
    if m.shape != (6, 6) or not np.isfinite(m).all():
        raise ValueError(
            f"controller.{label} must be 6 finite values (a diagonal) or a 6×6 matrix, got shape {m.shape}"
        )
    if not np.allclose(m, m.T, rtol=0.0, atol=1e-12 * max(1.0, float(np.abs(m).max()))):
        raise ValueError(f"controller.{label} must be symmetric")
    return 0.5 * (m + m.T)


class SE3LieController(Controller):
    """SE(3) exponential-coordinate impedance (the law is in the module docstring).

    ``A_diag``, ``D_diag``, ``K_diag``: diagonals of the 6×6 desired inertia, damping and
    stiffness (translation first). ``A``, ``D``, ``K`` (symmetric 6×6 arrays) replace them
    when given (programmatic use; the config carries diagonals). A must be positive
    definite, D and K positive semi-definite. ``desired_wrench``: F_d = [f; m] in the
    desired TCP frame [N, N·m]. ``formulation``: ``twist`` or ``lambda_space``.

    After each step the controller keeps (for inspection and tests) ``lam`` (λ),
    ``V_tilde``, ``F_tilde``, ``Vdot_ref`` and, with ``lambda_space``, ``lam_dot``,
    ``gamma``, ``lam_ddot_ref``, ``dexp``, ``dexp_inv``, ``dexp_dot``.
    """

    def __init__(
        self,
        context: ControlContext,
        *,
        A_diag,
        D_diag,
        K_diag,
        null_damping: float,
        condition_threshold: float,
        desired_wrench,
        formulation: Formulation | str,
        apparent_inertia_floor: float | None,
        A=None,
        D=None,
        K=None,
        **common,
    ):
        super().__init__(context, **common)
        # the schema's ranges (a diagonal given as a matrix instead: checked below)
        given = {"A_diag": (A_diag, A), "D_diag": (D_diag, D), "K_diag": (K_diag, K)}
        ranges.require(
            schemas.SE3LieConfig,
            "controller",
            **{k: d for k, (d, m) in given.items() if m is None},
            null_damping=null_damping,
            condition_threshold=condition_threshold,
            desired_wrench=desired_wrench,
            apparent_inertia_floor=apparent_inertia_floor,
        )
        self.A = _matrix(A_diag if A is None else A, "A_diag" if A is None else "A")
        self.D = _matrix(D_diag if D is None else D, "D_diag" if D is None else "D")
        self.K = _matrix(K_diag if K is None else K, "K_diag" if K is None else "K")
        try:
            self._A_chol = cho_factor(self.A)
        except np.linalg.LinAlgError:
            raise ValueError(
                f"controller.A_diag must give a positive definite inertia A, "
                f"got diagonal {np.diag(self.A).tolist()}"
            ) from None
        for label, m in (("D_diag", self.D), ("K_diag", self.K)):
            if np.linalg.eigvalsh(m).min() < -1e-12 * max(1.0, float(np.abs(m).max())):
                raise ValueError(
                    f"controller.{label} must be positive semi-definite "
                    f"(a non-negative diagonal), got diagonal {np.diag(m).tolist()}"
                )
        F_d = np.asarray(desired_wrench, dtype=float)
        self.formulation = Formulation(formulation)
        self.desired_wrench = F_d
        self.null_damping = float(null_damping)
        self.task_inertia = TaskInertia(condition_threshold)
        # G = A⁻¹[I, D] (one Cholesky solve, here): A⁻¹(x − D y) = G·[x; −y]
        self.G = np.ascontiguousarray(cho_solve(self._A_chol, np.hstack([np.eye(6), self.D])))
        # the deviation from §3 that keeps the delayed force feedback stable (None: off, or
        # no force feedback: no such loop; docs/controllers/se3_lie.md): A_eff ⪰ ratio·Λ_b,
        # applied to A⁻¹(…) in V̇_ref
        if (
            apparent_inertia_floor is not None
            and self.use_force_feedback
            and np.any(self.A - np.diag(np.diag(self.A)))
        ):
            raise ValueError("controller.apparent_inertia_floor needs a diagonal A (or null: off)")
        self.inertia_floor = inertia_floor(np.diag(self.A), apparent_inertia_floor, self.use_force_feedback)

        self._z = np.zeros(12)  # [dexp⁻ᵀ(γ − Kλ); −dexp·λ̇] for G (lambda_space)
        self.lam_dot = self.gamma = self.lam_ddot_ref = None
        self.dexp = self.dexp_inv = self.dexp_dot = None
        # the step: one compiled kernel (se3_kernel.py); lambda_space finishes V̇_ref in numpy
        self._kernel = StepKernel(
            self, int(context.n_steps), None if self.formulation is Formulation.twist else self._lambda_space
        )

    # ------------------------------------------------------------------ the step
    def compute(self, t: float, state: ArmModel, ref: Reference, wrench: np.ndarray) -> np.ndarray:
        return self._kernel(t, state, ref, wrench)

    def _lambda_space(self, lam, V_tilde, F_tilde, base) -> np.ndarray:
        """``formulation=lambda_space``: λ̈_ref = −K_Vλ̇ − K_Pλ + K_Fγ, then
        V̇_ref = Ad(T̃)V̇_d − dexp·λ̈_ref + ad(Ṽ)V − ḋexp·λ̇ (returned as V̇_ref − J̇_b v + b·V)."""
        lam_dot = lie.dexp_inv(lam).dot(V_tilde)
        X, Xi, Xd = lie.dexp_all(lam, lam_dot)
        gamma = F_tilde.dot(X)  # dexp(λ)ᵀF̃
        z = self._z
        z[:6] = (gamma - self.K.dot(lam)).dot(Xi)  # dexp⁻ᵀ(γ − Kλ)
        z[6:] = -X.dot(lam_dot)  # −dexp·λ̇
        Xd_lam_dot = Xd.dot(lam_dot)
        # dexp⁻¹[A⁻¹(dexp⁻ᵀ(γ − Kλ) − D·dexp·λ̇) − ḋexp·λ̇]
        lam_ddot = Xi.dot(self.G.dot(z) - Xd_lam_dot)
        a = base.copy()
        a -= X.dot(lam_ddot)
        a -= Xd_lam_dot
        self.lam_dot, self.gamma, self.lam_ddot_ref = lam_dot, gamma, lam_ddot
        self.dexp, self.dexp_inv, self.dexp_dot = X, Xi, Xd
        return a

    # ------------------------------------------------------------------ inspection
    lam = property(lambda self: self._kernel.field("lam"), doc="λ of the last step [m | rad]")
    V_tilde = property(
        lambda self: self._kernel.field("V_tilde"), doc="Ṽ of the last step (body axes) [m/s | rad/s]"
    )
    F_tilde = property(
        lambda self: self._kernel.field("F_tilde"), doc="F̃ of the last step (body axes) [N | N·m]"
    )

    @property
    def Vdot_ref(self) -> np.ndarray:
        """V̇_ref of the last step (body axes) [m/s², rad/s²]."""
        return self._kernel.field("a") + self._kernel.field("a_offset")

    @property
    def max_rotation_error(self) -> float:
        """The largest ‖λ_rot‖ seen [rad]."""
        return float(self._kernel.state["max_rot"][0])

    def raise_out_of_domain(self, t: float, w, th: float, w_prev, flipped: bool):
        """The step's ValueError: ‖λ_rot‖ at π, or λ_rot flipped through π within one step."""
        if not flipped:
            try:
                lie.check_rotation_domain((0.0, 0.0, 0.0, *w))
            except ValueError as exc:
                raise ValueError(f"se3_lie at t = {t:.3f} s: {exc}") from None
        p0, p1, p2 = w_prev
        raise ValueError(
            f"se3_lie at t = {t:.3f} s: the orientation error |λ_rot| passed through π "
            f"within one step (λ_rot flipped from {_sqrt(p0 * p0 + p1 * p1 + p2 * p2):.6g} "
            f"rad about one axis to {th:.6g} rad about the opposite one): the SE(3) "
            f"impedance requires |λ_rot| < π (the pose-error logarithm is not unique at π)"
        )

    def lambda_gains(self, lam, lam_dot):
        """(K_V, K_P, K_F) at (λ, λ̇), formed explicitly with solves (for tests)."""
        X, Xi, Xd = lie.dexp_all(lam, lam_dot)
        K_F = np.linalg.solve(X, cho_solve(self._A_chol, np.linalg.solve(X.T, np.eye(6))))
        K_V = np.linalg.solve(X, cho_solve(self._A_chol, self.D.dot(X)) + Xd)
        return K_V, K_F.dot(self.K), K_F

    def diagnostics(self) -> dict:
        out = {
            **self.task_inertia.diagnostics(),
            "se3_max_rotation_error_rad": float(self.max_rotation_error),
            **self.integral_diagnostics(),
        }
        if self.inertia_floor is not None:
            out.update(self.inertia_floor.diagnostics())
        return out

    def timeseries(self) -> dict[str, np.ndarray]:
        return {"se3_lambda": self._kernel.lam_log()}
