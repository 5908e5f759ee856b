"""Pinocchio model of the arm plus the rigid tool, and the per-step dynamics pass.

The controllers never touch MuJoCo's internals: they see the arm through
:class:`ArmModel`, which Pinocchio builds from the same arm MJCF MuJoCo simulates
(``buildModelFromMJCF`` reads inertias and armature) with the tool's inertia appended
to the flange, so M(q) and the bias forces match MuJoCo's (tests/sim/test_models.py).

Conventions: the controlled point is the tool's TCP; its Jacobian ``J`` is expressed
in LOCAL_WORLD_ALIGNED axes (origin at the TCP, world axes), linear rows first; twists
and wrenches are ``[linear; angular]``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from compliant_docking.config.validate import quaternion_problem

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
# bound once: the per-step update looks them up as globals, not as module attributes
_all_terms, _minverse = pin.computeAllTerms, pin.computeMinverse
_frame_jacobian, _frame_acceleration = pin.getFrameJacobian, pin.getFrameClassicalAcceleration


@dataclass(frozen=True)
class RigidTool:
    """A rigid tool in its own ``dock`` frame (see :mod:`compliant_docking.sim.scene`)."""

    mass: float
    com: np.ndarray  # centre of mass in the dock frame [m]
    inertia: np.ndarray  # 3×3 rotational inertia about the centre of mass, dock axes [kg·m²]
    tcp: pin.SE3  # controlled point in the dock frame
    sensor: pin.SE3  # force/torque sensor site in the dock frame


class ArmModel:
    """Pinocchio model of arm + tool with one dynamics pass per control step.

    After :meth:`update(q, v) <update>` the attributes hold, for that state:
    ``q``, ``v`` (the arrays passed in, not copies), ``M``, ``Minv`` (n×n), ``h`` = C(q,v)v + g(q) (n), ``J`` (6×n, TCP, world axes),
    ``Jdot_v`` = J̇v (6), ``pos`` (3), ``rot`` (3×3), ``twist`` = J v (6).
    ``M``, ``Minv``, ``h``, ``pos``, ``rot`` and ``rot_T`` (its transpose) are views into
    Pinocchio's data, bound once
    and refreshed in place by every update (copy them to keep a value).
    """

    def __init__(
        self,
        mjcf_path: str | Path,
        ee_site: str,
        mount: pin.SE3,
        tool: RigidTool,
        gravity: np.ndarray,
        adjust: Callable[[pin.Model], None] | None = None,
    ):
        """``adjust``: changes the arm's model in place before the tool is appended (a
        controller's believed link inertias: compliant_docking/sim/model_error.py)."""
        model = pin.buildModelFromMJCF(str(mjcf_path))
        if adjust is not None:
            adjust(model)
        if not model.existFrame(ee_site):
            raise ValueError(
                f"robot.ee_site {ee_site!r} is not a site of {mjcf_path}; "
                f"frames there: {', '.join(f.name for f in model.frames)}"
            )
        site_id = model.getFrameId(ee_site)
        site = model.frames[site_id]
        # dock frame relative to the parent joint of the flange site
        joint_to_dock = site.placement * mount
        tool_inertia = pin.Inertia(
            float(tool.mass), np.asarray(tool.com, float), np.asarray(tool.inertia, float)
        )
        model.appendBodyToJoint(site.parentJoint, tool_inertia, joint_to_dock)
        self.tcp_frame = model.addFrame(
            pin.Frame("tcp", site.parentJoint, site_id, joint_to_dock * tool.tcp, pin.FrameType.OP_FRAME)
        )
        self.sensor_frame = model.addFrame(
            pin.Frame(
                "ft_sensor", site.parentJoint, site_id, joint_to_dock * tool.sensor, pin.FrameType.OP_FRAME
            )
        )
        model.gravity.linear = np.asarray(gravity, dtype=float).copy()
        self.model = model
        self.data = model.createData()
        self.nv = model.nv
        self.tool = tool
        self.q_lower = model.lowerPositionLimit.copy()
        self.q_upper = model.upperPositionLimit.copy()
        # Pinocchio reuses its buffers: bind the views once, refresh them in update().
        self.M, self.Minv, self.h = self.data.M, self.data.Minv, self.data.nle
        placement = self.data.oMf[self.tcp_frame]
        self.pos, self.rot = placement.translation, placement.rotation
        self.rot_T = self.rot.T
        self.twist = np.zeros(6)
        self.update(pin.neutral(model), np.zeros(model.nv))

    def update(self, q: np.ndarray, v: np.ndarray) -> None:
        """Kinematics and dynamics at (q, v): one computeAllTerms + M⁻¹ + TCP quantities."""
        model, data, fid = self.model, self.data, self.tcp_frame
        _all_terms(model, data, q, v)
        _minverse(model, data, q)
        self.q, self.v = q, v
        # getFrameJacobian also refreshes the TCP placement oMf (hence pos and rot)
        self.J = _frame_jacobian(model, data, fid, _LWA)
        # computeAllTerms ran the forward pass with zero joint acceleration, so the
        # classical acceleration of the TCP is exactly J̇v.
        self.Jdot_v = _frame_acceleration(model, data, fid, _LWA).vector
        self.J.dot(v, out=self.twist)

    def tcp_placement(self, q: np.ndarray) -> pin.SE3:
        """World placement of the TCP at q (kinematics only; leaves the dynamics untouched)."""
        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, q)
        return data.oMf[self.tcp_frame].copy()

    def world_jacobian(self, q: np.ndarray, data: pin.Data | None = None) -> np.ndarray:
        """6×n TCP Jacobian in world axes at q (for post-processing)."""
        data = data or self.model.createData()
        return pin.computeFrameJacobian(self.model, data, q, self.tcp_frame, _LWA)

    def solve_ik(
        self,
        target: pin.SE3,
        q_guess: np.ndarray,
        *,
        tol: float = 1e-9,
        max_iter: int = 500,
        damping: float = 1e-6,
    ) -> np.ndarray:
        """Damped least-squares inverse kinematics of the TCP, clamped to joint limits.

        Raises ValueError naming the unreached pose when it does not converge.
        """
        model = self.model
        data = model.createData()
        q = np.clip(np.asarray(q_guess, dtype=float).copy(), self.q_lower, self.q_upper)
        err = np.inf
        for _ in range(max_iter):
            pin.framesForwardKinematics(model, data, q)
            current = data.oMf[self.tcp_frame]
            # error in the TCP's local frame, then mapped to world axes
            err6 = pin.log6(current.actInv(target)).vector
            err = float(np.linalg.norm(err6))
            if err < tol:
                break
            J = pin.computeFrameJacobian(model, data, q, self.tcp_frame, pin.ReferenceFrame.LOCAL)
            dq = J.T @ np.linalg.solve(J @ J.T + damping * np.eye(6), err6)
            q = np.clip(pin.integrate(model, q, dq), self.q_lower, self.q_upper)
        if err > 1e-6:
            raise ValueError(
                f"inverse kinematics did not reach the start pose (position "
                f"{np.round(target.translation, 4).tolist()}, residual {err:.2e}): it may be out "
                f"of reach or outside the joint limits. Move task.init_pos / the target, or "
                f"give robot.ik_guess a posture closer to it."
            )
        return q


def mount_placement(pos, quat_wxyz, key: str) -> pin.SE3:
    """SE3 from a position and a wxyz quaternion (as written in the configs, at ``key``)."""
    problem = quaternion_problem(key, [float(c) for c in quat_wxyz])  # the config check's rule
    if problem:
        raise ValueError(problem)
    w, x, y, z = (float(c) for c in quat_wxyz)
    quat = pin.Quaternion(w, x, y, z)
    return pin.SE3(quat.normalized().matrix(), np.asarray(pos, dtype=float))
