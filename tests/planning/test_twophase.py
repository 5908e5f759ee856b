"""The twophase planner: segment times, limits, the pre-dock point, derivatives."""

import math

import numpy as np
import pinocchio as pin
import pytest

from compliant_docking.planning.base import Reference
from compliant_docking.planning.twophase import quintic_segment_time
from tests.planning.cases import AXIS, DOWN, docking, fd_check, free_space, twophase


def test_twophase_segment_times_follow_the_formula():
    traj = twophase(docking(0.18), standoff=0.10)
    (n1, a0, a1), (n2, d0, d1) = traj.segments
    assert (n1, n2) == ("approach", "docking") and a0 == 0.0 and a1 == d0
    # approach 0.08 m at 0.10 m/s, 0.20 m/s²: max(1.5, √(5.7735·0.4)) = 1.5197 s (acceleration-bound)
    assert math.isclose(
        a1, max(1.875 * 0.08 / 0.10, math.sqrt(10 / math.sqrt(3) * 0.08 / 0.20)), rel_tol=1e-12
    )
    assert math.isclose(a1, 1.519671, rel_tol=1e-6)
    # docking 0.10 m at 0.02 m/s, 0.05 m/s²: 9.375 s (speed-bound)
    assert math.isclose(d1 - d0, 9.375, rel_tol=1e-12)
    assert math.isclose(traj.duration, 10.894671, rel_tol=1e-6)  # the research code's 10.9 s


@pytest.mark.parametrize("ahead", [0.18, 0.25])
def test_twophase_respects_its_limits_and_one_is_active(ahead):
    traj = twophase(docking(ahead), standoff=0.10)
    limits = {"approach": (0.10, 0.20), "docking": (0.02, 0.05)}
    for name, t0, t1 in traj.segments:
        t = np.linspace(t0, t1, 20001)[:-1]
        tab = traj.table(t)
        speed = np.linalg.norm(tab.twist[:, :3], axis=1).max()
        accel = np.linalg.norm(tab.accel[:, :3], axis=1).max()
        v, a = limits[name]
        assert speed <= v * (1 + 1e-9) and accel <= a * (1 + 1e-6)
        assert max(speed / v, accel / a) > 0.999  # the shortest quintic within the limits


def test_twophase_passes_the_pre_dock_point_at_rest():
    wp = docking(0.18, lateral=(0.01, -0.02))
    traj = twophase(wp, standoff=0.10)
    ref = Reference()
    _, _, t_pre = traj.segments[0]
    traj.sample(t_pre, ref)
    assert np.allclose(ref.pos, wp.goal.translation - 0.10 * AXIS, atol=1e-12)
    assert np.allclose(ref.twist, 0.0, atol=1e-12)
    traj.sample(traj.duration + 1.0, ref)
    assert np.allclose(ref.pos, wp.goal.translation, atol=1e-12) and np.allclose(ref.twist, 0.0)


def test_twophase_without_approach_when_the_start_is_within_the_standoff():
    traj = twophase(docking(0.08), standoff=0.10)
    assert [s[0] for s in traj.segments] == ["docking"]
    assert math.isclose(traj.duration, quintic_segment_time(0.08, 0.02, 0.05))
    assert traj.notes and "within the standoff" in traj.notes[0]


def test_twophase_fd_and_orientation_interpolation():
    rot_goal = DOWN @ pin.rpy.rpyToMatrix(0.2, -0.1, 0.3)
    traj = twophase(docking(0.18, rot_goal=rot_goal), standoff=0.10)
    t = np.linspace(0.01, traj.duration - 0.01, 3001)
    e_v, e_w, e_a = fd_check(traj, t)
    assert e_v < 1e-8 and e_w < 1e-8 and e_a < 1e-7
    end = traj.table(np.array([traj.duration]))
    assert np.allclose(end.rot[0], rot_goal, atol=1e-12)


def test_twophase_needs_a_goal():
    with pytest.raises(ValueError, match="needs a goal"):
        twophase(free_space())


# --------------------------------------------------------------------------- se3topp
