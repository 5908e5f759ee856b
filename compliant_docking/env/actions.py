"""What an action sets (``env.action.kind``), each component in [−1, 1] (docs/env.md).

``setpoint`` (the default): the controller keeps running at every physics step; the action
moves its setpoint and scales its stiffness, held for the policy step:

====  ===========================================================================
0-2   position offset of the setpoint along the believed socket axes, × max_offset_m
3-5   rotation offset (a rotation vector in the believed socket axes), × max_rotation_deg
6-8   (``gains: true``) stiffness scales across the docking axis, along it, and in
      rotation: max_stiffness_scale ** a (a = 0: the config's gains; damping × √scale)
====  ===========================================================================

The setpoint is the planner's reference with the offset applied (p + R_b Δp,
Exp(R_b Δθ) · R); its twist and acceleration stay the planner's. A zero action leaves the
reference and the gains as the run has them, bit for bit.

``torque``: residual joint torques, a · max_residual_torque, added to the controller's
command at every physics step of the policy step (the motors' clip still applies).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin

from compliant_docking.config.enums import ActionKind


class SetpointAction:
    """Pose offset of the setpoint and, optionally, stiffness scales of the controller."""

    def __init__(self, settings, believed_rotation: np.ndarray, gains: bool):
        self.axes = np.asarray(believed_rotation, dtype=float)
        self.max_offset = float(settings.max_offset_m)
        self.max_rotation = math.radians(float(settings.max_rotation_deg))
        self.gains = bool(gains)
        self.log_scale = math.log(float(settings.max_stiffness_scale))
        self.size = 9 if self.gains else 6
        self.sim: Any = None
        self.scales = (1.0, 1.0, 1.0)

    def bind(self, sim) -> None:
        """Act on ``sim`` from now on (a new episode: the config's gains)."""
        self.sim = sim
        self.scales = (1.0, 1.0, 1.0)

    def apply(self, a: list[float], first: int, last: int) -> None:
        """Set the reference of steps ``first`` … ``last − 1`` (not yet simulated) and the
        gains; ``a``: the action's components (floats in [−1, 1])."""
        ref = self.sim.reference
        dx, dy, dz, rx, ry, rz = a[:6]
        if dx or dy or dz:
            m = self.max_offset
            ref.pos[first:last] += self.axes.dot((dx * m, dy * m, dz * m))
        if rx or ry or rz:
            m = self.max_rotation
            turn = pin.exp3(self.axes.dot((rx * m, ry * m, rz * m)))
            ref.rot[first:last] = np.matmul(turn, ref.rot[first:last])
        if self.gains:
            log_scale = self.log_scale
            scales = (math.exp(log_scale * a[6]), math.exp(log_scale * a[7]), math.exp(log_scale * a[8]))
            if scales != self.scales:
                self.sim.controller.set_stiffness_scales(*scales)
                self.scales = scales


class ResidualTorque:
    """The controller's command plus a residual torque (wraps the controller for the loop)."""

    def __init__(self, controller, nv: int):
        self.controller = controller
        self.residual = np.zeros(nv)

    def compute(self, t, state, ref, wrench) -> np.ndarray:
        return self.controller.compute(t, state, ref, wrench) + self.residual

    def diagnostics(self) -> dict:
        return self.controller.diagnostics()

    def timeseries(self) -> dict[str, np.ndarray]:
        return self.controller.timeseries()


class TorqueAction:
    """Residual joint torques, a · max_residual_torque per joint."""

    def __init__(self, settings, nv: int):
        self.max_torque = float(settings.max_residual_torque)
        self.size = nv
        self.wrapper: ResidualTorque | None = None

    def bind(self, sim) -> None:
        """Wrap ``sim``'s controller (before the loop starts: :meth:`Simulation.start`)."""
        self.wrapper = ResidualTorque(sim.controller, self.size)
        sim.controller = self.wrapper

    def apply(self, a: list[float], first: int, last: int) -> None:
        m = self.max_torque
        self.wrapper.residual[:] = [x * m for x in a]  # type: ignore[union-attr]


def make_action(settings, *, nv: int, believed_rotation: np.ndarray, controller_class: type):
    """The action of ``env.action`` (``settings``); refuses gains the controller cannot scale."""
    kind = ActionKind(settings.kind)
    if kind is ActionKind.torque:
        return TorqueAction(settings, nv)
    if settings.gains and not hasattr(controller_class, "set_stiffness_scales"):
        raise ValueError(
            f"env.action.gains = true needs a controller whose stiffness the environment can "
            f"scale (controller=impedance); {controller_class.__name__} cannot: set "
            f"env.action.gains=false (pose offsets only) or env.action.kind=torque"
        )
    return SetpointAction(settings, believed_rotation, bool(settings.gains))
