"""The schema of the ``env`` config group: the Gymnasium environment of the docking task.

A run's config has no ``env`` node: the settings are composed on their own from
conf/env/docking.yaml (which holds the values, with their units and reasons) by
:func:`compliant_docking.config.store.load_env_config`, and
:func:`compliant_docking.env.make_env` sends it the ``env.*`` overrides
(``make_env("robot=fr3", "env.policy_step=0.02")``). docs/env.md describes the spaces and
the reward these settings shape.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from omegaconf import MISSING

from compliant_docking.config.enums import ActionKind
from compliant_docking.config.ranges import at_least, positive, within


@dataclass
class EnvActionConfig:
    """What one action sets, and its bounds (an action component of ±1 reaches them)."""

    kind: ActionKind = MISSING  # setpoint (pose offset and gain scales) | torque (residual torques)
    max_offset_m: float = positive(at_most=0.1, unit="m")  # setpoint offset per axis at |a| = 1 [m]
    max_rotation_deg: float = within(0.0, 30.0, unit="deg")  # setpoint rotation per axis at |a| = 1 [deg]
    gains: bool = MISSING  # setpoint: three more components scale the stiffness (lateral, axial, rotation)
    max_stiffness_scale: float = within(1.0, 100.0)  # a = ±1 multiplies / divides a stiffness by this
    max_residual_torque: float = positive(unit="N·m")  # torque: per joint at |a| = 1 [N·m]


@dataclass
class EnvRewardConfig:
    """Weights of the reward's terms (docs/env.md gives each term in closed form)."""

    distance: float = at_least(0.0)  # shaping: the potential −distance·d/d₀ toward the true seat
    force: float = at_least(0.0)  # per policy step, per budget of axial force over the budget
    success: float = at_least(0.0)  # bonus at the last step when the docking gate passes
    diverged: float = at_least(0.0)  # penalty when the physics diverges (the episode ends)


@dataclass
class EnvConfig:
    """``env``: the environment's settings (the run's groups set everything else)."""

    name: str = MISSING
    policy_step: float = positive(at_most=1.0, unit="s")  # one action is held this long [s]
    action: EnvActionConfig = MISSING
    reward: EnvRewardConfig = MISSING
    # write every finished episode as a run directory under this folder (null: none)
    record_dir: Optional[str] = MISSING
