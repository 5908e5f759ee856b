"""The apparent-inertia floor of the impedance laws (docs/controllers/impedance.md): a
deviation from docs/control_laws.md §1 and §3, option ``apparent_inertia_floor``."""

from __future__ import annotations

import numpy as np

from compliant_docking.control.jit import kernel
from compliant_docking.control.kernel_blocks import cholesky

#: the floor's state, one record: W^½, W^-½ and ratio (constant), [P, I] (6×12, P refreshed
#: in its left block), whether P is in force, the largest σ seen
FLOOR_STATE = np.dtype(
    [
        ("w_sqrt", "f8", (6,)),
        ("w_isqrt", "f8", (6,)),
        ("ratio", "f8"),
        ("P_and_I", "f8", (6, 12)),
        ("active", "?"),
        ("max_ratio", "f8"),
    ],
    align=True,
)


@kernel
def refresh_floor(lam_inv, floor):
    """Recompute P = W_eff⁻¹W for Λ⁻¹ = ``lam_inv`` into ``floor[0]`` (a :data:`FLOOR_STATE`
    record): ``P_and_I``'s left block and ``active`` (False when W ⪰ ratio·Λ already).

    The one implementation, called by :class:`ApparentInertiaFloor` (the numpy laws) and
    by the compiled SE(3) step (:mod:`~.se3_kernel`). A 6×6 Cholesky of W^½Λ⁻¹W^½ − ratio·I
    tells whether every 1/σ > ratio (nothing to do); else numba's ``np.linalg.eigh``
    (LAPACK ``dsyevd``) gives V and μ = 1/σ of T = W^½Λ⁻¹W^½ and
    P = W^-½ V diag(min(1, μ/ratio)) Vᵀ W^½."""
    f = floor[0]
    w_sqrt, w_isqrt, ratio = f.w_sqrt, f.w_isqrt, f.ratio
    T = np.empty((6, 6))  # W^½ Λ⁻¹ W^½, transposed (its lower triangle holds Λ⁻¹'s upper one)
    U = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            T[j, i] = lam_inv[i, j] * (w_sqrt[i] * w_sqrt[j])
            U[j, i] = T[j, i] - ratio if i == j else T[j, i]
    if cholesky(U, np.empty((6, 6))):  # every 1/σ > ratio: nothing to do
        f.active = False
        return
    if not np.all(np.isfinite(T)):  # (an eigen-solver's failure: P None)
        f.active = False
        return
    mu, V = np.linalg.eigh(T)
    if mu[0] <= 0.0:
        f.active = False
        return
    f.max_ratio = max(f.max_ratio, 1.0 / mu[0])
    inv_ratio = 1.0 / ratio
    c = np.empty(6)
    for m in range(6):
        c[m] = min(mu[m] * inv_ratio, 1.0)  # min(1, (1/ratio)/σ)
    P = f.P_and_I
    for i in range(6):
        for j in range(6):
            s = 0.0
            for m in range(6):
                s += (w_isqrt[i] * V[i, m] * c[m]) * (V[j, m] * w_sqrt[j])
            P[i, j] = s
    f.active = True


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
    are 10 ms, as for TaskInertia's conditioning check) by :func:`refresh_floor` (compiled):
    one 6×6 Cholesky of W^½Λ⁻¹W^½ − ratio·I tells whether W ⪰ ratio·Λ already (then P = I
    and the vector is returned untouched, so the law is exactly the specified one), else one
    symmetric eigen-decomposition gives V and σ. Between refreshes a step costs at most one
    6×6 product. ``ratio`` > 0: the range of ``controller.apparent_inertia_floor``, which
    the controllers check.

    The state (:data:`FLOOR_STATE`) is one record, ``state``, that the compiled SE(3) step
    refreshes in place as well (then :meth:`take_refresh` reads it).
    """

    def __init__(self, W_diag, ratio: float, every: int = 10):
        W = np.asarray(W_diag, dtype=float)
        self.state = np.zeros(1, FLOOR_STATE)
        s = self.state[0]
        s["w_sqrt"] = np.sqrt(W)
        s["w_isqrt"] = 1.0 / s["w_sqrt"]
        s["ratio"] = float(ratio)
        s["P_and_I"][:, 6:] = np.eye(6)
        self.ratio = float(ratio)
        self.every = int(every)
        self.P: np.ndarray | None = None  # W_eff⁻¹W, None while the floor is inactive
        self._step = 0
        self.active_steps = 0
        refresh_floor(np.eye(6), self.state.copy())  # load (or compile) it now, not in the loop

    @property
    def W_sqrt(self) -> np.ndarray:
        """W^½ (the diagonal)."""
        return self.state["w_sqrt"][0]

    @property
    def max_ratio(self) -> float:
        """The largest σ = eig(W^-½ Λ W^-½) seen while active."""
        return float(self.state["max_ratio"][0])

    def refresh(self, lam_inv: np.ndarray) -> None:
        """Recompute P for Λ⁻¹ = ``lam_inv`` (None when W ⪰ ratio·Λ already)."""
        refresh_floor(lam_inv, self.state)
        self.take_refresh()

    def take_refresh(self) -> None:
        """Read the state a refresh left (here or in the compiled SE(3) step): P is
        ``P_and_I``'s left block, or None when inactive."""
        s = self.state[0]
        self.P = s["P_and_I"][:, :6].copy() if s["active"] else None

    def due(self) -> bool:
        """Whether this step refreshes P (every ``every`` steps)."""
        return self._step % self.every == 0

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
            "inertia_floor_max_ratio": self.max_ratio if self.active_steps else None,
        }


def inertia_floor(W_diag, ratio: float | None, use_force_feedback: bool) -> ApparentInertiaFloor | None:
    """The floor a controller uses: None when ``ratio`` is None (the specified law) or without
    force feedback (no delayed-feedback loop to keep stable, the law stays the spec's)."""
    if ratio is None or not use_force_feedback:
        return None
    return ApparentInertiaFloor(W_diag, ratio)
