"""Per-step records of a run: preallocated in the loop, expanded and written once at the end.

The hot loop stores only what cannot be recomputed (q, v, torque command, measured
wrench, contact count, and any per-step signals a controller declares). Everything
derivable (TCP pose and twist from q, v; the reference from the planner) is
reconstructed after the loop, so recording costs a few row copies per step.

The time series is saved as ``timeseries.parquet``; the columns are documented in
docs/run_directory.md and listed by :data:`COLUMN_DOCS`. The column groups below are
the one place their names are written: readers (metrics, gates, figures) use them.
This module imports Pinocchio only inside :meth:`Telemetry.frame`, so readers stay light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

if TYPE_CHECKING:
    from compliant_docking.planning.base import ReferenceTable
    from compliant_docking.sim.models import ArmModel

#: column groups of the time series
POSITION = ["x", "y", "z"]
QUATERNION = ["qw", "qx", "qy", "qz"]
TWIST = ["vx", "vy", "vz", "wx", "wy", "wz"]
POSITION_REF = [f"{c}_ref" for c in POSITION]
QUATERNION_REF = [f"{c}_ref" for c in QUATERNION]
TWIST_REF = [f"{c}_ref" for c in TWIST]
ORI_ERROR = ["ori_error_x", "ori_error_y", "ori_error_z"]
FORCE = ["fx", "fy", "fz"]
MOMENT = ["mx", "my", "mz"]
WRENCH = [*FORCE, *MOMENT]


def axial_force(force: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Per step, −f·axis [N]: the measured force ON the tool (rows of ``force``, world axes)
    along the docking axis (normalised here), positive when the plug presses into the
    socket. The one definition behind the metrics, the figures and the video."""
    axis = np.asarray(axis, dtype=float)
    return -(np.asarray(force, dtype=float) @ (axis / np.linalg.norm(axis)))


COLUMN_DOCS = {
    "t": "time [s]",
    "q{i}": "joint positions [rad], joints 1..n",
    "v{i}": "joint velocities [rad/s]",
    "tau{i}": "joint torque applied after clipping [N·m]",
    "x, y, z": "TCP position, world [m]",
    "qw, qx, qy, qz": "TCP orientation quaternion, world",
    "vx, vy, vz, wx, wy, wz": "TCP twist, world axes [m/s, rad/s]",
    "x_ref, y_ref, z_ref": "reference TCP position [m]",
    "qw_ref, qx_ref, qy_ref, qz_ref": "reference orientation quaternion",
    "vx_ref … wz_ref": "reference twist",
    "pos_error": "‖x − x_ref‖ [m]",
    "ori_error_x/y/z": "log3(R_ref Rᵀ), world axes [rad]",
    "fx, fy, fz, mx, my, mz": "wrench on the tool measured by the F/T sensor, at the TCP, world "
    "axes [N, N·m] (exact, one step late: the value the controller received with the ideal "
    "sensor; row 0: the arm held at rest at its start posture, sim.simulate.start_held)",
    "sensed_fx … sensed_mz": "with a sensor model or a believed tool: the F/T reading the "
    "controller received (compliant_docking/sim/sensor.py)",
    "contacts": "number of MuJoCo contacts",
    "torque_saturated": "some joint command hit the torque clip",
    "<controller extras>": "per-step signals declared by the controller (e.g. adaptive "
    "stiffness, observer wrench), prefixed by their name",
}


