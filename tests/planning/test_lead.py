"""The bounded reference (planning/lead.py, docs/planners.md): in closed form, the lead over
a held plug stays within the limit, the time scaling is the identity while the plug follows,
the press is not counted as lead, and with the limit off the reference is the planner's."""

import numpy as np
import pinocchio as pin
import pytest

from compliant_docking.planning.base import PressHome, Reference, Waypoints
from compliant_docking.planning.lead import LeadLimit, bounded, copy_table
from compliant_docking.planning.quintic import QuinticPlanner
from compliant_docking.sim.simulate import prepare
from tests.helpers import make_cfg

AXIS = np.array([0.0, 0.0, -1.0])
DT = 0.001
START = pin.SE3(np.eye(3), np.array([0.5, 0.0, 0.30]))
GOAL = pin.SE3(np.eye(3), np.array([0.5, 0.0, 0.20]))  # 0.10 m down the axis


def planner(limit, duration=1.0):
    return QuinticPlanner(Waypoints(START, GOAL, AXIS), duration=duration, name="quintic", lead_limit=limit)


def steps(lead, table, plug, n):
    """Run the lead limit for n steps with the plug at plug(k) (a position) each step."""
    ref = Reference()
    for k in range(n):
        lead.row(k, ref, plug(k))
    return table


def test_the_lead_over_a_held_plug_stays_within_the_limit():
    p = planner(0.004)
    table = p.table(np.arange(1500) * DT)
    planned = copy_table(table)
    lead = bounded(p, table, AXIS)
    held = np.array([0.5005, 0.0, 0.27])  # stuck 30 mm down, 0.5 mm to the side
    steps(lead, table, lambda k: held, 1500)
    ahead = (table.pos - held) @ AXIS
    assert ahead.max() <= 0.004 + 1e-12  # never more than the limit ahead
    step = np.abs(np.diff(planned.pos @ AXIS)).max()
    assert ahead.max() > 0.004 - step  # and it gets there (within one planned step)
    held_rows = np.flatnonzero(np.all(table.twist[1:] == 0.0, axis=1)) + 1  # row 0 is at rest
    assert held_rows.size > 1000 and lead.held_steps == held_rows.size
    first = held_rows[0]
    assert np.array_equal(held_rows, np.arange(first, 1500))  # held for good: the plug stays
    # before the hold the reference is the planned one, row for row
    assert np.array_equal(table.pos[:first], planned.pos[:first])
    # from the first held step on, the lateral reference is the plug's (lateral axes compliant)
    assert np.allclose(table.pos[first:, :2], held[:2])


def test_the_time_scaling_is_the_identity_while_the_plug_follows():
    p = planner(0.004)
    table = p.table(np.arange(1500) * DT)
    planned = copy_table(table)
    lead = bounded(p, table, AXIS)
    steps(lead, table, lambda k: planned.pos[k], 1500)  # the plug exactly on the reference
    for name in ("pos", "rot", "twist", "accel"):
        assert np.array_equal(getattr(table, name), getattr(planned, name))
    assert lead.held_steps == 0 and lead.diagnostics(DT)["reference_max_delay_s"] == 0.0


def test_a_plan_that_does_not_advance_along_the_axis_is_never_held():
    """Holding only helps while the plan moves into the socket: a sideways plan (constant
    axial coordinate) runs row for row even with the plug stuck 10 mm behind it."""
    sideways = pin.SE3(np.eye(3), START.translation + np.array([0.0, 0.05, 0.0]))
    p = QuinticPlanner(Waypoints(START, sideways, AXIS), duration=1.0, name="quintic", lead_limit=0.004)
    table = p.table(np.arange(1500) * DT)
    planned = copy_table(table)
    lead = bounded(p, table, AXIS)
    stuck = START.translation - 0.010 * AXIS  # 10 mm behind the plan along the axis
    steps(lead, table, lambda k: stuck, 1500)
    assert np.array_equal(table.pos, planned.pos) and lead.held_steps == 0


def test_the_press_is_not_counted_as_lead():
    """A plug at the seat: the press home moves the reference 5 mm past it, unbounded."""
    p = PressHome(planner(0.002), 0.005 * AXIS, 0.5)
    table = p.table(np.arange(2000) * DT)
    planned = copy_table(table)
    lead = bounded(p, table, AXIS)
    steps(lead, table, lambda k: planned.pos[k] - p.intended_lead(planned.t[k : k + 1])[0], 2000)
    assert np.array_equal(table.pos, planned.pos)
    assert (table.pos[-1] - GOAL.translation) @ AXIS == pytest.approx(0.005)


def test_off_the_reference_is_the_planners():
    """trajectory.lead_limit=null: no lead limit, the loop reads the planner's table."""
    sim = prepare(
        make_cfg(
            "trajectory.lead_limit=null",
            "trajectory.duration=0.2",
            "task.settle_time=0.1",
            "task.press_duration=0.1",
        )
    )
    sim.start()
    assert sim.lead is None
    planned = sim.planner.table(np.arange(sim.n_steps) * sim.scene.model.opt.timestep)
    sim.advance(sim.n_steps)
    for name in ("pos", "rot", "twist", "accel"):
        assert np.array_equal(getattr(sim.reference, name), getattr(planned, name))


def test_a_lead_limit_must_be_positive():
    with pytest.raises(
        ValueError, match=r"^trajectory\.lead_limit must be a finite number > 0 m; got 0\.0\.$"
    ):
        planner(0.0)
    with pytest.raises(ValueError, match="lead_limit"):
        LeadLimit(*(2 * [planner(None).table(np.zeros(2))]), np.zeros(2), AXIS, -1.0)
