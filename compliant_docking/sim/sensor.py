"""The wrist force/torque sensor as the controllers see it: the external wrench on the tool at
the TCP, in world axes, one step old, with the tool's own weight removed."""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np
import pinocchio as pin

from compliant_docking.sim.scene import Scene


def wrench_reader(scene: Scene, data: mujoco.MjData, out: np.ndarray) -> Callable[[], None]:
    """A function writing into ``out`` the tool's external wrench [f; m] at the TCP, world axes.

    MuJoCo's force/torque sensors give what the tool subtree exerts on its parent about
    the sensor site, in the site frame: minus the external wrench (minus the tool's
    weight). A constant 6×6 map moves the moment to the TCP and flips the sign in the
    site frame; one rotation takes both halves to the world. The values come from the
    previous mj_step: a one-step measurement delay, as on a real robot.
    """
    raw = data.sensordata[scene.force_adr : scene.force_adr + 6]  # [force; torque], a view
    site_rot_T = data.site_xmat[scene.sensor_site].reshape(3, 3).T  # a view, tracks the data
    tool = scene.arm.tool
    # TCP → sensor offset in the sensor frame; moment about the TCP = m_s + r × f
    r = -(tool.sensor.actInv(tool.tcp)).translation
    to_tcp = -np.block([[np.eye(3), np.zeros((3, 3))], [pin.skew(r), np.eye(3)]])
    local = np.zeros((2, 3))  # the wrench at the TCP in sensor axes, rows [f; m]
    local_flat = local.reshape(6)
    out_rows = out.reshape(2, 3)  # a view of out
    # The tool's weight, as the sensor sees it, at the TCP: f = m g and
    # moment (c − p_tcp) × m g = −[m g]× R_dock (com − tcp) with constant parts.
    weight = tool.mass * scene.gravity
    has_weight = bool(np.any(weight))
    weight_moment = -pin.skew(weight)
    com_from_tcp = tool.com - tool.tcp.translation  # dock frame
    dock_rot = data.xmat[scene.tool_body].reshape(3, 3)

    def read() -> None:
        # ndarray.dot: a fraction of the call overhead of `@` on arrays this small
        to_tcp.dot(raw, out=local_flat)
        local.dot(site_rot_T, out=out_rows)  # each row rotated to world axes
        if has_weight:  # payload compensation, as on a real F/T sensor
            out[:3] -= weight
            out[3:] -= weight_moment.dot(dock_rot.dot(com_from_tcp))

    return read
