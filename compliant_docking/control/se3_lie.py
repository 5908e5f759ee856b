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
  formed: λ̈_ref = dexp⁻¹[A⁻¹(dexp⁻ᵀ(γ − Kλ) − D·dexp·λ̇) − ḋexp·λ̇]. Numpy throughout.
* ``formulation=twist`` (default): substituting λ̈_ref into (2), dexp·dexp⁻¹ = I and
  the two ḋexp·λ̇ terms cancel exactly, leaving

      V̇_ref = Ad(T̃)V̇_d + ad(Ṽ)V − A⁻¹(F̃ − D·Ṽ − dexp(λ)⁻ᵀ·K·λ),

  which needs only dexp⁻ᵀ applied to one vector (closed form, the coefficients of
  λ's own log). With diagonal A, D, K (the config's case) the step runs compiled, one
  kernel call (:mod:`~.se3_kernel`; speed: docs/controllers/se3_lie.md); else in numpy.

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
from compliant_docking.control import se3_kernel as kern
from compliant_docking.control.base import Controller, TaskInertia

# lie.py's scalar kernels (log3 and the Taylor/closed-form coefficients), called directly
# so that one evaluation of the coefficients serves both log6 and dexp⁻ᵀ.
from compliant_docking.control.lie import PI_MARGIN, inv_coefficients, log3_list
from compliant_docking.control.se3_kernel import TwistKernel
from compliant_docking.control.shaping import inertia_floor
from compliant_docking.planning.base import Reference
from compliant_docking.sim.context import ControlContext
from compliant_docking.sim.models import ArmModel

_sqrt = math.sqrt
_fromiter = np.fromiter
_F64 = np.float64
_PI_LIMIT = math.pi - PI_MARGIN
_HALF_PI = 0.5 * math.pi
_HALF_PI_SQ = _HALF_PI * _HALF_PI


