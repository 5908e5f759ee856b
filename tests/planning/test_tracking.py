"""The free-space tracking planner: segments, smoothness, derivatives."""

import numpy as np
import pytest

from tests.planning.cases import docking, fd_check, free_space, tracking


def test_tracking_segments_and_geometry():
    wp = free_space()
    traj = tracking(wp)
    names = [s[0] for s in traj.segments]
    assert names == ["transition_1", "circle", "transition_2", "figure8"]
    bounds = [(s[1], s[2]) for s in traj.segments]
    assert np.allclose(bounds, [(0, 1.5), (1.5, 6.5), (6.5, 8.0), (8.0, 13.0)])
    assert traj.duration == 13.0
    p0 = wp.start.translation
    circle = traj.table(np.linspace(1.5, 6.5, 2001))
    centre = p0 + np.array([0.0, 0.0, -0.06])
    assert np.allclose(np.linalg.norm(circle.pos - centre, axis=1), 0.10, atol=1e-12)
    assert np.allclose(circle.pos[:, 0], p0[0])  # vertical circle in the y-z plane
    assert np.isclose(circle.pos[:, 1].max(), p0[1] + 0.10, atol=1e-6)
    eight = traj.table(np.linspace(8.0, 13.0, 20001))
    assert np.allclose(eight.pos[:, 2], p0[2])  # horizontal
    assert np.isclose(np.abs(eight.pos[:, 0] - p0[0]).max(), 0.10, atol=1e-6)
    assert np.isclose(np.abs(eight.pos[:, 1] - p0[1]).max(), 0.07, atol=1e-6)
    assert np.allclose(traj.table(np.array([13.0, 20.0])).pos, p0, atol=1e-12)  # ends at the start
    assert np.allclose(traj.table(np.linspace(0, 20, 50)).rot, wp.start.rotation)  # orientation held


def test_tracking_is_c2_across_segment_joints():
    traj = tracking(free_space())
    eps = 1e-7
    for _, _, t_end in traj.segments:
        tab = traj.table(np.array([t_end - eps, t_end, t_end + eps]))
        for block, tol in ((tab.pos, 1e-9), (tab.twist, 1e-6), (tab.accel, 1e-5)):
            assert np.abs(block[0] - block[1]).max() < tol and np.abs(block[2] - block[1]).max() < tol
        assert np.allclose(tab.twist[1], 0.0, atol=1e-12) and np.allclose(tab.accel[1], 0.0, atol=1e-12)


def test_tracking_twist_and_accel_are_derivatives():
    traj = tracking(free_space())
    t = np.linspace(0.0, 15.0, 6001)
    e_v, e_w, e_a = fd_check(traj, t)
    assert e_v < 1e-8 and e_w < 1e-9 and e_a < 1e-6


def test_tracking_refuses_a_target():
    with pytest.raises(ValueError, match="target=none"):
        tracking(docking())


# --------------------------------------------------------------------------- all planners
