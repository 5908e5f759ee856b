"""Scripted policies of the environment's default (setpoint) action: the plain planner and a
spiral search, whose parameters a small policy search tunes (compliant_docking/env/example.py).

The spiral search is the classic one of peg-in-hole assembly: follow the planner until the
plug is blocked above the socket (an axial force while the tip is still higher than the
funnel's rim), then move the setpoint on an Archimedean spiral around the believed socket
axis, laterally stiff, until the tip drops into the funnel; then keep the lateral setpoint
where the tip is, so the funnel and the bore guide it, and let the planner press it home.
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass, fields

import numpy as np


@dataclass(frozen=True)
class SpiralParams:
    """The spiral search's parameters (each with the bounds the policy search draws in)."""

    contact_force: float = 0.5  # [N] axial force that means "blocked" (above the bore)
    search_height: float = 0.043  # [m] blocked only while the tip is higher than this above the seat
    drop_height: float = 0.040  # [m] in the funnel once the tip is lower than this: stop searching
    pitch: float = 0.008  # [m] radius gained per turn
    angular_speed: float = 1.5  # [rad/s] of the spiral
    lateral_gain: float = 1.0  # action: lateral stiffness scale while searching (−1 … 1, log)
    axial_gain: float = 0.0  # action: axial stiffness scale while searching
    rotation_gain: float = 0.0  # action: rotational stiffness scale throughout
    inserted_gain: float = 0.0  # action: lateral stiffness scale once in the funnel
    inserted_axial_gain: float = 0.5  # action: axial stiffness scale once in the funnel
    push: float = 0.5  # action: setpoint offset into the socket once in the funnel (0 … 1)

    @staticmethod
    def bounds() -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of every parameter (the policy search's box)."""
        low = np.array([0.1, 0.035, 0.030, 0.001, 0.2, -1.0, -1.0, -1.0, -1.0, -1.0, 0.0])
        high = np.array([3.0, 0.050, 0.045, 0.020, 6.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
        return low, high

    def vector(self) -> np.ndarray:
        return np.array(astuple(self), dtype=float)

    @classmethod
    def from_vector(cls, x) -> SpiralParams:
        low, high = cls.bounds()
        x = np.clip(np.asarray(x, dtype=float), low, high)
        return cls(**{f.name: float(v) for f, v in zip(fields(cls), x, strict=True)})


class PlainPlanner:
    """The zero action: the planned run, bit for bit."""

    def __init__(self, action_size: int):
        self.zero = np.zeros(action_size, dtype=np.float32)

    def reset(self) -> None:
        pass

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        return self.zero


class SpiralSearch:
    """The spiral search on the observation of ``names`` (:func:`observation_names`), for
    the setpoint action with gains; ``max_offset_m`` and ``policy_step`` as the env's."""

    def __init__(self, params: SpiralParams, names: list[str], max_offset_m: float, policy_step: float):
        self.p = params
        self.index = {name: i for i, name in enumerate(names)}
        self.max_offset = max_offset_m
        self.dt = policy_step
        self.reset()

    def reset(self) -> None:
        self.phase = "approach"
        self.angle = 0.0
        self.offset = np.zeros(2)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        i, p = self.index, self.p
        x, y, z = obs[i["x"]], obs[i["y"]], obs[i["z"]]
        axial = obs[i["fz"]]  # the socket pushes the tool out of it (+z): the axial force
        action = np.zeros(9, dtype=np.float32)
        action[8] = p.rotation_gain
        if self.phase == "approach" and axial > p.contact_force and z > p.search_height:
            self.phase = "search"
        if self.phase == "search":
            if z < p.drop_height:  # dropped into the funnel: it guides the plug from here
                self.phase = "insert"
            else:
                self.angle += p.angular_speed * self.dt
                radius = p.pitch * self.angle / (2.0 * math.pi)
                self.offset[:] = radius * math.cos(self.angle), radius * math.sin(self.angle)
                action[6], action[7] = p.lateral_gain, p.axial_gain
        if self.phase == "insert":  # follow the bore: the setpoint where the tip is
            self.offset[:] = x - obs[i["x_ref"]], y - obs[i["y_ref"]]
            action[2] = -p.push
            action[6], action[7] = p.inserted_gain, p.inserted_axial_gain
        action[:2] = np.clip(self.offset / self.max_offset, -1.0, 1.0)
        return action
