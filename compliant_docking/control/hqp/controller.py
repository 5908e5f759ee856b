"""``controller=hqp``: HQP-AC, a hierarchical QP with adaptive compliance.

docs/control_laws.md §2 (Ren & Shan 2026, Acta Astronautica, §3.2); docs/controllers/hqp.md.
Decision variable: the joint acceleration q̈. Per control step, with the wrench w = [f; m]
on the tool at the TCP (world axes; the sensor's or the momentum observer's):

* contact magnitude F = max(‖w‖ − contact_deadband, 0) [N];
* adaptive stiffness (Eq. 26-27) α = 1/(1 + exp(−k_alpha F)),
  K_r = clip((1 − α) K0, K_min_ratio K0, K0) — already 0.5 K0 at F = 0;
* task inertia Λ = (J M⁻¹ Jᵀ)⁻¹ from one eigendecomposition Λ⁻¹ = V diag(λ) Vᵀ (its small
  eigenvalues floored so that cond(Λ⁻¹) ≤ condition_threshold), giving Λ^½ = V diag(λ^-½) Vᵀ;
* damping (Eq. 29) D_r = Λ^½ K_r^½ + K_r^½ Λ^½ (see :func:`damping_matrix` for the case
  where this symmetric matrix is not positive definite);
* reference wrench F_r = −D_r Δν − K_r e + F_pre, e = [x − x_d; log3(R R_dᵀ)],
  Δν = ν − ν_d, F_pre = p(t)·[axis; 0] the optional preload (:class:`PreloadRamp`), plus
  [F_i; M_i] with the optional integral action (docs/controllers/integral.md);
* level 1 (Eq. 33-36): min ‖J q̈ + J̇v − (ν̇_d + Λ⁻¹F_r)‖² + 1e-8‖q̈‖² subject to the
  zero-order-hold predictions over dt_p
      |v + dt_p q̈| ≤ v_max,  q_min ≤ q + dt_p v + ½dt_p² q̈ ≤ q_max,  |M q̈ + ĥ| ≤ τ_max,
  ĥ = h + friction feed-forward, τ_max the software clip (context.torque_limits);
* level 2 (Eq. 38-43): a_null = k_sa q̈_sa + k_ji q̈_ji with q̈_sa = ((ω_th − w)/ω_th) ∇w/‖∇w‖
  when the manipulability w = √det(J Jᵀ) < ω_th (else 0) and q̈_ji = −D_ji v − K_ji(q − q_home);
  min ‖a − a_null‖² subject to the same constraints on q̈* + N a, N = I − M⁻¹JᵀΛJ;
* τ = M(q̈* + N a*) + ĥ.

Closed loop (constraints inactive, exact model): J q̈ + J̇v = ν̇_d + Λ⁻¹F_r and the contact
adds Λ⁻¹w, so Λ ë + D_r ė + K_r e = F_pre + w. A constant push w settles at K_r e = w (+F_pre).

Both QPs are ProxQP dense problems built at their first use and updated in place
afterwards. Each step first computes both levels' optima without constraints (level 1:
the minimum-norm least squares q̈ = Jᵀ(J Jᵀ + 1e-8 I)⁻¹ b; level 2: a = a_null) and checks
them against all 21 rows with one product; a level whose optimum meets every row has it
as its QP solution and ProxQP is not called (``solve_every_step`` calls it anyway). A
level-1 solve starts from that closed form, so the component along ker J — which the 1e-8
regulariser leaves undetermined at eps_abs = 1e-5 — stays the minimum-norm one; a level-2
solve starts from a = 0, feasible by construction (docs/controllers/hqp.md).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

import compliant_docking.control.hqp.kernel as K
from compliant_docking.config import ForceSource, NullSpaceMetric
from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import HQPConfig, RobotConfig
from compliant_docking.config.validate import torque_margin_problem
from compliant_docking.control.base import Controller, vector_setting
from compliant_docking.control.hqp.compliance import PreloadRamp, modal_damping
from compliant_docking.control.hqp.manipulability import check_revolute_chain
from compliant_docking.control.hqp.qp_level import QPLevel
from compliant_docking.control.integral import off_record
from compliant_docking.control.observer import MomentumObserver
from compliant_docking.planning.base import Reference
from compliant_docking.sim.context import ControlContext
from compliant_docking.sim.models import ArmModel

#: Tikhonov regulariser of the level-1 Hessian (docs/control_laws.md §2)
REGULARISER = 1e-8
#: stand-in for an infinite bound (ProxQP wants finite numbers)
BIG = 1e20


# --------------------------------------------------------------------------- the controller
class HQPController(Controller):
    """HQP-AC (see the module doc). Parameters as in :class:`compliant_docking.config.HQPConfig`.

    Constraint rows (21): velocity v + dt_p q̈, position q + dt_p v + ½dt_p² q̈, torque
    M q̈ + ĥ, each within its limits [mid − half, mid + half]. One product
    Z = [q̈, q, v, 1]·T (T: 22×21, see :meth:`_init_constraints`) gives the rows minus
    their mid values for both closed-form candidates at once; ProxQP gets the same rows
    in q̈ units ([I; I; M] q̈ ∈ [l, u]).
    """

    def __init__(
        self,
        context: ControlContext,
        *,
        K0,
        K_min_ratio: float,
        k_alpha: float,
        omega_th: float,
        k_sa: float,
        K_ji,
        D_ji,
        k_ji: float,
        dt_p: float,
        eps_abs: float,
        force_source: ForceSource | str,
        observer_kp: float,
        observer_ki: float,
        preload_force: float,
        preload_ramp_s: float,
        contact_deadband: float,
        condition_threshold: float,
        null_space_metric: NullSpaceMetric | str,
        solve_every_step: bool,
        **common,
    ):
        super().__init__(context, **common)
        arm = self.arm
        n = arm.nv
        self.n = n
        check_revolute_chain(arm.model)
        require(  # the schema's ranges: the config check's refusals, word for word
            HQPConfig, "controller", K0=K0, K_min_ratio=K_min_ratio, k_alpha=k_alpha, omega_th=omega_th,
            k_sa=k_sa, K_ji=K_ji, D_ji=D_ji, k_ji=k_ji, dt_p=dt_p, eps_abs=eps_abs, observer_kp=observer_kp,
            observer_ki=observer_ki, preload_force=preload_force, preload_ramp_s=preload_ramp_s,
            contact_deadband=contact_deadband, condition_threshold=condition_threshold,
        )  # fmt: skip
        require(
            RobotConfig, "robot", velocity_limits=context.velocity_limits, max_torque=context.torque_limits
        )
        self.K0 = vector_setting(K0, 6, "controller.K0")
        self.min_stiffness_ratio, self.sigmoid_gain = float(K_min_ratio), float(k_alpha)
        self.deadband = float(contact_deadband)
        self.sqrt_K0 = np.sqrt(self.K0)
        self._P = self.sqrt_K0[:, None] + self.sqrt_K0[None, :]  # D_r = √s·(Λ^½ ∘ P)
        # the step kernel's workspace (a record): every per-step buffer is a view of a field
        self._work = np.zeros(1, dtype=K.work_dtype(n))
        self.threshold = float(condition_threshold)
        self.manipulability_threshold, self.singularity_weight = float(omega_th), float(k_sa)
        self.posture_stiffness = float(k_ji) * vector_setting(K_ji, n, "controller.K_ji")
        self.posture_damping = float(k_ji) * vector_setting(D_ji, n, "controller.D_ji")
        self.q_home = np.asarray(context.q_home, dtype=float).copy()
        # q̈_ji = K_ji(q_home − q) − D_ji v as one product [q, v, 1]·T_ji
        kp, kd = self.posture_stiffness, self.posture_damping
        self._T_ji = np.vstack([-np.diag(kp), -np.diag(kd), kp * self.q_home])
        self.axis = np.asarray(context.axis, dtype=float) / np.linalg.norm(context.axis)
        self.preload = PreloadRamp(preload_force, preload_ramp_s, context.dt)
        self.force_source = ForceSource(force_source)
        self.observer = (
            MomentumObserver(context, observer_kp, observer_ki)
            if self.force_source is ForceSource.observer
            else None
        )
        self.solve_every_step = bool(solve_every_step)
        self.null_space_metric = NullSpaceMetric(null_space_metric)
        self._inertia_metric = self.null_space_metric is NullSpaceMetric.inertia
        self._init_constraints(context, float(dt_p), eps_abs)
        self._init_kernel()

        # per-run statistics and per-step records (the kernel's counters: properties below)
        self.steps = 0
        self.modal_damping_steps = 0
        self.level1_fallbacks = 0  # level 1 failed: unconstrained least squares, level 2 skipped
        self.level2_zero_steps = 0  # a = 0 (level 2 failed or skipped)
        self._rec = np.zeros(int(context.n_steps), dtype=K.STEP_RECORD)

    def _view(self, field: str) -> np.ndarray:
        """The workspace's field ``field`` (kernel.work_dtype), a view the kernel writes."""
        return self._work[field][0]

    def _init_kernel(self) -> None:
        """The kernel's constants (``params``) and the views of its workspace this class reads."""
        n = self.n
        params = np.zeros(1, dtype=K.params_dtype(self.n))
        friction = self.friction
        for name, value in (
            ("deadband", self.deadband),
            ("K_min_ratio", self.min_stiffness_ratio),
            ("k_alpha", self.sigmoid_gain),
            ("threshold", self.threshold),
            ("omega_th", self.manipulability_threshold),
            ("k_sa", self.singularity_weight),
            ("regulariser", REGULARISER),
            ("inertia_metric", self._inertia_metric),
            ("use_force_feedback", self.use_force_feedback),
            ("solve_every_step", self.solve_every_step),
            ("friction", friction.active),
            ("friction_mode", friction.code),
            ("K0", self.K0),
            ("P", self._P),
            ("axis", self.axis),
            ("T_ji", self._T_ji),
            ("half", self._half),
            ("friction_f", friction.f),
            ("friction_b", friction.b),
            ("friction_scale", friction.scale),
        ):
            params[name] = value
        self._params = params
        # the integral action's record (its state advanced by the kernel; off: F_i = M_i = 0)
        self._integral = off_record() if self.integral is None else self.integral.record
        # the preload ramp's state lives in the workspace from now on
        self._view("preload")[:] = self.preload.state
        self.preload.state = self._view("preload")
        self._D = self._view("DK")[:6]  # of [D_r; K_r]
        self._JMinv, self._lam = self._view("JMinv"), self._view("lam")
        self._lam_sqrt, self._V = self._view("lam_sqrt"), self._view("V")
        self._root, self._b = self._view("root"), self._view("b")
        self._a_null, self._Na = self._view("a_null"), self._view("Na")
        self._Z = self._view("Z")
        self._tau_fast = self._Z[1, 2 * n :]  # the final candidate's torque rows
        # Load the compiled kernel now (0.2 s from numba's cache, ~12 s to compile after a
        # source change) rather than in the loop's first step: one call on the arm's current
        # state, with the argument types of the loop, into a scratch copy of the workspace.
        arm, z3, z6 = self.arm, np.zeros(3), np.zeros(6)
        K.hqp_step(
            arm.J, arm.M, arm.Minv, arm.h, arm.q, arm.v, arm.Jdot_v, arm.twist, arm.pos,
            z6, z3, z6, z3, z6, params, self._work.copy(), self._integral.copy(),
            np.zeros(1, dtype=K.STEP_RECORD), 1,
        )  # fmt: skip

    # counters the kernel keeps in its workspace
    @property
    def lambda_floor_steps(self) -> int:
        return int(self._work["floor_steps"][0])

    @property
    def lambda_max_condition(self) -> float:
        return float(self._work["max_cond"][0])

    @property
    def singularity_steps(self) -> int:
        """Steps with w < omega_th (singularity avoidance active)."""
        return int(self._work["singular_steps"][0])

    @property
    def _fast_steps(self) -> int:
        """Steps where both closed forms met every row."""
        return int(self._work["fast_steps"][0])

    def _init_constraints(self, context: ControlContext, dt_p: float, eps_abs: float) -> None:
        """Constant parts of the 21 constraint rows, and the two QP levels.

        T maps [q̈, q, v, 1] to the rows minus their mid values:
        rows of T      velocity (7)   position (7)       torque (7)
        q̈ (7)          dt_p I         ½dt_p² I           M          (M refreshed each step)
        q (7)          0              I                  0
        v (7)          I              dt_p I             0
        1 (1)          0              −q_mid             ĥ          (ĥ refreshed each step)
        """
        n, arm = self.n, self.arm
        self.dt_p = dt_p
        self.eps_abs = float(eps_abs)
        v_max = vector_setting(context.velocity_limits, n, "robot.velocity_limits")
        tau_max = vector_setting(context.torque_limits, n, "robot.max_torque")
        q_min = np.clip(np.asarray(arm.q_lower, dtype=float), -BIG, BIG)
        q_max = np.clip(np.asarray(arm.q_upper, dtype=float), -BIG, BIG)
        self.v_max, self.tau_max, self.q_min, self.q_max = v_max, tau_max, q_min, q_max
        # the torque rows keep 2·eps_abs inside the clip: the solver's tolerance (and level 2's
        # eps_abs margin) then never lets the command reach the clip the motors apply
        margin = torque_margin_problem(tau_max.tolist(), self.eps_abs)
        if margin:
            raise ValueError(margin)
        half = np.concatenate([v_max, 0.5 * (q_max - q_min), tau_max - 2.0 * self.eps_abs])
        self._tau_bound = tau_max - 2.0 * self.eps_abs
        self._half = half
        self._bounds = np.vstack([-half, half])
        eye = np.eye(n)
        T = self._view("T")
        T[:n, :n], T[:n, n : 2 * n] = dt_p * eye, 0.5 * dt_p**2 * eye
        T[n : 2 * n, n : 2 * n] = eye
        T[2 * n : 3 * n, :n], T[2 * n : 3 * n, n : 2 * n] = eye, dt_p * eye
        T[3 * n, n : 2 * n] = -0.5 * (q_min + q_max)
        self._T = T
        self._T_M = T[:n, 2 * n :]  # M (symmetric: Mᵀ = M)
        self._T_state = T[n:]  # [q, v, 1] → offsets o
        self._hhat = T[3 * n, 2 * n :]  # ĥ = h + friction feed-forward (a view)
        self._Y = self._view("Y")  # rows [q̈, q, v, 1]: level-1 and final candidates
        self._Y[:, 3 * n] = 1.0
        self._X = self._Y[:, :n]
        self._Y_q, self._Y_v = self._Y[:, n : 2 * n], self._Y[:, 2 * n : 3 * n]
        self._to_qdd = np.concatenate(
            [np.full(n, 1.0 / dt_p), np.full(n, 2.0 / dt_p**2), np.ones(n)]
        )  # row scales: state units → q̈ units
        self.level1 = QPLevel(n, 3 * n, eps_abs, "level1")
        # Level 2's rows [N; N; M N] have rank n − 6 (1 for a 7-joint arm): with ProxQP's
        # defaults (mu_in 0.1, eps_primal_inf 1e-4) and a start at a_null it declares some
        # feasible instances infeasible; a start at a = 0 (feasible by construction, with an
        # eps_abs margin), mu_in = 1e-2 and an infeasibility threshold below that margin do not.
        self.level2 = QPLevel(n, 3 * n, eps_abs, "level2", mu_in=1e-2, eps_primal_inf=0.01 * eps_abs)
        self._a_zero = np.zeros(n)
        self.level1.C[: 2 * n] = np.vstack([eye, eye])
        self.level2.H[:] = eye

    # ------------------------------------------------------------------ per step
    def compute(self, t: float, state: ArmModel, ref: Reference, wrench: np.ndarray) -> np.ndarray:
        """One call of the compiled step (control/hqp/kernel.py) and, when a row binds, the
        constrained path in Python; the module doc gives the law."""
        arm = state
        w_ext = wrench if self.observer is None else self.observer.update(state, wrench)
        rot_err = pin.log3(ref.rot.dot(arm.rot_T))  # log3(R_d Rᵀ) = −log3(R R_dᵀ)
        k = self.steps
        J, M, Minv = arm.J, arm.M, arm.Minv
        status = K.hqp_step(
            J, M, Minv, arm.h, arm.q, arm.v, arm.Jdot_v, arm.twist, arm.pos,
            ref.twist, ref.pos, ref.accel, rot_err, w_ext, self._params, self._work, self._integral, self._rec, k,
        )  # fmt: skip
        if status == K.MODAL:  # Eq. 29's D_r is not positive definite: damp each mode critically
            self.modal_damping_steps += 1
            V = self._V
            self._D[:] = modal_damping(self._lam_sqrt, (V * self._root).dot(V.T), self.K0)
            status = K.hqp_back(
                J, M, Minv, arm.h, arm.q, arm.v, arm.Jdot_v, arm.twist, arm.pos,
                ref.twist, ref.pos, ref.accel, rot_err, self._params, self._work, self._integral, self._rec, k,
            )  # fmt: skip
        if status == K.FAST:
            tau = self._tau_fast.copy()  # M(q̈ + N a) + ĥ
        elif status == K.NOT_FINITE:  # q or v not finite: so is τ, and the loop stops the run
            tau = np.full(self.n, np.nan)  # as diverged ("the controller returned a non-finite torque")
        else:
            tau = self._solve_levels(
                J, M, Minv, self._JMinv, self._lam, self._b, self._a_null, status == K.SLOW_OK1
            )
        if self.observer is not None:
            self.observer.command(tau)
        self.steps = k + 1
        return tau

    def _solve_levels(self, J, M, Minv, JMinv, lam, b, a_null, ok1: bool) -> np.ndarray:
        """The constrained path: the QP of each level whose closed form violates a row."""
        n, L1, L2, X = self.n, self.level1, self.level2, self._X
        # bounds in q̈ units: [I; I; M] q̈ ∈ (±half − o) ⊙ row scales, o = [q, v, 1]·T_state
        np.subtract(self._bounds, self._Y[0, n:].dot(self._T_state), out=L1.lu)
        L1.lu *= self._to_qdd
        if ok1 and not self.solve_every_step:
            L1.closed_form += 1
            qdd = X[0]
        else:
            np.dot(J.T, J, out=L1.H)
            if self._inertia_metric:
                L1.H += REGULARISER * M
            else:
                L1.H.flat[:: n + 1] += REGULARISER
            np.negative(b.dot(J), out=L1.g)
            L1.C[2 * n :] = M
            if not self._box_feasible(L1.lu) or not L1.solve(X[0]):
                self.level1_fallbacks += 1
                self.level2_zero_steps += 1
                return M.dot(X[0]) + self._hhat  # unconstrained least squares, no level 2
            qdd = L1.x
            if not self.solve_every_step:  # q̈* + N a_null may satisfy every row: done
                X[1] = qdd + self._Na
                Z = self._Y[1].dot(self._T)
                if (np.abs(Z) <= self._half).all():
                    L2.closed_form += 1
                    return Z[2 * n :]
        # level 2: [I; I; M](q̈* + N a) within the same bounds, N = I − M⁻¹JᵀΛJ
        JtLJ = J.T.dot(lam.dot(J))
        N = L2.C[:n]
        np.subtract(np.eye(n), Minv.dot(JtLJ), out=N)
        L2.C[n : 2 * n] = N
        np.subtract(M, JtLJ, out=L2.C[2 * n :])
        rows = qdd.dot(self._T[:n]) * self._to_qdd  # [I; I; M] q̈*
        np.subtract(L1.lu, rows, out=L2.lu)
        # a = 0 stays strictly feasible: level 2 is not asked to repair level 1's residual
        # (≤ eps_abs), and rows active at level 1 keep a margin of eps_abs (with a zero-width
        # side, the rank-deficient rows make ProxQP report false infeasibility)
        np.minimum(L2.l, -self.eps_abs, out=L2.l)
        np.maximum(L2.u, self.eps_abs, out=L2.u)
        np.negative(a_null, out=L2.g)
        tau = M.dot(qdd)
        if L2.solve(self._a_zero, update_H=False):
            tau += L2.C[2 * n :].dot(L2.x)
        else:
            self.level2_zero_steps += 1
        tau += self._hhat
        # a solved QP meets its torque rows to eps_abs; keep the last 1e-5 N·m inside too
        return np.clip(tau, -self._tau_bound, self._tau_bound, out=tau)

    def _box_feasible(self, lu: np.ndarray) -> bool:
        """Whether the velocity and position rows of each joint (both bounds on q̈_i) overlap;
        if not, level 1 is infeasible without asking ProxQP (counted as a failure)."""
        n = self.n
        if (np.maximum(lu[0, :n], lu[0, n : 2 * n]) <= np.minimum(lu[1, :n], lu[1, n : 2 * n])).all():
            return True
        self.level1.failures += 1
        self.level1.infeasible_box += 1
        return False

    # ------------------------------------------------------------------ after the run
    def diagnostics(self) -> dict:
        out = {
            "lambda_fallback_steps": self.lambda_floor_steps,
            "lambda_max_condition": float(self.lambda_max_condition),
            "hqp_modal_damping_steps": self.modal_damping_steps,
            "hqp_level1_fallbacks": self.level1_fallbacks,
            "hqp_level2_zero_steps": self.level2_zero_steps,
            "hqp_singularity_steps": self.singularity_steps,
            "hqp_force_source": self.force_source.value,
            **self.integral_diagnostics(),
        }
        out.update(self.level1.diagnostics(self._fast_steps))
        out.update(self.level2.diagnostics(self._fast_steps))
        if self.observer is not None:
            out.update(self.observer.errors())
        return out

    def timeseries(self) -> dict[str, np.ndarray]:
        rec = self._rec[: self.steps]
        out = {
            "hqp_F": rec["F"].copy(),
            "hqp_K_r": rec["s"][:, None] * self.K0,  # columns hqp_K_r_1 … hqp_K_r_6
            "hqp_preload": rec["preload"].copy(),
            "hqp_manipulability": rec["w"].copy(),
        }
        if self.observer is not None:
            out.update(self.observer.timeseries())
        return out
