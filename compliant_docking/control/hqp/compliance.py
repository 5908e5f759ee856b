"""HQP-AC's compliance law: contact magnitude, adaptive stiffness (Eq. 26-27), the damping
designs (Eq. 29 and the modal fallback) and the preload ramp (docs/control_laws.md §2)."""

from __future__ import annotations

import math

import numpy as np

# compiled (the step kernel calls them), defined next to it: see kernel.py
from compliant_docking.control.hqp.kernel import PRELOAD_CONTACT_N as PRELOAD_CONTACT_N
from compliant_docking.control.hqp.kernel import PRELOAD_RELEASE_N as PRELOAD_RELEASE_N
from compliant_docking.control.hqp.kernel import preload_step
from compliant_docking.control.hqp.kernel import stiffness_scale as stiffness_scale


def contact_magnitude(wrench: np.ndarray, deadband: float) -> float:
    """F = max(‖[f; m]‖ − deadband, 0) [N] (the norm mixes N and N·m, as in the paper)."""
    return max(math.sqrt(float(wrench.dot(wrench))) - deadband, 0.0)


def adaptive_stiffness(F: float, K0: np.ndarray, K_min_ratio: float, k_alpha: float) -> np.ndarray:
    """K_r = clip((1 − α)·K0, K_min_ratio·K0, K0) element-wise (Eq. 26-27)."""
    alpha = 1.0 / (1.0 + math.exp(-k_alpha * F)) if k_alpha * F > -700.0 else 0.0
    K0 = np.asarray(K0, dtype=float)
    return np.clip((1.0 - alpha) * K0, K_min_ratio * K0, K0)


def sym_sqrt(A: np.ndarray) -> np.ndarray:
    """The symmetric positive square root of a symmetric positive definite matrix."""
    eigval, eigvec = np.linalg.eigh(A)
    return (eigvec * np.sqrt(np.maximum(eigval, 0.0))).dot(eigvec.T)


def factorization_damping(
    lam_sqrt: np.ndarray, k_sqrt: np.ndarray, out: np.ndarray | None = None
) -> np.ndarray:
    """D = Λ^½ K^½ + K^½ Λ^½ for a diagonal K = diag(k_sqrt²) (Eq. 29).

    Symmetric always; positive definite when Λ and K commute (then D = 2Λ^½K^½), but not
    in general: the symmetrised product of two SPD matrices can be indefinite when Λ is
    ill-conditioned and K anisotropic.
    """
    X = lam_sqrt * k_sqrt  # Λ^½ K^½ (columns scaled)
    return np.add(X, X.T, out=out)


def modal_damping(lam_sqrt: np.ndarray, lam_inv_sqrt: np.ndarray, K: np.ndarray) -> np.ndarray:
    """D = 2 Λ^½ (Λ^-½ K Λ^-½)^½ Λ^½: critical damping of every mode of Λ ë + D ė + K e = 0.

    With y = Λ^½ e the system becomes ÿ + D̃ ẏ + K̃ y = 0, K̃ = Λ^-½ K Λ^-½, and D̃ = 2K̃^½
    damps each eigenmode critically. Always symmetric positive definite; equal to
    :func:`factorization_damping` when Λ and K commute.
    """
    K_tilde = (
        lam_inv_sqrt.dot(np.asarray(K, dtype=float)[:, None] * lam_inv_sqrt)
        if np.ndim(K) == 1
        else lam_inv_sqrt.dot(K).dot(lam_inv_sqrt)
    )
    return 2.0 * lam_sqrt.dot(sym_sqrt(0.5 * (K_tilde + K_tilde.T))).dot(lam_sqrt)


def damping_matrix(Lambda: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, bool]:
    """D_r for a task inertia Λ (SPD) and a diagonal stiffness K (vector): the factorization
    design of Eq. 29, or the modal design where that one is not positive definite.

    Returns (D, modal_used). The controller does the same from its own eigendecomposition.
    """
    eigval, eigvec = np.linalg.eigh(Lambda)
    lam_sqrt = (eigvec * np.sqrt(eigval)).dot(eigvec.T)
    D = factorization_damping(lam_sqrt, np.sqrt(np.asarray(K, dtype=float)))
    if np.linalg.eigvalsh(D)[0] > 0.0:
        return D, False
    lam_inv_sqrt = (eigvec / np.sqrt(eigval)).dot(eigvec.T)
    return modal_damping(lam_sqrt, lam_inv_sqrt, K), True


class PreloadRamp:
    """Preload magnitude p(t) ∈ [0, target] [N].

    Ramps up at rate = target/ramp_s while in contact and back down at the same rate out
    of contact. In contact from the step the contact magnitude exceeds PRELOAD_CONTACT_N
    (1 N) until it falls below PRELOAD_RELEASE_N (0.5 N): without this hysteresis a press
    settling under 1 N (0.63 N in the default docking scene) would never hold a preload.
    ``target`` ≥ 0 and ``ramp_s`` > 0: the ranges of ``controller.preload_force`` and
    ``controller.preload_ramp_s``, which the controller checks (``config.ranges.require``).
    """

    def __init__(self, target: float, ramp_s: float, dt: float):
        self.target = float(target)
        self.step = self.target / float(ramp_s) * float(dt)
        # [value, in contact (0/1), step, target]: the state compiled code updates in place
        # (the HQP step kernel works on a copy of it in its workspace)
        self.state = np.array([0.0, 0.0, self.step, self.target])

    @property
    def value(self) -> float:
        return float(self.state[0])

    @property
    def in_contact(self) -> bool:
        return bool(self.state[1])

    def update(self, F: float) -> float:
        return float(preload_step(self.state, float(F)))
