"""The task's geometry: start and goal poses of the TCP and the docking axis, and the run length."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import TaskConfig
from compliant_docking.config.validate import quaternion_problem, start_problems
from compliant_docking.planning.base import Planner, Waypoints
from compliant_docking.sim.geometry.fragment import MATED
from compliant_docking.sim.scene import Scene
from compliant_docking.sim.settings import SimSettings


def task_waypoints(settings: SimSettings, scene: Scene) -> Waypoints:
    """Start and goal TCP poses and the docking axis, from the socket pose the planner believes.

    Without ``task.init_quat`` the plug points along the socket axis into the socket.
    Its roll about that axis: for a round interface (``scene.key.symmetry`` 0) the roll
    of the TCP at ``robot.ik_guess``, so the start posture needs no wrist turn; for a
    keyed one, the mating roll (tcp x along the believed seat's x, turned by a multiple
    of 360°/symmetry; :mod:`compliant_docking.sim.geometry.fragment`) nearest to it.
    """
    task = settings.task
    stroke = np.asarray(task.stroke, dtype=float)
    length = float(np.linalg.norm(stroke))
    guess = scene.arm.tcp_placement(np.asarray(settings.robot.ik_guess, dtype=float)).rotation
    # the config check's rule
    unplaced = start_problems(task.stroke, task.init_pos, has_target=scene.socket is not None)
    if unplaced:
        raise ValueError(unplaced[0])
    if scene.socket is None:
        rot = (
            _quat_matrix(task.init_quat, "task.init_quat")
            if task.init_quat is not None
            else _with_axis(guess, np.array([0.0, 0.0, -1.0]))
        )  # plug pointing down
        axis = stroke / length if length > 0 else rot[:, 2]
        return Waypoints(start=pin.SE3(rot, np.asarray(task.init_pos, float)), goal=None, axis=axis)

    axis = stroke / length
    seat = scene.socket.believed
    if task.init_pos is None:
        start_pos = seat.translation - stroke
    else:
        start_pos = np.asarray(task.init_pos, dtype=float)
    if task.init_quat is not None:
        rot = _quat_matrix(task.init_quat, "task.init_quat")
    elif scene.key.keyed:
        rot = keyed_rotation(seat.rotation, scene.key.symmetry, guess)
    else:
        rot = _with_axis(guess, -seat.rotation[:, 2])
    return Waypoints(start=pin.SE3(rot, start_pos), goal=pin.SE3(rot, start_pos + stroke), axis=axis)


def nominal_waypoints(settings: SimSettings) -> Waypoints:
    """The task's waypoints from the config alone, up to a rigid motion of the whole path:
    :func:`task_waypoints` places the goal at start + ``task.stroke`` with the start's
    orientation, so the planner's duration and its own checks are those of the run.
    For the checks before a run (compliant_docking/run/preflight.py); no scene needed."""
    task = settings.task
    stroke = np.asarray(task.stroke, dtype=float)
    length = float(np.linalg.norm(stroke))
    start = pin.SE3(np.eye(3), np.zeros(3) if task.init_pos is None else np.asarray(task.init_pos, float))
    axis = stroke / length if length > 0 else np.array([0.0, 0.0, 1.0])
    if settings.socket is None:
        return Waypoints(start=start, goal=None, axis=axis)
    return Waypoints(start=start, goal=pin.SE3(np.eye(3), start.translation + stroke), axis=axis)


def keyed_rotation(seat: np.ndarray, symmetry: int, near: np.ndarray) -> np.ndarray:
    """The mated tcp orientation (world) for a seat orientation ``seat`` and a key of
    ``symmetry``: seat · Rx(180°) · Rz(360°·k/symmetry), the k nearest to ``near``."""
    best, best_angle = seat, np.inf
    for k in range(symmetry):
        phi = 2.0 * np.pi * k / symmetry
        c, s = np.cos(phi), np.sin(phi)
        rot = seat @ MATED @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        angle = np.arccos(np.clip((np.trace(rot.T @ near) - 1.0) / 2.0, -1.0, 1.0))
        if angle < best_angle:
            best, best_angle = rot, angle
    return best


def _with_axis(rot: np.ndarray, z_axis: np.ndarray) -> np.ndarray:
    """The rotation whose z axis is ``z_axis``, closest in roll to ``rot``."""
    z = z_axis / np.linalg.norm(z_axis)
    x = rot[:, 0] - (rot[:, 0] @ z) * z
    if np.linalg.norm(x) < 1e-6:  # rot's x lies along z: use its y for the roll instead
        x = np.cross(rot[:, 1] - (rot[:, 1] @ z) * z, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _quat_matrix(quat, setting: str) -> np.ndarray:
    q = np.asarray(quat, dtype=float)
    problem = quaternion_problem(setting, q.ravel().tolist())  # the config check's rule
    if problem:
        raise ValueError(problem)
    return pin.Quaternion(q[0], q[1], q[2], q[3]).matrix()


def run_duration(task: TaskConfig, planner: Planner) -> tuple[float, list[str]]:
    """The run length: task.duration if set, else the planner's duration + settle_time."""
    notes: list[str] = []
    if task.duration is None:
        return planner.duration + float(task.settle_time), notes
    require(TaskConfig, "task", duration=task.duration)  # the config check's rule
    duration = float(task.duration)
    if duration < planner.duration:
        notes.append(
            f"task.duration = {duration:g} s is shorter than the trajectory "
            f"({planner.duration:.3g} s): the run is incomplete"
        )
    return duration, notes


def hold_extension(task: TaskConfig, planner: Planner) -> float:
    """The longest a held reference may extend the run [s]: ``task.max_hold`` when the
    planner's reference is bounded (``trajectory.lead_limit``) and the run length follows
    the planner (``task.duration`` null); else 0 (a fixed run length is kept as given)."""
    if planner.lead_limit is None or task.duration is not None:
        return 0.0
    max_hold = float(task.max_hold)
    require(TaskConfig, "task", max_hold=max_hold)  # the config check's rule
    return max_hold
