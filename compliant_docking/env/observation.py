"""What the agent observes: what a real controller could know, in the believed socket frame.

The socket frame the planner BELIEVES (origin at the seat, +z out of the opening; where the
true socket is, the agent does not know). One observation, float32, in this order
(:func:`observation_names`):

=================  ====  ===========================================================
q1 … qn            n     joint positions [rad]
v1 … vn            n     joint velocities [rad/s]
x, y, z            3     TCP (plug tip) position relative to the believed seat [m]
rx, ry, rz         3     TCP orientation error: log3(R R_goalᵀ), R_goal the planned
                         (mated) orientation [rad]
vx, vy, vz         3     TCP linear velocity [m/s]
wx, wy, wz         3     TCP angular velocity [rad/s]
fx, fy, fz         3     sensed force on the tool at the TCP (the F/T reading the
                         controller gets next) [N]
mx, my, mz         3     sensed moment [N·m]
x_ref … z_ref      3     the planner's setpoint for the next step, relative to the seat [m]
phase              1     elapsed fraction of the episode, 0 … 1
=================  ====  ===========================================================

Every vector is expressed in the believed socket axes.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin

_forward, _place, _velocity, _log3 = (
    pin.forwardKinematics,
    pin.updateFramePlacement,
    pin.getFrameVelocity,
    pin.log3,
)
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_get_state, _QV = mujoco.mj_getState, int(mujoco.mjtState.mjSTATE_QPOS | mujoco.mjtState.mjSTATE_QVEL)

#: the names of the 3-vectors, in their order after q and v
VECTORS = (
    ("x", "y", "z"),
    ("rx", "ry", "rz"),
    ("vx", "vy", "vz"),
    ("wx", "wy", "wz"),
    ("fx", "fy", "fz"),
    ("mx", "my", "mz"),
    ("x_ref", "y_ref", "z_ref"),
)


def observation_names(nv: int) -> list[str]:
    """The name of every component of an observation of an ``nv``-joint arm."""
    names = [f"q{i + 1}" for i in range(nv)] + [f"v{i + 1}" for i in range(nv)]
    for triple in VECTORS:
        names += triple
    return [*names, "phase"]


class Observer:
    """Writes the observation of a simulation's current state (after :meth:`Simulation.start`).

    The TCP pose and twist come from Pinocchio's kinematics at the current (q, v), in a data
    of the observer's own (the loop's arm model is left alone); the wrench is the sensor's
    reading, which the loop reads again at its next step: observing changes nothing of the
    run. Few calls per observation: it runs once per policy step, between loops that leave
    the caches cold.
    """

    def __init__(self, sim, believed: pin.SE3, goal_rotation: np.ndarray):
        self.sim = sim
        nv = self.nv = sim.scene.model.nv
        arm = sim.scene.arm
        self.model, self.data, self.frame = arm.model, arm.model.createData(), arm.tcp_frame
        self.tcp = self.data.oMf[self.frame]  # a view, refreshed by updateFramePlacement
        self.axes = believed.rotation.copy()  # believed socket axes in the world (columns)
        self.goal_T = np.ascontiguousarray(goal_rotation.T)
        self.last_setpoint = sim.reference.pos[-1].copy()  # the planner's, after the last step
        self.rows = np.zeros((len(VECTORS), 3))  # world vectors, one per row
        # the seat in the believed socket axes, taken off the two positions after the rotation
        self.shift = np.zeros((len(VECTORS), 3))
        self.shift[0] = self.shift[6] = believed.translation.dot(self.axes)
        self.out = np.zeros(2 * nv + 3 * len(VECTORS) + 1)
        self.state = self.out[: 2 * nv]  # [q, v], one mj_getState
        self.local = self.out[2 * nv : -1].reshape(len(VECTORS), 3)  # the vectors, socket axes
        self.wrench_rows = sim.wrench.reshape(2, 3)  # a view of the sensor's buffer

    def __call__(self) -> np.ndarray:
        sim, rows, model, kin = self.sim, self.rows, self.model, self.data
        data = sim.data
        _get_state(sim.scene.model, data, self.state, _QV)
        _forward(model, kin, data.qpos, data.qvel)
        _place(model, kin, self.frame)
        sim.sense_wrench()
        k = sim.steps_done
        tcp = self.tcp
        rows[0] = tcp.translation
        rows[1] = _log3(tcp.rotation.dot(self.goal_T))
        rows[2:4] = _velocity(model, kin, self.frame, _LWA).vector.reshape(2, 3)
        rows[4:6] = self.wrench_rows
        rows[6] = sim.reference.pos[k] if k < sim.n_steps else self.last_setpoint
        np.subtract(rows.dot(self.axes), self.shift, out=self.local)  # row x ↦ (Rᵀx)ᵀ − seat
        self.out[-1] = k / sim.n_steps
        return self.out.astype(np.float32)

    @property
    def tcp_position(self) -> np.ndarray:
        """The TCP position in the world at the last observation (a view)."""
        return self.tcp.translation
