"""The time series' derived columns: the batched conversions equal Pinocchio's, bit for bit."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.spatial.transform import Rotation

from compliant_docking.sim.telemetry import quaternions_wxyz


def test_batched_quaternions_are_pinocchios_bit_for_bit():
    """Eigen's conversion (pin.Quaternion) has two branches, trace > 0 and not; both are
    hit by random rotations, and the 180° turns about each axis (trace −1) take the
    largest-diagonal choice of the second branch. Equality is exact: the time series is
    bit-identical whether a row is converted alone or in a batch."""
    rots = Rotation.random(4000, random_state=12).as_matrix()
    flips = np.array([np.diag(d) for d in ((1, -1, -1), (-1, 1, -1), (-1, -1, 1))], dtype=float)
    rots = np.concatenate([rots, flips, np.eye(3)[None]])
    trace = np.trace(rots, axis1=1, axis2=2)
    assert (trace > 0).sum() > 1000 and (trace <= 0).sum() > 1000  # both branches
    expected = np.array([np.roll(pin.Quaternion(r).coeffs(), 1) for r in rots])  # xyzw → wxyz
    got = quaternions_wxyz(rots)
    assert got.tobytes() == expected.tobytes()
    assert np.allclose(np.linalg.norm(got, axis=1), 1.0, atol=1e-15)  # unit, to rounding
