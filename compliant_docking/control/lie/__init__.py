r"""Lie-group maths on SO(3) and SE(3) for the SE(3) impedance controller.

Conventions (fixed; the controllers depend on them)
---------------------------------------------------
* Twists and wrenches are 6-vectors with the LINEAR part first:
  ``xi = [v; w]`` (v linear, w angular), ``F = [f; m]``.
* ``hat6(xi) = [[hat3(w), v], [0, 0]]``, ``exp6(xi) = expm(hat6(xi))`` and ``log6``
  is its inverse for rotation angles below pi; ``Ad_T = [[R, hat3(p) R], [0, R]]``,
  ``ad(xi) = [[hat3(w), hat3(v)], [0, hat3(w)]]``. These general helpers are
  Pinocchio's (same conventions: ``pin.exp6``, ``pin.log6``, ``pin.SE3.action``,
  ``pin.Motion.action``, …; see :mod:`.se3`); this package keeps what no library has
  or what measures better: dexp with its inverse and analytic time derivative
  (1e-16 against Pinocchio's 1e-7 at docking-size angles), the scalar coefficient
  kernels and the log3 kernel the controller calls on Python floats.
* ``dexp(lam)`` is the RIGHT-trivialised differential of exp (the "left Jacobian"
  J_l of SE(3)):  d/dt Exp(lam(t)) = hat6(dexp(lam) lam_dot) Exp(lam), i.e.
  ``dexp(lam) = sum_k ad(lam)^k / (k+1)!``.  ``dexp_inv`` is its inverse and
  ``dexp_dot(lam, lam_dot)`` is d/dt dexp(lam(t)) (analytic).

Closed forms used
-----------------
With theta = |w|, x = theta^2 and the scalar functions

    a = sin(theta)/theta,  b = (1 - cos theta)/theta^2,  c = (theta - sin theta)/theta^3,

the SO(3) quantities are

    J(w)     = I + b hat3(w) + c hat3(w)^2      = a I + hat3(b w) + c w w^T
    J(w)^-1  = I - hat3(w)/2 + e hat3(w)^2      = g I - hat3(w)/2 + e w w^T

with g = (theta/2) cot(theta/2) and e = (1 - g)/theta^2.  For a scalar function f(theta)

Modules: :mod:`.series` (scalar coefficient kernels, Taylor switches), :mod:`.so3` (log3
kernel, SO(3) Jacobians), :mod:`.se3` (the π domain check), :mod:`.dexp`. The names below are the package's public API.
"""

from compliant_docking.control.lie.dexp import dexp, dexp_all, dexp_dot, dexp_inv
from compliant_docking.control.lie.se3 import check_rotation_domain
from compliant_docking.control.lie.series import (
                                               PI_MARGIN,
                                               TAYLOR_THETA_0,
                                               TAYLOR_THETA_1,
                                               TAYLOR_THETA_2,
                                               coef0,
                                               coef1,
                                               coef2,
                                               coefficients,
                                               inv_coefficients,
                                               trig_terms,
)
from compliant_docking.control.lie.so3 import (
                                               log3_list,
                                               so3_left_jacobian,
                                               so3_left_jacobian_inv,
)

__all__ = [
    "TAYLOR_THETA_0",
    "TAYLOR_THETA_1",
    "TAYLOR_THETA_2",
    "PI_MARGIN",
    "so3_left_jacobian",
    "so3_left_jacobian_inv",
    "check_rotation_domain",
    "dexp",
    "dexp_inv",
    "dexp_dot",
    "dexp_all",
    "trig_terms",
    "coef0",
    "coef1",
    "coef2",
    "coefficients",
    "inv_coefficients",
    "log3_list",
]
