"""``trajectory=quintic``: rest-to-rest quintic from the start to the goal position.

The orientation is held at the start orientation (docs/control_laws.md §4).
"""

from __future__ import annotations

import numpy as np

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import QuinticConfig
from compliant_docking.planning.base import (
    Planner,
    ReferenceTable,
    Waypoints,
    quintic_scaling,
)


class QuinticPlanner(Planner):
    def __init__(self, waypoints: Waypoints, *, duration: float, name: str, lead_limit: float | None):
        if waypoints.goal is None:
            raise ValueError(
                "trajectory=quintic needs a goal (a target); with target=none use trajectory=tracking"
            )
        require(QuinticConfig, "trajectory", duration=duration, lead_limit=lead_limit)  # the schema's ranges
        self.duration = float(duration)
        self.lead_limit = None if lead_limit is None else float(lead_limit)
        self._start = waypoints.start.translation.copy()
        self._delta = waypoints.goal.translation - self._start
        self._rot = waypoints.start.rotation.copy()

    def table(self, t: np.ndarray) -> ReferenceTable:
        T = self.duration
        t = np.asarray(t, dtype=float)
        s, ds, dds = quintic_scaling(t / T)
        n = len(t)
        twist, accel = np.zeros((n, 6)), np.zeros((n, 6))
        twist[:, :3] = np.outer(ds / T, self._delta)
        accel[:, :3] = np.outer(dds / T**2, self._delta)
        return ReferenceTable(
            t=t,
            pos=self._start + np.outer(s, self._delta),
            rot=np.broadcast_to(self._rot, (n, 3, 3)).copy(),
            twist=twist,
            accel=accel,
        )
