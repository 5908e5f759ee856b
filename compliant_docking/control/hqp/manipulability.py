"""The gradient of the manipulability w = √det(J Jᵀ) for a serial chain of revolute joints
(HQP-AC's singularity avoidance, Eq. 38-42), in closed form from J alone."""

from __future__ import annotations

import numpy as np

_LEVI_CIVITA = np.zeros((3, 3, 3))
_LEVI_CIVITA[0, 1, 2] = _LEVI_CIVITA[1, 2, 0] = _LEVI_CIVITA[2, 0, 1] = 1.0
_LEVI_CIVITA[0, 2, 1] = _LEVI_CIVITA[2, 1, 0] = _LEVI_CIVITA[1, 0, 2] = -1.0
_EPS9 = _LEVI_CIVITA.reshape(3, 9)  # (x × y)_k = Σ_ab ε_kab x_a y_b, on vec(x yᵀ)
#: [ω × Gv; v × Gv + ω × Gω] from the stacked outer products [v Gvᵀ; ω Gωᵀ; ω Gvᵀ]
_CROSS_MAP = np.zeros((6, 27))
_CROSS_MAP[:3, 18:] = _EPS9
_CROSS_MAP[3:, :9] = _EPS9
_CROSS_MAP[3:, 9:18] = _EPS9


def manipulability_gradient(J: np.ndarray, G: np.ndarray, w: float) -> np.ndarray:
    """∇w of w = √det(J Jᵀ) for a serial chain of revolute joints, J = [v; ω] at a point p.

    G = (J Jᵀ)⁻¹ J. ∂w/∂q_i = w·⟨G, ∂J/∂q_i⟩ with, for columns j,
    ∂J_j/∂q_i = [ω_i × v_j; ω_i × ω_j] if i < j and [ω_j × v_i; 0] if i ≥ j, so with
    a_j = v_j × Gv_j + ω_j × Gω_j and b_j = Gv_j × ω_j

        ∂w/∂q_i = w (Σ_{j>i} ω_i·a_j + Σ_{j≤i} v_i·b_j)
                = w (Σ_{j>i} (ω_i·a_j − v_i·b_j) + v_i·Σ_j b_j).

    The cross products come column by column from one product with the Levi-Civita symbol.
    """
    n = J.shape[1]
    Jr, Gr = J.reshape(2, 3, n), G.reshape(2, 3, n)  # [v, ω] and [Gv, Gω]
    outer = np.empty((27, n))
    np.multiply(Jr[:, :, None, :], Gr[:, None, :, :], out=outer[:18].reshape(2, 3, 3, n))
    np.multiply(Jr[1][:, None, :], Gr[0][None, :, :], out=outer[18:].reshape(3, 3, n))
    C = _CROSS_MAP.dot(outer)  # [−b; a]
    pairs = J.T.dot(C)  # [i, j] = ω_i·a_j − v_i·b_j
    return w * ((pairs * _upper(n)).sum(axis=1) - Jr[0].T.dot(C[:3].sum(axis=1)))


_UPPER: dict[int, np.ndarray] = {}


def _upper(n: int) -> np.ndarray:
    """The mask U[i, j] = 1 for j > i (sums over the joints after i)."""
    if n not in _UPPER:
        _UPPER[n] = np.triu(np.ones((n, n)), 1)
    return _UPPER[n]
