"""Per-configuration statistics, paired comparisons on common draws, and summary.md's words."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.stats import wilcoxon

from compliant_docking.results import configuration_stats, paired_comparisons, stats
from compliant_docking.results.summary import summary_markdown
from compliant_docking.results.tables import comparison_markdown, comparison_table


def frame(n: int = 10, *, robots=("fr3",), controllers=("impedance", "hqp"), seed: int = 0) -> pd.DataFrame:
    """Jobs as load_runs returns them: every robot × controller over the same n draws (the
    drawn misalignment depends on the seed only). hqp strikes 5 N softer than impedance on
    every draw (plus noise), se3_lie the same as impedance; hqp docks 2 s later and fails
    the last two draws."""
    rng = np.random.default_rng(seed)
    draws = rng.uniform(-0.002, 0.002, size=(n, 2))
    base = rng.uniform(10.0, 30.0, size=n)
    rows = []
    for robot in robots:
        for controller in controllers:
            for s in range(n):
                strike = base[s] - (5.0 if controller == "hqp" else 0.0) + rng.normal(0.0, 0.5)
                docked = not (controller == "hqp" and s >= n - 2)
                rows.append(
                    {
                        "run_dir": f"/x/{robot}_{controller}_{s}",
                        "job": f"{robot}_{controller}_{s}",
                        "status": "ok",
                        "error": None,
                        "success": docked,
                        "robot": robot,
                        "controller": controller,
                        "trajectory": "quintic",
                        "overridden": "robot,controller,task.misalignment.seed",
                        "task.misalignment.seed": s,
                        "misalignment_x_m": draws[s, 0],
                        "misalignment_y_m": draws[s, 1],
                        "misalignment_yaw_deg": 0.0,
                        "misalignment_tilt_deg": 0.0,
                        "peak_axial_force_N": strike,
                        "seated_time_s": 15.0 + (2.0 if controller == "hqp" else 0.0),
                    }
                )
    return pd.DataFrame(rows)


def test_configuration_stats_pool_the_draws_of_each_configuration():
    df = frame(10)
    table = configuration_stats(df)
    assert list(table["configuration"]) == ["impedance", "hqp"]
    imp = table.set_index("configuration").loc["impedance"]
    values = df.loc[df["controller"] == "impedance", "peak_axial_force_N"]
    assert imp["jobs"] == 10 and imp["docked"] == 10 and imp["peak_axial_force_N_n"] == 10
    assert imp["peak_axial_force_N_mean"] == pytest.approx(values.mean())
    assert imp["peak_axial_force_N_median"] == pytest.approx(values.median())
    assert imp["peak_axial_force_N_mean_low"] < values.mean() < imp["peak_axial_force_N_mean_high"]
    hqp = table.set_index("configuration").loc["hqp"]
    assert hqp["success_rate"] == pytest.approx(0.8)
    assert (hqp["success_rate_low"], hqp["success_rate_high"]) == pytest.approx(stats.wilson(8, 10))
    assert np.isnan(imp["pos_tracking_rms_m_mean"])  # a compared metric nobody reported: NaN


def test_paired_comparisons_pair_the_same_draws_and_correct_with_holm():
    df = frame(10, robots=("iiwa14", "fr3"))
    df = df.sample(frac=1.0, random_state=1)  # order must not matter: pairs are by draw
    paired = paired_comparisons(df)
    force = paired[paired["metric"] == "peak_axial_force_N"]
    assert list(force["stratum"]) == list(dict.fromkeys(df["robot"]))  # one per robot
    row = force.iloc[0]
    assert (row["a"], row["b"], row["pairs"], row["n"]) == (df["controller"].iloc[0], row["b"], 10, 10)
    sub = df[df["robot"] == row["stratum"]].sort_values("task.misalignment.seed")
    a = sub.loc[sub["controller"] == row["a"], "peak_axial_force_N"].to_numpy()
    b = sub.loc[sub["controller"] == row["b"], "peak_axial_force_N"].to_numpy()
    assert row["p_value"] == wilcoxon(b - a).pvalue == pytest.approx(2 / 1024)  # every pair agrees
    assert row["p_holm"] == pytest.approx(min(1.0, 2 * row["p_value"]))  # 2 comparisons of this metric
    assert row["significant"] and abs(row["median_difference"]) == pytest.approx(5.0, abs=1.0)
    time_rows = paired[paired["metric"] == "seated_time_s"]  # hqp's 2 undocked draws: no NaN here
    assert (time_rows["n"] == 10).all()
    success = paired[paired["metric"] == "success"].iloc[0]
    assert {success["only_a"], success["only_b"]} == {0, 2} and success["p_value"] == pytest.approx(0.5)
    assert not success["significant"]


def test_a_draw_not_shared_or_repeated_is_not_paired():
    df = frame(6)
    # hqp's draw 0 was a different pose (another range): not the same draw, not a pair
    df.loc[(df["controller"] == "hqp") & (df["task.misalignment.seed"] == 0), "misalignment_x_m"] = 0.5
    # impedance ran draw 1 twice: ambiguous, left out and counted; unpaired: impedance's
    # draw 0, hqp's draws 0 and 1
    twice = df[(df["controller"] == "impedance") & (df["task.misalignment.seed"] == 1)]
    df = pd.concat([df, twice.assign(job="again")], ignore_index=True)
    row = paired_comparisons(df).iloc[0]
    assert row["pairs"] == 4 and row["dropped"] == 2 and row["unpaired"] == 3


def test_no_comparison_without_two_controllers():
    assert paired_comparisons(frame(5, controllers=("hqp",))).empty


def test_summary_says_in_words_what_is_significant_and_what_is_not():
    text = summary_markdown(frame(10, controllers=("impedance", "hqp", "se3_lie")), "t")
    words = text.split("## Paired comparisons", 1)[1].split("### ", 1)[0]
    force = words.split("- **peak axial force (raw, per step) [N]**", 1)[1].split("\n- ", 1)[0].splitlines()
    assert force[0] == ", 3 comparisons: 2 significant at 5 %:"
    assert force[1].startswith("  - hqp − impedance: ") and force[2].startswith("  - se3_lie − hqp: ")
    assert force[3].startswith("  - not significant (1): se3_lie − impedance")  # the same strikes
    success = next(line for line in words.splitlines() if line.startswith("- **success rate [%]**"))
    assert "none significant" in success
    assert "| configuration | jobs | failed | docked | success rate [95 % CI] |" in text.replace("  ", " ")


def test_the_table10_comparison_turns_beyond_six_configurations():
    df = frame(2, robots=("iiwa14", "fr3", "ur5", "ur10"), controllers=("impedance", "hqp"))
    wide = comparison_markdown(comparison_table(df))
    header = next(line for line in wide.splitlines() if line.startswith("| configuration"))
    assert "peak axial force (raw, per step) [N]" in header  # metrics as columns
    rows = [line for line in wide.split("**contact safety**")[1].split("**")[0].splitlines() if "·" in line]
    assert len(rows) == 8  # one row per configuration
    narrow = comparison_markdown(comparison_table(frame(2)))
    assert narrow.splitlines()[0].startswith("| metric") and "impedance" in narrow.splitlines()[0]
