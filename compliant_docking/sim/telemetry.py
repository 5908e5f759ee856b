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
    "axes [N, N·m] (the value the controller received, one step late)",
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
        model = arm.model
        data = model.createData()
        pos, quat, twist = np.zeros((n, 3)), np.zeros((n, 4)), np.zeros((n, 6))
        ref_quat, ori_err = np.zeros((n, 4)), np.zeros((n, 3))
        ref_pos, ref_twist, ref_rot = reference.pos[:n], reference.twist[:n], reference.rot[:n]
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        for k in range(n):
            pin.forwardKinematics(model, data, self.q[k], self.v[k])
            placement = pin.updateFramePlacement(model, data, arm.tcp_frame)
            pos[k] = placement.translation
            quat[k] = _wxyz(placement.rotation)
            twist[k] = pin.getFrameVelocity(model, data, arm.tcp_frame, lwa).vector
            ref_quat[k] = _wxyz(ref_rot[k])
            ori_err[k] = pin.log3(ref_rot[k] @ placement.rotation.T)

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


def _wxyz(rot: np.ndarray) -> np.ndarray:
    import pinocchio as pin

    x, y, z, w = pin.Quaternion(rot).coeffs()
    return np.array([w, x, y, z])
