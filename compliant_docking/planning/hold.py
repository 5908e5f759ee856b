"""``trajectory=hold``: hold the start pose (push tests, compliance identification)."""

from __future__ import annotations

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import HoldConfig
from compliant_docking.planning.base import Planner, Reference, Waypoints


class HoldPlanner(Planner):
    def __init__(self, waypoints: Waypoints, *, duration: float, name: str):
        require(HoldConfig, "trajectory", duration=duration)  # the schema's range
        self.duration = float(duration)
        self._pos = waypoints.start.translation.copy()
        self._rot = waypoints.start.rotation.copy()

    def sample(self, t: float, ref: Reference) -> None:
        ref.pos[:] = self._pos
        ref.rot[:] = self._rot
        ref.twist[:] = 0.0
        ref.accel[:] = 0.0
