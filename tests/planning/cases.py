"""Shared cases of the planner tests: docking and free-space waypoints, finite differences."""

import functools
import math

import numpy as np
import pinocchio as pin
from omegaconf import OmegaConf

from compliant_docking.config import load_config
from compliant_docking.planning.base import Waypoints
from compliant_docking.planning.quintic import QuinticPlanner
from compliant_docking.planning.se3topp import SE3ToppPlanner
from compliant_docking.planning.tracking import TrackingPlanner
from compliant_docking.planning.twophase import TwoPhasePlanner

AXIS = np.array([0.0, 0.0, -1.0])
DOWN = np.diag([1.0, -1.0, -1.0])  # plug pointing down (z along −world z)


def docking(ahead=0.18, rot_goal=None, lateral=(0.0, 0.0)):
    """Start `ahead` metres before the goal along −z (plus a lateral offset)."""
    goal = pin.SE3(DOWN if rot_goal is None else rot_goal, np.array([0.55, 0.0, 0.20]))
    start = pin.SE3(DOWN, goal.translation + np.array([*lateral, ahead]))
    return Waypoints(start=start, goal=goal, axis=AXIS)


def free_space():
    return Waypoints(start=pin.SE3(DOWN, np.array([0.55, 0.0, 0.45])), goal=None, axis=AXIS)


def fd_check(traj, t, h=1e-6):
    """Max errors of the world twist/accel against central differences of pose/twist."""
    ref, lo, hi = traj.table(t), traj.table(t - h), traj.table(t + h)
    dp = (hi.pos - lo.pos) / (2 * h)
    omega = np.array([pin.log3(a @ b.T) for a, b in zip(hi.rot, lo.rot)]) / (2 * h)
    dtw = (hi.twist - lo.twist) / (2 * h)
    return (
        np.abs(dp - ref.twist[:, :3]).max(),
        np.abs(omega - ref.twist[:, 3:]).max(),
        np.abs(dtw - ref.accel).max(),
    )


def away_from(t, instants, margin):
    return np.all(np.abs(t[:, None] - np.asarray(instants)[None, :]) > margin, axis=1)


def rotating_case(angle=math.pi / 2):
    """Approach with a rotation about an axis NOT along the translation (centripetal term)."""
    # about an axis that the start rotation moves: world and body angular velocity differ
    rot_goal = DOWN @ pin.exp3(angle * np.array([0.6, 0.8, 0.0]))
    return docking(0.18, rot_goal=rot_goal, lateral=(0.03, -0.02))


def coupled_case():
    """A 90° turn with a large lateral move and loose angular limits: the centripetal part
    of the linear acceleration binds (approach limits v, a, ω, α = 0.10, 0.05, 5, 5)."""
    rot_goal = DOWN @ pin.exp3(np.array([0.0, math.pi / 2, 0.0]))
    wp = docking(0.18, rot_goal=rot_goal, lateral=(0.3, 0.0))
    return wp, dict(a_max_approach=0.05, omega_max_approach=5.0, alpha_max_approach=5.0)


@functools.cache
def _yaml_params(option: str) -> dict:
    node = load_config(f"trajectory={option}").trajectory
    params = OmegaConf.to_container(node, resolve=True)
    params.pop("_target_")
    return params


def _planner(cls, option: str):
    def make(waypoints, **overrides):
        """The planner with the parameters of conf/trajectory/<option>.yaml, some overridden."""
        return cls(waypoints, **{**_yaml_params(option), **overrides})

    return make


quintic = _planner(QuinticPlanner, "quintic")
twophase = _planner(TwoPhasePlanner, "twophase")
se3topp = _planner(SE3ToppPlanner, "se3topp")
tracking = _planner(TrackingPlanner, "tracking")