class Telemetry:
    """Preallocated per-step buffers for ``n_steps`` steps of an ``nv``-joint arm."""

    def __init__(self, n_steps: int, nv: int, dt: float):
        self.dt = dt
        self.capacity = n_steps
        self.count = 0
        # One row per step [q, v, command], filled by one mj_getState(QPOS|QVEL|CTRL) copy.
        self.state = np.zeros((n_steps, 3 * nv))
        self.q = self.state[:, :nv]
        self.v = self.state[:, nv : 2 * nv]
        self.tau_cmd = self.state[:, 2 * nv :]
        self.wrench = np.zeros((n_steps, 6))
        self.contacts = np.zeros(n_steps, dtype=np.int32)

    @property
    def time(self) -> np.ndarray:
        return np.arange(self.count) * self.dt

    def applied_torque(self, limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The torque the motors applied (command clipped to ±limits) and the saturation flags."""
        cmd = self.tau_cmd[: self.count]
        saturated = np.asarray((np.abs(cmd) > limits).any(axis=1))
        return np.clip(cmd, -limits, limits), saturated

    def frame(
        self,
        arm: ArmModel,
        reference: ReferenceTable,
        torque_limits: np.ndarray,
        extras: dict[str, np.ndarray] | None = None,
    ) -> pd.DataFrame:
        """The recorded steps as one DataFrame, with the derived columns filled in."""
        import pinocchio as pin

        n, nv = self.count, self.q.shape[1]
        t = self.time
        model, frame_id = arm.model, arm.tcp_frame
        data = model.createData()
        pose, twist = np.zeros((n, 4, 4)), np.zeros((n, 6))
        ref_pos, ref_twist, ref_rot = reference.pos[:n], reference.twist[:n], reference.rot[:n]
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        forward, place, velocity = pin.forwardKinematics, pin.updateFramePlacement, pin.getFrameVelocity
        q, v = self.q, self.v
        for k in range(n):  # the TCP pose and twist: Pinocchio's kinematics, step by step
            forward(model, data, q[k], v[k])
            pose[k] = place(model, data, frame_id).homogeneous
            twist[k] = velocity(model, data, frame_id, lwa).vector
        pos, rot = pose[:, :3, 3], pose[:, :3, :3]
        quat, ref_quat = quaternions_wxyz(rot), quaternions_wxyz(ref_rot)
        # log3(R_ref Rᵀ): the products batched, Pinocchio's log3 per step (bit for bit as before)
        relative = np.matmul(ref_rot, rot.transpose(0, 2, 1))
        ori_err = np.zeros((n, 3))
        log3 = pin.log3
        for k in range(n):
            ori_err[k] = log3(relative[k])

        tau, saturated = self.applied_torque(np.asarray(torque_limits, dtype=float))
        columns: dict[str, np.ndarray] = {"t": t}
        for name, block in (("q", self.q), ("v", self.v), ("tau", tau)):
            for i in range(nv):
                columns[f"{name}{i + 1}"] = block[:n, i]
        _put(columns, POSITION, pos)
        _put(columns, QUATERNION, quat)
        _put(columns, TWIST, twist)
        _put(columns, POSITION_REF, ref_pos)
        _put(columns, QUATERNION_REF, ref_quat)
        _put(columns, TWIST_REF, ref_twist)
        columns["pos_error"] = np.linalg.norm(pos - ref_pos, axis=1)
        _put(columns, ORI_ERROR, ori_err)
        _put(columns, WRENCH, self.wrench[:n])
        columns["contacts"] = self.contacts[:n]
        columns["torque_saturated"] = saturated
        for name, values in (extras or {}).items():
            values = np.asarray(values)[:n]
            if values.ndim == 1:
                columns[name] = values
            else:
                for i in range(values.shape[1]):
                    columns[f"{name}_{i + 1}"] = values[:, i]
        return pd.DataFrame(columns)


def _put(columns: dict, names: list[str], block: np.ndarray) -> None:
    for i, name in enumerate(names):
        columns[name] = block[:, i]


def quaternions_wxyz(rot: np.ndarray) -> np.ndarray:
    """Unit quaternions [w, x, y, z] of a stack of rotation matrices (n × 3 × 3).

    Eigen's conversion (Shepperd's method, as ``pin.Quaternion(R)``), vectorized and
    bit for bit the same (tests/sim/test_telemetry.py checks it on random rotations of
    both branches): 50× faster than a Pinocchio call per row.
    """
    rot = np.asarray(rot, dtype=float).reshape(-1, 3, 3)
    out = np.empty((len(rot), 4))
    # Eigen sums the trace as m00 + (m11 + m22); the order matters to the last bit
    trace = rot[:, 0, 0] + (rot[:, 1, 1] + rot[:, 2, 2])
    pos = trace > 0.0
    if pos.any():
        r = rot[pos]
        t = np.sqrt(trace[pos] + 1.0)
        out[pos, 0] = 0.5 * t
        t = 0.5 / t
        out[pos, 1] = (r[:, 2, 1] - r[:, 1, 2]) * t
        out[pos, 2] = (r[:, 0, 2] - r[:, 2, 0]) * t
        out[pos, 3] = (r[:, 1, 0] - r[:, 0, 1]) * t
    rows = np.flatnonzero(~pos)
    if rows.size:  # the largest diagonal entry i leads
        r = rot[rows]
        a = np.arange(len(rows))
        i = np.where(r[:, 1, 1] > r[:, 0, 0], 1, 0)
        i = np.where(r[:, 2, 2] > r[a, i, i], 2, i)
        j, k = (i + 1) % 3, (i + 2) % 3
        t = np.sqrt(r[a, i, i] - r[a, j, j] - r[a, k, k] + 1.0)
        xyz = np.empty((len(rows), 3))
        xyz[a, i] = 0.5 * t
        t = 0.5 / t
        w = (r[a, k, j] - r[a, j, k]) * t
        xyz[a, j] = (r[a, j, i] + r[a, i, j]) * t
        xyz[a, k] = (r[a, k, i] + r[a, i, k]) * t
        out[rows, 0] = w
        out[rows, 1:] = xyz
    return out
