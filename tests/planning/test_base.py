"""What every planner shares: the table equals the samples, typed configs, planned durations."""

import math

import numpy as np
import pytest
from omegaconf import OmegaConf

from compliant_docking.planning.base import Reference
from tests.helpers import make_cfg
from tests.planning.cases import docking, free_space, rotating_case, se3topp, tracking, twophase


@pytest.mark.parametrize(
    "make",
    [
        lambda: twophase(docking(0.18)),
        lambda: se3topp(rotating_case()),
        lambda: tracking(free_space()),
    ],
    ids=["twophase", "se3topp", "tracking"],
)
def test_table_equals_sample(make):
    traj = make()
    t = np.concatenate([[-1.0, 0.0], np.linspace(0.0, traj.duration + 1.0, 37), [traj.duration]])
    table, ref = traj.table(t), Reference()
    for k, tk in enumerate(t):
        traj.sample(float(tk), ref)
        assert np.array_equal(table.pos[k], ref.pos) and np.array_equal(table.rot[k], ref.rot)
        assert np.array_equal(table.twist[k], ref.twist) and np.array_equal(table.accel[k], ref.accel)


# --------------------------------------------------------------------------- configs
#: each planner's defaults as docs/control_laws.md §4 states them (Table 8 for se3topp), and
#: the docking planners' bound on the reference's lead (docs/planners.md)
SPEC_DEFAULTS = {
    "quintic": dict(duration=15.0, lead_limit=0.012),
    "twophase": dict(
        standoff=0.10,
        v_max_approach=0.10,
        a_max_approach=0.20,
        v_max_docking=0.02,
        a_max_docking=0.05,
        lead_limit=0.012,
    ),
    "se3topp": dict(
        standoff=0.10,
        v_max_approach=0.10,
        a_max_approach=0.20,
        omega_max_approach=0.20,
        alpha_max_approach=0.20,
        v_max_docking=0.02,
        a_max_docking=0.05,
        omega_max_docking=0.05,
        alpha_max_docking=0.05,
        lead_limit=0.012,
    ),
    "tracking": dict(
        transition_duration=1.5,
        circle_duration=5.0,
        circle_radius=0.10,
        circle_frequency=0.2,
        circle_center_offset=-0.06,
        figure8_duration=5.0,
        figure8_radius_x=0.10,
        figure8_radius_y=0.07,
        figure8_frequency=0.2,
    ),
}


@pytest.mark.parametrize("planner", SPEC_DEFAULTS)
def test_composed_defaults_are_the_specified_values_and_unknown_keys_are_rejected(planner):
    """Every parameter the planner takes comes from its YAML with the value of the spec."""
    node = OmegaConf.to_container(make_cfg(f"trajectory={planner}").trajectory, resolve=True)
    assert node.pop("name") == planner and node.pop("_target_").endswith("Planner")
    assert node == SPEC_DEFAULTS[planner]
    with pytest.raises(Exception, match="bogus"):
        make_cfg(f"trajectory={planner}", "trajectory.bogus=1")


def test_planned_durations_on_the_default_scene():
    from compliant_docking.sim.simulate import prepare

    two = prepare(make_cfg("trajectory=twophase")).planner
    topp = prepare(make_cfg("trajectory=se3topp")).planner
    # the default scene is the research code's iiwa14 case: start 0.18 m before the seat,
    # goal at the seat (the press past it comes after the motion), standoff 0.10 m:
    # approach 0.08 m, docking 0.10 m → twophase 1.52 + 9.375 s, se3topp 1.3 + 5.4 s
    assert math.isclose(two.duration, 1.52 + 9.375, rel_tol=1e-3)
    # approach in s-units: v = 0.1/0.08 = 1.25, a = 0.2/0.08 = 2.5, √a > v: trapezoid 1/v + v/a
    assert math.isclose(topp.duration, (1 / 1.25 + 1.25 / 2.5) + 5.4, rel_tol=1e-9)
    assert topp.duration < two.duration


# --------------------------------------------------------------------------- end to end
