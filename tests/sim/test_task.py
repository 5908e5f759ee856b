"""The task geometry: start and goal poses, the press after the motion, the run length."""

import numpy as np
import pytest

from compliant_docking.planning.base import PressHome
from compliant_docking.run.runner import execute
from compliant_docking.sim.simulate import prepare
from tests.helpers import make_cfg


def test_start_is_a_stroke_before_the_seat_and_the_plan_ends_there():
    sim = prepare(make_cfg())
    seat = sim.scene.socket.believed
    wp = sim.waypoints
    stroke = np.asarray(sim.cfg.task.stroke)
    assert np.allclose(wp.start.translation, seat.translation - stroke)
    assert np.allclose(wp.goal.translation, seat.translation)
    assert np.allclose(wp.axis, stroke / np.linalg.norm(stroke))
    # the plug points into the socket
    assert np.allclose(wp.start.rotation[:, 2], -seat.rotation[:, 2])
    # and the start posture reaches the start pose
    assert np.allclose(sim.scene.arm.tcp_placement(sim.q0).translation, wp.start.translation, atol=1e-9)


def test_roll_about_the_axis_follows_the_ik_guess():
    """The plug is axisymmetric: the start posture keeps the wrist where ik_guess has it."""
    sim = prepare(make_cfg())
    assert abs(sim.q0[6] - sim.cfg.robot.ik_guess[6]) < np.radians(5)


def test_press_moves_the_reference_past_the_seat_after_the_motion():
    sim = prepare(make_cfg())
    traj = sim.planner
    assert isinstance(traj, PressHome)
    T, P = traj.duration, traj.press_duration
    t = np.array([0.0, T - 1e-3, T, T + P / 2, T + P, T + P + 1.0])
    table = traj.table(t)
    seat = sim.waypoints.goal.translation
    depth = (table.pos - seat) @ sim.waypoints.axis
    assert depth[2] == pytest.approx(0.0, abs=1e-12)  # at the seat when the motion ends
    assert depth[3] == pytest.approx(0.0025, abs=1e-9)  # half way through the press
    assert depth[4] == pytest.approx(0.005, abs=1e-12) and depth[5] == pytest.approx(0.005)
    for k in (2, 4, 5):  # rest to rest
        assert np.allclose(table.twist[k], 0.0, atol=1e-12)
        assert np.allclose(table.accel[k], 0.0, atol=1e-9)
    assert traj.segments[-1] == ("press", T, T + P)


def test_press_must_fit_in_the_settle_time(tmp_path):
    record = execute(make_cfg("task.press_duration=4.0"), tmp_path, echo=False)
    assert record["status"] == "failed" and "task.press_duration" in record["error"]


def test_a_run_shorter_than_its_trajectory_is_incomplete(tmp_path):
    record = execute(
        make_cfg("task.duration=3.0", "task.progress=false"), tmp_path, figures=False, echo=False
    )
    assert record["status"] == "incomplete" and record["success"] is False
    assert "shorter than the trajectory" in record["gate_failures"]
    assert (
        record["gate_verdict"].startswith("not docked: ")
        and "shorter than the trajectory" in record["gate_verdict"]
    )
    assert record["sim_time_s"] == pytest.approx(3.0)


def test_run_length_follows_the_planner():
    for trajectory in ("quintic", "twophase"):
        sim = prepare(make_cfg(f"trajectory={trajectory}"))
        assert sim.duration == pytest.approx(sim.planner.duration + sim.cfg.task.settle_time)
