"""SE(3): the domain of the exponential coordinates of the impedance's pose error.

The general SE(3) helpers are Pinocchio's (measured 3-100× faster per call and as
accurate; docs/controllers/se3_lie.md): with twists and wrenches ``[linear; angular]``
as here, exp6 = ``pin.exp6(xi)`` (``.homogeneous`` for the 4×4), log6 = ``pin.log6(T).vector``,
Ad_T = ``pin.SE3(T).action``, Ad_T⁻¹ = ``.actionInverse``, Ad_T⁻ᵀ = ``.dualAction``,
ad(xi) = ``pin.Motion(xi).action``, T⁻¹ = ``.inverse()``, T⁻¹T_d = ``T.actInv(T_d)``.
"""

from __future__ import annotations

import math

from compliant_docking.control.lie.series import PI_MARGIN, floats

_sqrt = math.sqrt
_PI = math.pi


def check_rotation_domain(lam, margin=PI_MARGIN):
    """Raise ValueError unless the rotation part of ``lam`` = [v; w] has |w| < pi - margin.

    The exponential coordinates of the pose error used by the SE(3) impedance are only
    unique (and the impedance only defined) for |lam_rot| < pi.
    """
    w = floats(lam, 6)[3:]
    t = _sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    raise_if_near_pi(t, margin)


def raise_if_near_pi(t, margin):
    if not t < _PI - margin:  # also catches NaN
        raise ValueError(
            f"orientation error |λ_rot| = {t:.9g} rad ({math.degrees(t):.7g} deg) is not below "
            f"π - {margin:g}: the SE(3) impedance requires |λ_rot| < π "
            f"(the pose-error logarithm is not unique at π)"
        )
