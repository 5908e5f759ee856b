"""The reward: shaping toward the seat, a penalty on axial force over budget, the gate's bonus.

Per policy step (docs/env.md; weights from ``env.reward``):

    r = [Φ(s') − Φ(s)] − w_force · max(0, F̄ − F_budget) / F_budget
        + w_success · [last step and the docking gate passes] − w_diverged · [diverged]

- Φ(s) = −w_distance · d(s) / d₀: d the distance from the plug tip (TCP) to the TRUE seat,
  d₀ its value at reset. The shaping is potential-based: over an episode it sums to
  w_distance · (1 − d_end / d₀), whatever the path, so it does not change which policy is
  best; it tells the agent, which sees only the believed socket, where the socket really is.
- F̄: the mean over the policy step's physics steps of the axial force (−f·axis, positive
  when the plug presses into the socket: the metrics' definition, sim.telemetry.axial_force);
  F_budget: the gate's budget ``task.gate.peak_force_budget_N``. The mean over a policy step
  is a moving-average filter, as the gate's filtered peak force is over ``task.force_window``.
- success: the docking gate, judged on the whole episode exactly as a run is judged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the names of the terms, in the order :func:`terms` gives them
TERMS = ("shaping", "force", "success", "diverged")


@dataclass(frozen=True)
class Weights:
    """``env.reward``: the weight of each term."""

    distance: float
    force: float
    success: float
    diverged: float


def potential(distance: float, start_distance: float, weight: float) -> float:
    """Φ = −weight · distance / start_distance (0 at the seat, −weight at the start)."""
    return -weight * distance / start_distance


def force_penalty(axial_force: np.ndarray, budget: float, weight: float) -> float:
    """−weight · max(0, mean(axial_force) − budget) / budget (0 within budget)."""
    n = len(axial_force)
    if n == 0:
        return 0.0
    excess = float(axial_force.sum()) / n - budget
    return -weight * excess / budget if excess > 0.0 else 0.0


def terms(
    weights: Weights,
    *,
    potential_before: float,
    potential_after: float,
    axial_force: np.ndarray,
    budget: float,
    success: bool,
    diverged: bool,
) -> dict[str, float]:
    """The reward's terms of one policy step ({name: value}; the reward is their sum)."""
    return {
        "shaping": potential_after - potential_before,
        "force": force_penalty(axial_force, budget, weights.force),
        "success": weights.success if success else 0.0,
        "diverged": -weights.diverged if diverged else 0.0,
    }
