"""One level of the hierarchical QP: a dense ProxQP problem built once and updated in place."""

from __future__ import annotations

import time

import numpy as np
from proxsuite import proxqp

_SOLVED = proxqp.QPSolverOutput.PROXQP_SOLVED

#: ProxQP outer and inner iteration caps per solve: a warm-started feasible problem needs
#: about ten; an infeasible one (ProxQP rarely detects it) would otherwise run for seconds
MAX_ITER = 100
MAX_ITER_IN = 100
#: stand-in for an infinite bound (ProxQP wants finite numbers)


class QPLevel:
    """A dense ProxQP problem min ½xᵀHx + gᵀx s.t. l ≤ Cx ≤ u, built at its first solve and
    updated in place afterwards; the owner writes H, g, C and the bounds ``lu`` = [l; u]
    (a 2×m buffer) before calling :meth:`solve`.

    Solves are warm-started at a given x with the previous multipliers. Counts failures
    (any status but solved, or a non-finite result) and times every update + solve.
    ``eps_abs`` > 0: the range of ``controller.eps_abs``, which the controller checks.
    """

    def __init__(
        self,
        n: int,
        n_in: int,
        eps_abs: float,
        name: str,
        mu_in: float | None = None,
        eps_primal_inf: float | None = None,
    ):
        self.name = name
        qp = proxqp.dense.QP(n, 0, n_in)
        qp.settings.eps_abs = float(eps_abs)
        qp.settings.eps_rel = 0.0
        qp.settings.max_iter = MAX_ITER
        qp.settings.max_iter_in = MAX_ITER_IN
        qp.settings.verbose = False
        self.mu_in = None if mu_in is None else float(mu_in)
        if mu_in is not None:
            qp.settings.default_mu_in = self.mu_in
        if eps_primal_inf is not None:
            qp.settings.eps_primal_inf = float(eps_primal_inf)
        # proxsuite 0.8: the initial-guess mode must be set before init() (setting it
        # between init() and the first solve() crashes)
        qp.settings.initial_guess = proxqp.InitialGuess.WARM_START
        self.qp = qp
        self.H = np.zeros((n, n))
        self.g = np.zeros(n)
        self.C = np.zeros((n_in, n))
        self.lu = np.zeros((2, n_in))
        self.l, self.u = self.lu[0], self.lu[1]
        self.x = np.zeros(n)
        self._y = np.zeros(0)
        self._z = np.zeros(n_in)
        self._built = False
        self.solves = 0
        self.failures = 0
        self.iterations = 0
        self.time_total = 0.0
        self.time_max = 0.0
        self.setup_time = 0.0
        self.infeasible_box = 0  # level 1 only: velocity and position rows disjoint
        self.closed_form = 0  # steps whose closed-form optimum met every row (no solve needed)

    def solve(self, x0: np.ndarray, update_H: bool = True) -> bool:
        """Solve with the current buffers from the guess x0; the solution goes to ``x``."""
        qp = self.qp
        start = time.perf_counter()
        if self._built:
            qp.update(
                self.H if update_H else None, self.g, None, None, self.C, self.l, self.u, mu_in=self.mu_in
            )
        else:
            qp.init(self.H, self.g, None, None, self.C, self.l, self.u)
            self._built = True
            self.setup_time = time.perf_counter() - start
        qp.solve(x0, self._y, self._z)
        elapsed = time.perf_counter() - start
        self.solves += 1
        self.time_total += elapsed
        if elapsed > self.time_max:
            self.time_max = elapsed
        results = qp.results
        self.iterations += results.info.iter
        x = results.x
        if results.info.status != _SOLVED or not np.isfinite(x).all():
            self.failures += 1
            self._z[:] = 0.0
            return False
        self.x[:] = x
        self._z[:] = results.z
        return True

    def diagnostics(self, closed_form_elsewhere: int = 0) -> dict:
        p = f"hqp_{self.name}"
        n = self.solves
        return {
            f"{p}_solves": n,
            f"{p}_failures": self.failures,
            f"{p}_closed_form_steps": self.closed_form + closed_form_elsewhere,
            f"{p}_iterations_mean": self.iterations / n if n else None,
            f"{p}_solve_mean_us": self.time_total / n * 1e6 if n else None,
            f"{p}_solve_max_us": self.time_max * 1e6 if n else None,
            f"{p}_setup_us": self.setup_time * 1e6 if n else None,
            f"{p}_infeasible_box": self.infeasible_box,
        }
