"""The quintic planner: boundary conditions, peaks, finite differences, table = sample."""

import numpy as np
import pinocchio as pin

from compliant_docking.planning.base import Reference, Waypoints, quintic_scaling
from tests.planning.cases import quintic


def make(duration=15.0):
    start = pin.SE3(pin.rpy.rpyToMatrix(np.pi, 0.1, 0.2), np.array([0.5, 0.1, 0.3]))
    goal = pin.SE3(start.rotation, np.array([0.52, 0.05, 0.19]))
    return (
        quintic(Waypoints(start=start, goal=goal, axis=np.array([0, 0, -1.0])), duration=duration),
        start,
        goal,
    )


def test_rest_to_rest_boundaries_and_hold():
    traj, start, goal = make()
    ref = Reference()
    for t, pos in ((0.0, start.translation), (15.0, goal.translation), (17.0, goal.translation)):
        traj.sample(t, ref)
        assert np.allclose(ref.pos, pos, atol=1e-12)
        assert np.allclose(ref.twist, 0.0, atol=1e-12) and np.allclose(ref.accel, 0.0, atol=1e-12)
        assert np.allclose(ref.rot, start.rotation)


def test_peak_speed_and_acceleration_match_the_closed_form():
    traj, start, goal = make()
    L, T = np.linalg.norm(goal.translation - start.translation), traj.duration
    t = np.linspace(0, T, 30001)
    table = traj.table(t)
    speed = np.linalg.norm(table.twist[:, :3], axis=1)
    accel = np.linalg.norm(table.accel[:, :3], axis=1)
    assert np.isclose(speed.max(), 1.875 * L / T, rtol=1e-6)
    assert np.isclose(accel.max(), 10 / np.sqrt(3) * L / T**2, rtol=1e-4)
    assert np.isclose(t[np.argmax(speed)], T / 2, atol=1e-3)


def test_velocity_and_acceleration_are_derivatives():
    traj, _, _ = make()
    t = np.linspace(0.5, 14.5, 2001)
    h = 1e-5
    table = traj.table(t)
    v, a = table.twist[:, :3], table.accel[:, :3]
    dp = (traj.table(t + h).pos - traj.table(t - h).pos) / (2 * h)
    dv = (traj.table(t + h).twist[:, :3] - traj.table(t - h).twist[:, :3]) / (2 * h)
    assert np.abs(dp - v).max() < 1e-8
    assert np.abs(dv - a).max() < 1e-7


def test_table_equals_sample():
    traj, _, _ = make()
    t = np.array([0.0, 1.3, 7.5, 14.99, 20.0])
    table = traj.table(t)
    ref = Reference()
    for k, tk in enumerate(t):
        traj.sample(tk, ref)
        assert np.allclose(table.pos[k], ref.pos) and np.allclose(table.twist[k], ref.twist)
        assert np.allclose(table.accel[k], ref.accel) and np.allclose(table.rot[k], ref.rot)


def test_scaling_is_clamped_outside_the_unit_interval():
    assert quintic_scaling(-1.0) == (0.0, 0.0, 0.0)
    assert quintic_scaling(2.0) == (1.0, 0.0, 0.0)
