"""The bounded reference: a docking planner's reference, slowed so that it never leads the
plug by more than ``trajectory.lead_limit`` along the insertion axis (docs/planners.md).

An open-loop reference keeps moving while the plug sticks (the FR3's joint friction on the
funnel's chamfer): it runs 10-30 mm ahead, and the plug, released, falls onto the seat with
the energy of that stretched spring. Here the planner's time advances with the simulation's
only while the next step of the planned motion stays within ``lead_limit`` of the plug
along the axis; otherwise the reference holds (at rest: zero twist and acceleration) until
the plug catches up. The time scaling is therefore the identity while the plug follows, and
a held plug sees a reference at most ``lead_limit`` ahead.

The press home (:class:`~compliant_docking.planning.base.PressHome`) is an intended lead:
its offset is left out of the lead, so the press is the task's, bounded or not.
"""

from __future__ import annotations

import numpy as np

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import QuinticConfig
from compliant_docking.planning.base import Planner, Reference, ReferenceTable


class LeadLimit:
    """Chooses, step by step, the row of the planned table the controller gets.

    ``planned``: the planner's table of every step (left untouched); ``live``: the table the
    controller and the log read, whose row k is rewritten at step k with the planned row in
    use (twist and acceleration zero while held). ``axial``: the planned motion's coordinate
    along ``axis`` per row, the press offset left out [m]. ``limit`` [m].
    """

    def __init__(
        self, planned: ReferenceTable, live: ReferenceTable, axial: np.ndarray, axis: np.ndarray, limit: float
    ):
        checked = checked_lead_limit(limit)
        if checked is None:
            raise ValueError("LeadLimit needs a trajectory.lead_limit > 0 m (null means no LeadLimit)")
        self.planned, self.live = planned, live
        self.axial = np.asarray(axial, dtype=float).tolist()  # Python floats: a per-step lookup
        u = np.asarray(axis, dtype=float)
        self.axis = tuple((u / np.linalg.norm(u)).tolist())
        self.limit = checked
        self.index = -1  # the planned row in use (none before the first step)
        self.compliant = False  # lateral axes follow the plug (from the first held step on)
        self.held_steps = 0
        self.max_delay = 0.0  # the largest lag of the planner's time behind the run's [steps]

    def row(self, k: int, ref: Reference, tcp: np.ndarray) -> Reference:
        """Point ``ref`` at row k of the live table after choosing it for the TCP position ``tcp``."""
        j = self.index + 1
        if j >= len(self.axial):
            j = len(self.axial) - 1
        elif j > 0:
            u0, u1, u2 = self.axis
            t0, t1, t2 = tcp.tolist()
            ahead = self.axial[j] - (u0 * t0 + u1 * t1 + u2 * t2)
            # hold only a step that moves further along the axis while already too far ahead
            if ahead > self.limit and self.axial[j] > self.axial[j - 1]:
                j -= 1
                self.compliant = True
        self.index, previous = j, self.index
        if j == k and not self.compliant:  # on time: row k of the live table is the planned one
            return self.live.row(k, ref)
        planned, live = self.planned, self.live
        if self.compliant:  # the planned axial position, the plug's lateral one
            p0, p1, p2 = planned.pos[j].tolist()
            u0, u1, u2 = self.axis
            t0, t1, t2 = tcp.tolist()
            gap = u0 * (p0 - t0) + u1 * (p1 - t1) + u2 * (p2 - t2)
            live.pos[k] = (t0 + gap * u0, t1 + gap * u1, t2 + gap * u2)
        else:
            live.pos[k] = planned.pos[j]
        live.rot[k] = planned.rot[j]
        if j == previous:  # held: the reference at rest
            live.twist[k] = 0.0
            live.accel[k] = 0.0
            self.held_steps += 1
            if k - j > self.max_delay:
                self.max_delay = k - j
        else:
            live.twist[k] = planned.twist[j]
            live.accel[k] = planned.accel[j]
        return live.row(k, ref)

    def diagnostics(self, dt: float) -> dict:
        return {
            "reference_held_steps": self.held_steps,
            "reference_max_delay_s": self.max_delay * dt,
        }


def checked_lead_limit(limit: float | None) -> float | None:
    """``trajectory.lead_limit`` as a float (None: off); raises ValueError outside the
    schema's range (> 0 m), in the config check's words."""
    require(QuinticConfig, "trajectory", lead_limit=limit)
    return None if limit is None else float(limit)


def bounded(planner: Planner, table: ReferenceTable, axis: np.ndarray) -> LeadLimit | None:
    """The lead limit of ``planner`` over its ``table`` (None when the planner has none):
    ``table`` becomes the live table; the planned one is a copy."""
    if planner.lead_limit is None:
        return None
    axial = (table.pos - planner.intended_lead(table.t)).dot(
        np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    )
    return LeadLimit(copy_table(table), table, axial, axis, planner.lead_limit)


def copy_table(table: ReferenceTable) -> ReferenceTable:
    """An independent copy of ``table`` (its arrays copied)."""
    return ReferenceTable(
        t=table.t.copy(),
        pos=table.pos.copy(),
        rot=table.rot.copy(),
        twist=table.twist.copy(),
        accel=table.accel.copy(),
    )