def _matrix(value, label: str) -> np.ndarray:
    """A symmetric 6×6 matrix from a 6-vector (its diagonal) or a 6×6 array."""
    m = np.asarray(value, dtype=float)
    if m.shape == (6,):
        m = np.diag(m)
    if m.shape != (6, 6) or not np.isfinite(m).all():
        raise ValueError(f"controller.{label} must be 6 finite values (a diagonal) or a 6×6 "
                         f"matrix, got shape {m.shape}")
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

    def __init__(self, context: ControlContext, *,
                 A_diag,
                 D_diag,
                 K_diag,
                 null_damping: float, condition_threshold: float,
                 desired_wrench,
                 formulation: Formulation | str,
                 apparent_inertia_floor: float | None,
                 A=None, D=None, K=None, **common):
        super().__init__(context, **common)
        given = {"A_diag": (A_diag, A), "D_diag": (D_diag, D), "K_diag": (K_diag, K)}  # a matrix: checked below
        ranges.require(schemas.SE3LieConfig, "controller", **{k: d for k, (d, m) in given.items() if m is None},
                       null_damping=null_damping, condition_threshold=condition_threshold,  # the schema's ranges
                       desired_wrench=desired_wrench, apparent_inertia_floor=apparent_inertia_floor)
        self.A = _matrix(A_diag if A is None else A, "A_diag" if A is None else "A")
        self.D = _matrix(D_diag if D is None else D, "D_diag" if D is None else "D")
        self.K = _matrix(K_diag if K is None else K, "K_diag" if K is None else "K")
        try:
            self._A_chol = cho_factor(self.A)
        except np.linalg.LinAlgError:
            raise ValueError(f"controller.A_diag must give a positive definite inertia A, "
                             f"got diagonal {np.diag(self.A).tolist()}") from None
        for label, m in (("D_diag", self.D), ("K_diag", self.K)):
            if np.linalg.eigvalsh(m).min() < -1e-12 * max(1.0, float(np.abs(m).max())):
                raise ValueError(f"controller.{label} must be positive semi-definite "
                                 f"(a non-negative diagonal), got diagonal {np.diag(m).tolist()}")
        F_d = np.asarray(desired_wrench, dtype=float)
        self.formulation = Formulation(formulation)
        self.desired_wrench = F_d
        self.null_damping = float(null_damping)
        self.task_inertia = TaskInertia(condition_threshold)
        # G = A⁻¹[I, D] (one Cholesky solve, here): A⁻¹(x − D y) = G·[x; −y]
        self.G = np.ascontiguousarray(cho_solve(self._A_chol, np.hstack([np.eye(6), self.D])))
        self._twist = self.formulation is Formulation.twist
        # diagonal A, D, K (the config's case): the compiled step, element by element
        diagonal = [not np.any(m - np.diag(np.diag(m))) for m in (self.A, self.D, self.K)]
        self._K_diag = np.diag(self.K).tolist() if diagonal[2] else None
        self._G_diag = (np.diag(self.G[:, :6]).tolist() + np.diag(self.G[:, 6:]).tolist()
                        if diagonal[0] and diagonal[1] else None)
        # the deviation from §3 that keeps the delayed force feedback stable (None: off, or
        # no force feedback: no such loop; docs/controllers/se3_lie.md): A_eff ⪰ ratio·Λ_b,
        # applied to A⁻¹(…) in V̇_ref
        if apparent_inertia_floor is not None and self.use_force_feedback and not diagonal[0]:
            raise ValueError("controller.apparent_inertia_floor needs a diagonal A (or null: off)")
        self.inertia_floor = inertia_floor(np.diag(self.A), apparent_inertia_floor, self.use_force_feedback)

        nv = self.arm.nv
        # World vectors, one per row, turned into TCP-frame vectors by ONE product per step
        # (row x ↦ xR = (Rᵀx)ᵀ): rows 0-2 the columns of R_d | 3 p_d − p | 4-5 ṗ, ω |
        # 6-7 J̇v = [a; α] | 8-9 ṗ_d, ω_d | 10-11 p̈_d, α_d | 12-13 f, m
        # | 14-15 the integral force F_i and moment M_i (only with integral action).
        rows = 16 if self.integral is not None else 14
        self._world = np.zeros((rows, 3))
        self._body = np.zeros((rows, 3))
        self._w_integral = self._world[14:16] if self.integral is not None else np.zeros((2, 3))
        flat = self._world.reshape(3 * rows)
        self._w_err = self._world[3]
        self._w_twist, self._w_jdv = flat[12:18], flat[18:24]
        self._w_ref_twist, self._w_ref_accel = flat[24:30], flat[30:36]
        self._w_wrench = flat[36:42]
        self._F_body = self._body.reshape(3 * rows)[36:42]  # view: F_body after the product
        self._buffers = (self._world, self._w_err, self._w_twist, self._w_jdv,
                         self._w_ref_twist, self._w_ref_accel, self._w_wrench, self._body)
        self._z = np.zeros(12)  # [dexp⁻ᵀ(γ − Kλ); −dexp·λ̇] for G (lambda_space)
        self._Jb = np.zeros((6, nv))
        self._Jb_lin, self._Jb_ang = self._Jb[:3], self._Jb[3:]
        self._has_F_d, self._F_d = bool(np.any(F_d)), F_d.tolist()
        self._max_rot = 0.0
        self._w_prev = (0.0, 0.0, 0.0)  # λ_rot of the previous step
        # per-step record of λ (exponential coordinates of the pose error)
        self._lam_log = np.zeros((max(int(context.n_steps), 0), 6))
        self._n_log = len(self._lam_log)
        self._k = 0
        # quantities of the last step (for inspection and tests; the kernel keeps its own)
        self._lam, self._V_tilde, self._F_tilde, self._a = np.zeros(6), (0.0,) * 6, (0.0,) * 6, np.zeros(6)
        self._a_offset = (0.0,) * 6
        self.lam_dot = self.gamma = self.lam_ddot_ref = None
        self.dexp = self.dexp_inv = self.dexp_dot = None
        self._kernel = TwistKernel(self, self._K_diag, self._G_diag) if (
            self._twist and self._K_diag is not None and self._G_diag is not None) else None

    # ------------------------------------------------------------------ the step
    def compute(self, t: float, state: ArmModel, ref: Reference, wrench: np.ndarray) -> np.ndarray:
        if self._kernel is not None:  # twist, diagonal gains: compiled (se3_kernel.py)
            return self._kernel(t, state, ref, wrench)
        arm = state
        # --- world → TCP (body) axes: one product for every vector
        W, w_err, w_twist, w_jdv, w_ref_twist, w_ref_accel, w_wrench, body = self._buffers
        W[0:3] = ref.rot.T
        np.subtract(ref.pos, arm.pos, out=w_err)
        w_twist[:] = arm.twist
        w_jdv[:] = arm.Jdot_v
        w_ref_twist[:] = ref.twist
        w_ref_accel[:] = ref.accel
        if self.use_force_feedback:
            w_wrench[:] = wrench
        integral = self.integral
        if integral is not None:  # F_i, M_i (world) ride along to TCP axes
            self._w_integral.reshape(6)[:] = integral.update_pose(w_err, wrench, ref.rot, arm.rot_T)
        W.dot(arm.rot, out=body)
        rows = body.tolist()
        F_i = rows.pop(14) + rows.pop(14) if integral is not None else None  # [F_i; M_i]
        ((c00, c01, c02), (c10, c11, c12), (c20, c21, c22), (e0, e1, e2),
         (pv0, pv1, pv2), (pw0, pw1, pw2), (ja0, ja1, ja2), (jb0, jb1, jb2),
         (dv0, dv1, dv2), (dw0, dw1, dw2), (da0, da1, da2), (db0, db1, db2),
         (f0, f1, f2), (m0, m1, m2)) = rows
        # R̃ = RᵀR_d has columns (c00, c01, c02), (c10, …), (c20, …); p̃ = Rᵀ(p_d − p) = e

        # --- λ = log6(T̃) = [J(w)⁻¹p̃; w], w = log3(R̃); refused at ‖w‖ ≥ π
        w0, w1, w2, th = log3_list(c00, c10, c20, c01, c11, c21, c02, c12, c22)
        if not th < _PI_LIMIT:
            self.raise_out_of_domain(t, (w0, w1, w2), th, self._w_prev, False)
        if th > _HALF_PI:  # a step through π shows as a flip of λ_rot (log3 stays ≤ π)
            p0, p1, p2 = self._w_prev
            if p0 * w0 + p1 * w1 + p2 * w2 < 0.0 and p0 * p0 + p1 * p1 + p2 * p2 > _HALF_PI_SQ:
                self.raise_out_of_domain(t, (w0, w1, w2), th, self._w_prev, True)
        self._w_prev = (w0, w1, w2)
        g, e, dg, de = inv_coefficients(th)  # J(w)⁻¹'s coefficients g, e and g1, e1
        wp = w0 * e0 + w1 * e1 + w2 * e2
        l0 = g * e0 - 0.5 * (w1 * e2 - w2 * e1) + e * wp * w0
        l1 = g * e1 - 0.5 * (w2 * e0 - w0 * e2) + e * wp * w1
        l2 = g * e2 - 0.5 * (w0 * e1 - w1 * e0) + e * wp * w2
        k = self._k
        if k < self._n_log:  # λ is written once, into its row of the record (a view)
            lam = self._lam_log[k]
            lam[:] = (l0, l1, l2, w0, w1, w2)
        else:
            lam = _fromiter((l0, l1, l2, w0, w1, w2), _F64, 6)
        self._k = k + 1

        # --- Ad(T̃)V_d and Ad(T̃)V̇_d: with T̃ = T⁻¹T_d these are the reference twist and
        # its derivative carried to the TCP, in its axes (rotations commute with ×):
        #   Ad(T̃)V_d = [Rᵀṗ_d − (Rᵀω_d) × p̃;  Rᵀω_d]
        #   Ad(T̃)V̇_d = [Rᵀp̈_d − (Rᵀω_d) × (Rᵀṗ_d) − (Rᵀα_d) × p̃;  Rᵀα_d]
        av0 = dv0 - (dw1 * e2 - dw2 * e1)
        av1 = dv1 - (dw2 * e0 - dw0 * e2)
        av2 = dv2 - (dw0 * e1 - dw1 * e0)
        # --- Ṽ = Ad(T̃)V_d − V
        t0, t1, t2 = av0 - pv0, av1 - pv1, av2 - pv2
        t3, t4, t5 = dw0 - pw0, dw1 - pw1, dw2 - pw2
        # --- base = Ad(T̃)V̇_d + ad(Ṽ)V − J̇_b v + b·V, with ad(Ṽ)V = [w̃×v + ṽ×w; w̃×w]
        #     and J̇_b v = [Rᵀa − (Rᵀω)×(Rᵀṗ); Rᵀα]
        bn = self.null_damping
        aa0 = da0 - (dw1 * dv2 - dw2 * dv1) - (db1 * e2 - db2 * e1)
        aa1 = da1 - (dw2 * dv0 - dw0 * dv2) - (db2 * e0 - db0 * e2)
        aa2 = da2 - (dw0 * dv1 - dw1 * dv0) - (db0 * e1 - db1 * e0)
        o0 = ja0 - (pw1 * pv2 - pw2 * pv1) - bn * pv0  # J̇_b v − b·V
        o1 = ja1 - (pw2 * pv0 - pw0 * pv2) - bn * pv1
        o2 = ja2 - (pw0 * pv1 - pw1 * pv0) - bn * pv2
        o3, o4, o5 = jb0 - bn * pw0, jb1 - bn * pw1, jb2 - bn * pw2
        base = (aa0 + t4 * pv2 - t5 * pv1 + t1 * pw2 - t2 * pw1 - o0,
                aa1 + t5 * pv0 - t3 * pv2 + t2 * pw0 - t0 * pw2 - o1,
                aa2 + t3 * pv1 - t4 * pv0 + t0 * pw1 - t1 * pw0 - o2,
                db0 + t4 * pw2 - t5 * pw1 - o3,
                db1 + t5 * pw0 - t3 * pw2 - o4,
                db2 + t3 * pw1 - t4 * pw0 - o5)

        # --- F̃ = Ad(T̃)⁻ᵀF_d − F_body, with Ad(T̃)⁻ᵀ[f; m] = [R̃f; p̃ × R̃f + R̃m]
        if self._has_F_d:
            g0, g1, g2, n0, n1, n2 = self._F_d
            r0 = c00 * g0 + c10 * g1 + c20 * g2
            r1 = c01 * g0 + c11 * g1 + c21 * g2
            r2 = c02 * g0 + c12 * g1 + c22 * g2
            F_tilde = (r0 - f0, r1 - f1, r2 - f2,
                       e1 * r2 - e2 * r1 + c00 * n0 + c10 * n1 + c20 * n2 - m0,
                       e2 * r0 - e0 * r2 + c01 * n0 + c11 * n1 + c21 * n2 - m1,
                       e0 * r1 - e1 * r0 + c02 * n0 + c12 * n1 + c22 * n2 - m2)
        else:
            F_tilde = (-f0, -f1, -f2, -m0, -m1, -m2)
        if F_i is not None:  # a gains A⁻¹[RᵀF_i; RᵀM_i]: F̃ − [F_i; M_i] enters A⁻¹(F̃ − D·Ṽ − dexp⁻ᵀKλ)
            F_tilde = tuple(a - b for a, b in zip(F_tilde, F_i))
        V_tilde = (t0, t1, t2, t3, t4, t5)

        J, Jb, Rt = arm.J, self._Jb, arm.rot_T
        Rt.dot(J[:3], out=self._Jb_lin)
        Rt.dot(J[3:], out=self._Jb_ang)
        JbMinv = Jb.dot(arm.Minv)
        # body J_b, J_b M⁻¹ and the floor's P: A⁻¹(…) → A_eff⁻¹(…), a = base + P(a − base)
        P = None if self.inertia_floor is None else self.inertia_floor.current(Jb, JbMinv)
        if self._twist:
            # --- V̇_ref = Ad(T̃)V̇_d + ad(Ṽ)V − A⁻¹(F̃ − D·Ṽ − dexp⁻ᵀKλ)
            # dexp⁻ᵀy = [J⁻ᵀy_v; Qiᵀy_v + J⁻ᵀy_w] with J⁻ᵀy = g y + ½ w×y + e w(w·y) and
            # Qiᵀy = g1 s y + ½ λ_v×y + e(λ_v(w·y) + w(λ_v·y)) + e1 s w(w·y), s = w·λ_v
            y0, y1, y2, y3, y4, y5 = self.K.dot(lam).tolist()
            s = w0 * l0 + w1 * l1 + w2 * l2
            wy = w0 * y0 + w1 * y1 + w2 * y2
            ly = l0 * y0 + l1 * y1 + l2 * y2
            wz = w0 * y3 + w1 * y4 + w2 * y5
            ewy = e * wy
            ewz = e * wz
            qs = dg * s  # g1 s
            qw = e * ly + de * s * wy  # e λ_v·y + e1 s w·y
            # r = F̃ − dexp⁻ᵀKλ
            r0 = F_tilde[0] - (g * y0 + 0.5 * (w1 * y2 - w2 * y1) + ewy * w0)
            r1 = F_tilde[1] - (g * y1 + 0.5 * (w2 * y0 - w0 * y2) + ewy * w1)
            r2 = F_tilde[2] - (g * y2 + 0.5 * (w0 * y1 - w1 * y0) + ewy * w2)
            r3 = F_tilde[3] - (qs * y0 + 0.5 * (l1 * y2 - l2 * y1) + ewy * l0 + qw * w0
                               + g * y3 + 0.5 * (w1 * y5 - w2 * y4) + ewz * w0)
            r4 = F_tilde[4] - (qs * y1 + 0.5 * (l2 * y0 - l0 * y2) + ewy * l1 + qw * w1
                               + g * y4 + 0.5 * (w2 * y3 - w0 * y5) + ewz * w1)
            r5 = F_tilde[5] - (qs * y2 + 0.5 * (l0 * y1 - l1 * y0) + ewy * l2 + qw * w2
                               + g * y5 + 0.5 * (w0 * y4 - w1 * y3) + ewz * w2)
            # a = V̇_ref − J̇_b v + b·V = base − A⁻¹(r − D·Ṽ) = base − G·[r; −Ṽ]
            a = _fromiter(base, _F64, 6)
            a -= self.G.dot(_fromiter((r0, r1, r2, r3, r4, r5, -t0, -t1, -t2, -t3, -t4, -t5),
                                      _F64, 12))
        else:
            a = self._lambda_space(lam, V_tilde, F_tilde, base)

        if P is not None:  # (None: floor inactive, a untouched)
            base_v = _fromiter(base, _F64, 6)
            a = base_v + P.dot(a - base_v)
        force = self.task_inertia.solve(Jb, JbMinv, a)  # Λ(V̇_ref − J̇_b v + bV)
        if self.use_force_feedback:
            force -= self._F_body
        v = arm.v
        tau = force.dot(Jb)
        tau += arm.h
        tau -= bn * arm.M.dot(v)
        if self.friction.active:
            tau += self.friction(tau, v, arm.h)

        # --- bookkeeping
        if th > self._max_rot:
            self._max_rot = th
        self._lam, self._V_tilde, self._F_tilde = lam, V_tilde, F_tilde
        self._a, self._a_offset = a, (o0, o1, o2, o3, o4, o5)
        return tau

    def _lambda_space(self, lam, V_tilde, F_tilde, base) -> np.ndarray:
        """``formulation=lambda_space``: λ̈_ref = −K_Vλ̇ − K_Pλ + K_Fγ, then
        V̇_ref = Ad(T̃)V̇_d − dexp·λ̈_ref + ad(Ṽ)V − ḋexp·λ̇ (returned as V̇_ref − J̇_b v + b·V)."""
        V_tilde = np.array(V_tilde)
        F_tilde = np.array(F_tilde)
        lam_dot = lie.dexp_inv(lam).dot(V_tilde)
        X, Xi, Xd = lie.dexp_all(lam, lam_dot)
        gamma = F_tilde.dot(X)  # dexp(λ)ᵀF̃
        z = self._z
        z[:6] = (gamma - self.K.dot(lam)).dot(Xi)  # dexp⁻ᵀ(γ − Kλ)
        z[6:] = -X.dot(lam_dot)  # −dexp·λ̇
        Xd_lam_dot = Xd.dot(lam_dot)
        # dexp⁻¹[A⁻¹(dexp⁻ᵀ(γ − Kλ) − D·dexp·λ̇) − ḋexp·λ̇]
        lam_ddot = Xi.dot(self.G.dot(z) - Xd_lam_dot)
        a = np.array(base)
        a -= X.dot(lam_ddot)
        a -= Xd_lam_dot
        self.lam_dot, self.gamma, self.lam_ddot_ref = lam_dot, gamma, lam_ddot
        self.dexp, self.dexp_inv, self.dexp_dot = X, Xi, Xd
        return a

    # ------------------------------------------------------------------ inspection
    @property
    def diagonal_gains(self) -> bool:
        """Whether A, D, K are diagonal (the config's case; with twist: the compiled step)."""
        return self._K_diag is not None and self._G_diag is not None

    def _last(self, name: str, offset: int):
        return getattr(self, name) if self._kernel is None else self._kernel.mem[offset:offset + 6].copy()

    lam = property(lambda self: np.asarray(self._last("_lam", kern.LAM), dtype=float),
                   doc="λ of the last step [m | rad]")
    V_tilde = property(lambda self: np.asarray(self._last("_V_tilde", kern.V_TILDE), dtype=float),
                       doc="Ṽ of the last step (body axes) [m/s | rad/s]")
    F_tilde = property(lambda self: np.asarray(self._last("_F_tilde", kern.F_TILDE), dtype=float),
                       doc="F̃ of the last step (body axes) [N | N·m]")

    @property
    def Vdot_ref(self) -> np.ndarray:
        """V̇_ref of the last step (body axes) [m/s², rad/s²]."""
        return self._last("_a", kern.A) + self._last("_a_offset", kern.A_OFFSET)

    @property
    def max_rotation_error(self) -> float:
        """The largest ‖λ_rot‖ seen [rad]."""
        return self._max_rot if self._kernel is None else float(self._kernel.mem[kern.MAX_ROT])

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
            f"impedance requires |λ_rot| < π (the pose-error logarithm is not unique at π)")

    def lambda_gains(self, lam, lam_dot):
        """(K_V, K_P, K_F) at (λ, λ̇), formed explicitly with solves (for tests)."""
        X, Xi, Xd = lie.dexp_all(lam, lam_dot)
        K_F = np.linalg.solve(X, cho_solve(self._A_chol, np.linalg.solve(X.T, np.eye(6))))
        K_V = np.linalg.solve(X, cho_solve(self._A_chol, self.D.dot(X)) + Xd)
        return K_V, K_F.dot(self.K), K_F

    def diagnostics(self) -> dict:
        out = {**self.task_inertia.diagnostics(),
               "se3_max_rotation_error_rad": float(self.max_rotation_error),
               **self.integral_diagnostics()}
        if self.inertia_floor is not None:
            out.update(self.inertia_floor.diagnostics())
        return out

    def timeseries(self) -> dict[str, np.ndarray]:
        return {"se3_lambda": self._lam_log[:min(self._k, len(self._lam_log))]}
