"""The comparison presets repeat every cell over the same N misalignment draws (common random
numbers), in both signs along x and y, with N large enough for a paired test to reach 5 %
after Holm's correction over the preset's comparisons."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import yaml

from compliant_docking import CONF_DIR
from compliant_docking.sim.misalignment import Misalignment
from compliant_docking.sim.misalignment import draw as draw_settings
from compliant_docking.sim.settings import sim_settings
from tests.helpers import make_cfg, misalignment


def draw(given: dict) -> Misalignment:
    """The draw of ``task.misalignment`` set to ``given``."""
    return draw_settings(misalignment(**given))


def preset(name: str) -> tuple[dict, dict]:
    """(the swept lists, the task.misalignment settings) of conf/experiment/<name>.yaml."""
    data = yaml.safe_load((CONF_DIR / "experiment" / f"{name}.yaml").read_text())
    params = {k: str(v) for k, v in data["hydra"]["sweeper"]["params"].items()}
    return params, data["task"]["misalignment"]


def draws_of(params: dict) -> int:
    text = params["task.misalignment.seed"]
    assert text.startswith("range(") and text.endswith(")"), text
    return len(range(*map(int, text[6:-1].split(","))))


@pytest.mark.parametrize("name", ["controller_comparison", "misalignment", "clearance"])
def test_presets_repeat_each_cell_over_draws_in_both_signs(name):
    params, settings = preset(name)
    n = draws_of(params)
    for axis in ("x_range", "y_range"):
        low, high = settings[axis]
        assert low == -high < 0  # both signs, symmetric
    assert settings["tilt_deg_range"][0] == 0.0 < settings["tilt_deg_range"][1]
    drawn = [draw({**settings, "seed": s}) for s in range(n)]
    xs, ys = np.array([d.x for d in drawn]), np.array([d.y for d in drawn])
    assert (xs > 0).any() and (xs < 0).any() and (ys > 0).any() and (ys < 0).any()
    assert len({round(d.tilt_deg, 9) for d in drawn}) == n  # N distinct poses, not a grid of 4
    # room for significance: the exact signed-rank test's smallest two-sided p, 2/2^N, must
    # pass Holm's first threshold 0.05/m over the m controller pairs × strata of a metric
    controllers = params["controller"].split(",")
    strata = math.prod(
        len(v.split(",")) for k, v in params.items() if k not in ("controller", "task.misalignment.seed")
    )
    comparisons = strata * math.comb(len(controllers), 2)
    assert 2 / 2**n <= 0.05 / comparisons, (n, comparisons)


def test_every_controller_robot_and_planner_docks_into_the_same_sockets():
    """The composed configs of every cell of controller_comparison draw the same poses for
    the same seed: the draw depends on the seed and the ranges only."""
    params, _ = preset("controller_comparison")
    lists = {k: params[k].split(",") for k in ("controller", "robot", "trajectory")}
    # each value of each group once (the groups' files are what could set a pose)
    cells = {(c, lists["robot"][0], lists["trajectory"][0]) for c in lists["controller"]}
    cells |= {(lists["controller"][1], r, t) for r in lists["robot"] for t in lists["trajectory"]}
    # each cell composed once: the seed is the command line's override, which no group file
    # can change, so the composed misalignment with its seed set to each value is what a
    # composition with that seed gives
    composed = [
        sim_settings(
            make_cfg(
                "+experiment=controller_comparison",
                f"controller={controller}",
                f"robot={robot}",
                f"trajectory={trajectory}",
                "task.misalignment.seed=0",
            )
        ).task.misalignment
        for controller, robot, trajectory in sorted(cells)
    ]
    for seed in (0, 7):
        poses = set()
        for cell in composed:
            poses.add(draw_settings(dataclasses.replace(cell, seed=seed)))
        assert len(poses) == 1, poses
        [pose] = poses
        assert pose == draw({**preset("controller_comparison")[1], "seed": seed})


def test_the_jamming_map_tiles_its_plane_with_enough_draws_per_cell():
    """The cells tile x ∈ [−6, 6] mm × tilt ∈ [0, 5]° edge to edge; every Wilson 95 %
    interval of N draws is at most ±10 % whatever the count docked; each job's draw lies in
    its cell, in the plane (y = 0, the tilt leaning towards +x: yaw 90°)."""
    from compliant_docking.results.stats import wilson

    params, settings = preset("jamming_map")
    assert set(params["robot"].split(",")) == {"iiwa14", "fr3"}
    assert set(params["controller"].split(",")) == {"impedance", "hqp", "se3_lie"}
    cells = {}
    for key, span in (
        ("task.misalignment.x_range", (-0.006, 0.006)),
        ("task.misalignment.tilt_deg_range", (0, 5)),
    ):
        bounds = yaml.safe_load("[" + params[key] + "]")
        assert bounds[0][0] == span[0] and bounds[-1][1] == span[1]
        assert all(a[1] == b[0] for a, b in zip(bounds, bounds[1:]))  # no gap, no overlap
        cells[key] = bounds
    n = draws_of(params)
    assert max((hi - lo) / 2 for lo, hi in (wilson(k, n) for k in range(n + 1))) <= 0.10
    assert max((hi - lo) / 2 for lo, hi in (wilson(k, n - 1) for k in range(n))) > 0.10  # N is the least
    assert (settings["y"], settings["yaw_deg"]) == (0.0, 90.0)
    for x_range in (cells["task.misalignment.x_range"][0], cells["task.misalignment.x_range"][-1]):
        for seed in (0, n - 1):
            d = draw({**settings, "x_range": x_range, "tilt_deg_range": [4.0, 5.0], "seed": seed})
            assert x_range[0] <= d.x <= x_range[1] and 4.0 <= d.tilt_deg <= 5.0 and d.y == 0.0
