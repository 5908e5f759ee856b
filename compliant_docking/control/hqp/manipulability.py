"""The gradient of the manipulability w = √det(J Jᵀ) for a serial chain of revolute joints
(HQP-AC's singularity avoidance, Eq. 38-42), in closed form from J alone."""

from __future__ import annotations

import numpy as np

from compliant_docking.control.hqp.kernel import gradient_over_w

_REVOLUTE = {"JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned"}


def check_revolute_chain(model) -> None:
    """Raise ValueError unless the Pinocchio ``model`` is a chain of revolute joints (the
    gradient's premise)."""
    kinds = {j.shortname() for j in model.joints[1:]}
    if not kinds <= _REVOLUTE or model.nq != model.nv:
        raise ValueError(
            f"controller=hqp needs a serial arm of revolute joints "
            f"(manipulability gradient); got joints {sorted(kinds)}"
        )


class ManipulabilityGradient:
    """∇w/w for an n-joint serial chain of revolute joints.

    With J = [v; ω] at the point p and G = (J Jᵀ)⁻¹ J, ∂w/∂q_i = w·⟨G, ∂J/∂q_i⟩ and, for
    columns j, ∂J_j/∂q_i = [ω_i × v_j; ω_i × ω_j] if i < j and [ω_j × v_i; 0] if i ≥ j, so
    with a_j = v_j × Gv_j + ω_j × Gω_j and b_j = Gv_j × ω_j

        ∂w/∂q_i = w (Σ_{j≤i} v_i·b_j + Σ_{j>i} ω_i·a_j).

    Evaluated by the compiled :func:`~compliant_docking.control.hqp.kernel.gradient_over_w`
    (which HQP's step kernel calls directly): two passes over the columns with running sums.
    """

    def __init__(self, n: int):
        self.n = n

    def __call__(self, J: np.ndarray, G: np.ndarray) -> np.ndarray:
        """∇w/w (a fresh array) for J (6×n) and G = (J Jᵀ)⁻¹ J."""
        out = np.empty(self.n)
        gradient_over_w(np.asarray(J, dtype=float), np.asarray(G, dtype=float), out)
        return out


_GRADIENTS: dict[int, ManipulabilityGradient] = {}


def manipulability_gradient(J: np.ndarray, G: np.ndarray, w: float) -> np.ndarray:
    """∇w of w = √det(J Jᵀ) for a serial chain of revolute joints, J = [v; ω] at a point p,
    G = (J Jᵀ)⁻¹ J (see :class:`ManipulabilityGradient`)."""
    n = J.shape[1]
    if n not in _GRADIENTS:
        _GRADIENTS[n] = ManipulabilityGradient(n)
    return w * _GRADIENTS[n](J, G)
