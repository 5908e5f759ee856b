"""The convergence report: jobs paired across one setting, and what is compared, in closed form."""

from __future__ import annotations

import pandas as pd
import pytest

from compliant_docking.results.convergence import FORCE_FLOOR_N, agreement, main, pair_jobs, relative_change


def runs() -> pd.DataFrame:
    """Two robots × 4 draws at timestep 1 ms (a) and 0.5 ms (b), as load_runs returns them.
    At b, fr3's draw 3 flips to docked, every filtered force is 10 % higher, fr3's draw 0
    sinks 0.2 mm deeper; the raw peak doubles. Rows shuffled: pairing must not rely on order."""
    rows = []
    for timestep in (0.001, 0.0005):
        for robot in ("iiwa14", "fr3"):
            for seed in range(4):
                b = timestep == 0.0005
                force = 10.0 + seed
                rows.append(
                    {
                        "job": f"{robot}_{seed}_{timestep}",
                        "status": "ok",
                        "success": not (robot == "fr3" and seed == 3 and not b),
                        "robot": robot,
                        "controller": "impedance",
                        "task.misalignment.seed": seed,
                        "physics.timestep": timestep,
                        "overridden": "robot,task.misalignment.seed" + (",physics.timestep" if b else ""),
                        "filtered_peak_axial_force_N": force * (1.1 if b else 1.0),
                        "peak_axial_force_N": 3 * force * (2.0 if b else 1.0),
                        "seat_depth_error_m": 1e-4 + (2e-4 if (b and robot == "fr3" and seed == 0) else 0.0),
                        "seat_lateral_error_m": 5e-5,
                    }
                )
    return pd.DataFrame(rows).sample(frac=1.0, random_state=3)


def test_jobs_pair_on_every_other_overridden_key():
    pairs = pair_jobs(runs(), "physics.timestep")
    assert pairs.values == ("0.001", "0.0005") or pairs.values == ("0.0005", "0.001")
    assert pairs.keys == ["robot", "task.misalignment.seed"]
    assert len(pairs.frame) == 8
    same = (
        pairs.frame["job_a"].str.rsplit("_", n=1).str[0] == pairs.frame["job_b"].str.rsplit("_", n=1).str[0]
    )
    assert same.all()


def test_agreement_in_closed_form():
    table = agreement(pair_jobs(runs().sort_values("physics.timestep", ascending=False), "physics.timestep"))
    overall = table.loc["all"]
    assert overall["pairs"] == 8
    assert overall["outcome agreement"] == pytest.approx(7 / 8)  # fr3's draw 3 flips
    assert table.loc["fr3", "outcome agreement"] == pytest.approx(3 / 4)
    assert table.loc["iiwa14", "outcome agreement"] == 1.0
    assert overall["max Δ seat_depth_error_m"] == pytest.approx(2e-4)
    assert overall["max Δ seat_lateral_error_m"] == 0.0
    assert overall["median rel. Δ filtered_peak_axial_force_N"] == pytest.approx(0.1)
    assert overall["max rel. Δ filtered_peak_axial_force_N"] == pytest.approx(0.1)
    assert overall["share ≤ 20 % filtered_peak_axial_force_N"] == 1.0
    assert overall["max rel. Δ peak_axial_force_N"] == pytest.approx(1.0)
    assert overall["share ≤ 20 % peak_axial_force_N"] == 0.0


def test_small_forces_change_relative_to_a_one_newton_floor():
    change = relative_change(pd.Series([0.1, 10.0, 2.0]), pd.Series([0.3, 12.0, 1.0]))
    assert FORCE_FLOOR_N == 1.0
    assert list(change) == pytest.approx([0.2, 0.2, 0.5])


def test_setting_that_does_not_pair_is_refused_naming_it():
    with pytest.raises(ValueError, match="no job has that setting"):
        pair_jobs(runs(), "physics.nothing")
    single = runs()
    single["physics.timestep"] = 0.001
    with pytest.raises(ValueError, match="exactly two values"):
        pair_jobs(single, "physics.timestep")


def test_the_command_refuses_a_missing_sweep_in_one_line(tmp_path, capsys):
    assert main([str(tmp_path / "nowhere"), "--vary", "physics.timestep"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("compliant_docking.results.convergence: ") and err.count("\n") == 1
