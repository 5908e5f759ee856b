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
@pytest.mark.parametrize("planner", ["twophase", "se3topp", "tracking"])
def test_config_defaults_match_the_schema_and_unknown_keys_are_rejected(planner):
    cfg = make_cfg(f"trajectory={planner}")
    node = OmegaConf.to_container(cfg.trajectory)
    assert node["name"] == planner
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
