"""What the simulation hands a controller: its run-time context, and the interface it calls.

A controller is built once per run as ``Controller(context=ControlContext(...), **params)``
(the parameters from its config group, by Hydra's ``instantiate``) and stepped by the loop
through :class:`StepController`. The controllers themselves live in
:mod:`compliant_docking.control`, a layer above this one: the loop knows them only by this
interface.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from compliant_docking.planning.base import Reference
from compliant_docking.sim.models import ArmModel


@dataclass
class ControlContext:
    """What a controller needs besides its gains (built by the simulation)."""

    arm: ArmModel
    dt: float
    n_steps: int  # steps the run will last (for preallocating per-step records)
    q_home: np.ndarray  # joint posture at t = 0 (start-pose IK solution)
    velocity_limits: np.ndarray  # [rad/s]
    torque_limits: np.ndarray  # software clip of the command (applied by the motors) [N·m]
    joint_friction: np.ndarray  # MuJoCo dof_frictionloss, not modelled by Pinocchio [N·m]
    joint_damping: np.ndarray  # MuJoCo dof_damping, not modelled by Pinocchio [N·m·s/rad]
    axis: np.ndarray  # unit docking axis in the world


class StepController(Protocol):
    """The interface the simulation loop uses (:class:`compliant_docking.control.base.Controller`)."""

    def compute(self, t: float, state: ArmModel, ref: Reference, wrench: np.ndarray) -> np.ndarray:
        """The joint torque command of this step (the motors clip it)."""
        ...

    def diagnostics(self) -> dict:
        """Scalars about the run for ``metrics.json``."""
        ...

    def timeseries(self) -> dict[str, np.ndarray]:
        """Per-step signals for the run's time series."""
        ...
