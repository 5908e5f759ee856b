"""The gradient of the manipulability w = √det(J Jᵀ) for a serial chain of revolute joints
(HQP-AC's singularity avoidance, Eq. 38-42), in closed form from J alone."""

from __future__ import annotations

import numpy as np

_LEVI_CIVITA = np.zeros((3, 3, 3))
_LEVI_CIVITA[0, 1, 2] = _LEVI_CIVITA[1, 2, 0] = _LEVI_CIVITA[2, 0, 1] = 1.0
_LEVI_CIVITA[0, 2, 1] = _LEVI_CIVITA[2, 1, 0] = _LEVI_CIVITA[1, 0, 2] = -1.0


def _cross_map() -> np.ndarray:
    """The 6×36 map from vec(J_r G_c) (rows r of J, c of G, per column) to [b; a] with
    b = Gv × ω and a = v × Gv + ω × Gω: (x × y)_k = Σ_ab ε_kab x_a y_b."""
    out = np.zeros((6, 6, 6))  # [k, r, c]
    for k in range(3):
        for a in range(3):
            for b in range(3):
                eps = _LEVI_CIVITA[k, a, b]
                out[k, 3 + b, a] += eps  # b_k = Σ ε_kab Gv_a ω_b
                out[3 + k, a, b] += eps  # (v × Gv)_k
                out[3 + k, 3 + a, 3 + b] += eps  # (ω × Gω)_k
    return out.reshape(6, 36)


_CROSS_MAP = _cross_map()
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


_ONES6 = np.ones(6)


class ManipulabilityGradient:
    """∇w/w for an n-joint serial chain of revolute joints, with buffers for n reused
    across calls (the hot loop calls it every step the arm is near a singularity).

    With J = [v; ω] at the point p and G = (J Jᵀ)⁻¹ J, ∂w/∂q_i = w·⟨G, ∂J/∂q_i⟩ and, for
    columns j, ∂J_j/∂q_i = [ω_i × v_j; ω_i × ω_j] if i < j and [ω_j × v_i; 0] if i ≥ j, so
    with a_j = v_j × Gv_j + ω_j × Gω_j and b_j = Gv_j × ω_j

        ∂w/∂q_i = w (Σ_{j≤i} v_i·b_j + Σ_{j>i} ω_i·a_j).

    Evaluated as: the 36 products J_rj G_cj (one broadcast product), [b; a] from them (one
    product with the Levi-Civita map), the partial sums over j (two products with constant
    triangular matrices) and the column-wise dot with J (one product and one sum): six
    numpy calls per gradient.
    """

    def __init__(self, n: int):
        self.n = n
        self._outer = np.empty((6, 6, n))
        self._outer_flat = self._outer.reshape(36, n)
        self._sums = np.empty((6, n))
        self._sums_b, self._sums_a = self._sums[:3], self._sums[3:]
        self._through = np.ascontiguousarray(np.tril(np.ones((n, n))).T)  # [j, i] = 1 for j ≤ i
        self._after = np.ascontiguousarray(np.triu(np.ones((n, n)), 1).T)  # [j, i] = 1 for j > i

    def __call__(self, J: np.ndarray, G: np.ndarray) -> np.ndarray:
        """∇w/w (a fresh array) for J (6×n) and G = (J Jᵀ)⁻¹ J."""
        np.multiply(J[:, None, :], G[None, :, :], out=self._outer)
        ba = _CROSS_MAP.dot(self._outer_flat)  # [b; a], 6×n
        ba[:3].dot(self._through, out=self._sums_b)  # Σ_{j≤i} b_j
        ba[3:].dot(self._after, out=self._sums_a)  # Σ_{j>i} a_j
        sums = self._sums
        np.multiply(sums, J, out=sums)
        return _ONES6.dot(sums)


_GRADIENTS: dict[int, ManipulabilityGradient] = {}


def manipulability_gradient(J: np.ndarray, G: np.ndarray, w: float) -> np.ndarray:
    """∇w of w = √det(J Jᵀ) for a serial chain of revolute joints, J = [v; ω] at a point p,
    G = (J Jᵀ)⁻¹ J (see :class:`ManipulabilityGradient`)."""
    n = J.shape[1]
    if n not in _GRADIENTS:
        _GRADIENTS[n] = ManipulabilityGradient(n)
    return w * _GRADIENTS[n](J, G)
