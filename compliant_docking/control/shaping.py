"""The apparent-inertia floor of the impedance laws (docs/controllers/impedance.md): a
deviation from docs/control_laws.md §1 and §3, option ``apparent_inertia_floor``."""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack


class ApparentInertiaFloor:
    """Keeps the commanded apparent inertia W at least ``ratio``·Λ in every direction.

    Why: with exact force feedback an impedance law commands the task force
    Λ·W⁻¹(K e + D ė + w) − w, so the measured wrench w, one step old, returns through
    (Λ W⁻¹ − I). A held (stiff) contact answers a commanded force within the step, so the
    contact wrench obeys w_k ≈ −d·(Λ W⁻¹ − I)·w_(k−1) + … (d ≈ 0.95-0.99, MuJoCo's contact
    impedance): wherever the arm's task inertia Λ exceeds about twice W, the wrench flips
    sign and grows every step and the contact makes and breaks at hundreds of hertz.

    With S = W^-½ Λ W^-½ = V diag(σ) Vᵀ, the floor uses W_eff = W^½ V diag(max(1, σ·ratio)) Vᵀ W^½
    instead of W: Λ W_eff⁻¹ has eigenvalues min(σ, 1/ratio), so the delayed-feedback gain
    Λ W_eff⁻¹ − I stays within [−1, 1/ratio − 1]; K and D are unchanged (a push F still
    settles at F/k), only the apparent inertia of the directions where σ > 1/ratio grows.
    The controller hands :meth:`apply` the vector W⁻¹u (u: the impedance wrench) and gets
    W_eff⁻¹u back, i.e. P·W⁻¹u with P = W_eff⁻¹W = W^-½ V diag(min(1, 1/(ratio·σ))) Vᵀ W^½.
    P is refreshed every ``every`` steps (Λ follows the posture, slowly: at 1 kHz ten steps
    are 10 ms, as for TaskInertia's conditioning check): one 6×6 Cholesky of
    W^½Λ⁻¹W^½ − ratio·I tells whether W ⪰ ratio·Λ already (then P = I and the vector is
    returned untouched, so the law is exactly the specified one), else one LAPACK
    ``dsyevd`` gives V and σ. Between refreshes a step costs at most one 6×6 product.
    ``ratio`` > 0: the range of ``controller.apparent_inertia_floor``, which the
    controllers check.
    """

    def __init__(self, W_diag, ratio: float, every: int = 10):
        W = np.asarray(W_diag, dtype=float)
        self.ratio = float(ratio)
        self.every = int(every)
        self._w_sqrt = np.sqrt(W)
        self._w_isqrt = 1.0 / self._w_sqrt
        self._scale = np.outer(self._w_sqrt, self._w_sqrt)
        self._shift = self.ratio * np.eye(len(W))
        self.P: np.ndarray | None = None  # W_eff⁻¹W, None while the floor is inactive
        # [P, I] (6×12), refreshed with P: P·d + y in one product, [P, I]·[d; y]
        self.P_and_I = np.hstack([np.zeros((len(W), len(W))), np.eye(len(W))])
        self._step = 0
        self.active_steps = 0
        self.max_ratio = 0.0  # largest σ = eig(W^-½ Λ W^-½) seen while active

    def refresh(self, lam_inv: np.ndarray) -> None:
        """Recompute P for Λ⁻¹ = ``lam_inv`` (None when W ⪰ ratio·Λ already)."""
        T = lam_inv * self._scale  # W^½ Λ⁻¹ W^½ = S⁻¹, eigenvalues 1/σ
        if lapack.dpotrf(T - self._shift)[1] == 0:  # every 1/σ > ratio: nothing to do
            self.P = None
            return
        mu, V, info = lapack.dsyevd(T)
        if info != 0 or mu[0] <= 0.0:
            self.P = None
            return
        self.max_ratio = max(self.max_ratio, 1.0 / mu[0])
        c = np.minimum(mu * (1.0 / self.ratio), 1.0)  # min(1, (1/ratio)/σ)
        self.P = (self._w_isqrt[:, None] * V * c).dot(V.T * self._w_sqrt)
        self.P_and_I[:, : len(c)] = self.P

    def due(self) -> bool:
        """Whether this step refreshes P (every ``every`` steps)."""
        return self._step % self.every == 0

    def refreshed_elsewhere(self, active: bool, max_ratio: float) -> None:
        """Take the result of a refresh computed elsewhere (se3_lie's compiled step), which
        wrote P into ``P_and_I``'s left block: P is that block, or None when inactive."""
        self.P = self.P_and_I[:, : len(self._w_sqrt)].copy() if active else None
        self.max_ratio = max_ratio

    def count_step(self) -> None:
        """The step's bookkeeping, once its P is current."""
        self._step += 1
        if self.P is not None:
            self.active_steps += 1

    def current(self, J: np.ndarray, JMinv: np.ndarray) -> np.ndarray | None:
        """This step's P = W_eff⁻¹W given its J and J M⁻¹, or None while the floor is inactive
        (the caller then leaves its W⁻¹u untouched, bit for bit)."""
        if self.due():
            self.refresh(JMinv.dot(J.T))
        self.count_step()
        return self.P

    def apply(self, J: np.ndarray, JMinv: np.ndarray, x: np.ndarray) -> np.ndarray:
        """W_eff⁻¹W x (x itself while the floor is inactive)."""
        P = self.current(J, JMinv)
        return x if P is None else P.dot(x)

    def diagnostics(self) -> dict:
        return {
            "inertia_floor_active_steps": self.active_steps,
            "inertia_floor_max_ratio": float(self.max_ratio) if self.active_steps else None,
        }


def inertia_floor(W_diag, ratio: float | None, use_force_feedback: bool) -> ApparentInertiaFloor | None:
    """The floor a controller uses: None when ``ratio`` is None (the specified law) or without
    force feedback (no delayed-feedback loop to keep stable, the law stays the spec's)."""
    if ratio is None or not use_force_feedback:
        return None
    return ApparentInertiaFloor(W_diag, ratio)
