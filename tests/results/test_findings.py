"""docs/findings.md's generator on synthetic sweeps whose answer is known."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.stats import wilcoxon

from compliant_docking.results.findings import findings_markdown, main, pairs
from tests.helpers import REPO_ROOT
from tests.results.test_compare import frame


def sweep(n: int = 12, *, effect: bool = True):
    """The frame of test_compare (hqp strikes 5 N softer on every draw, fails the last two)
    with the first-strike column; ``effect=False``: hqp strikes as impedance does."""
    df = frame(n, robots=("fr3", "iiwa14"), controllers=("impedance", "hqp", "se3_lie"))
    if not effect:
        imp = df[df["controller"] == "impedance"].set_index(["robot", "task.misalignment.seed"])
        is_hqp = df["controller"] == "hqp"
        keys = list(zip(df.loc[is_hqp, "robot"], df.loc[is_hqp, "task.misalignment.seed"]))
        df.loc[is_hqp, "peak_axial_force_N"] = imp.loc[keys, "peak_axial_force_N"].to_numpy() + 1e-3 * np.sin(
            np.arange(is_hqp.sum())
        )
    df["first_strike_force_N"] = df["peak_axial_force_N"] * 0.5
    df["filtered_peak_axial_force_N"] = df["peak_axial_force_N"] * 0.2
    df["git_commit"], df["git_dirty"] = "abc123", False
    return df


def test_pairs_join_the_same_draw_of_the_two_controllers():
    df = sweep(8)
    merged = pairs(df[df["robot"] == "fr3"], "impedance", "hqp")
    assert len(merged) == 8  # one pair per draw, the other robot and se3_lie left out
    assert (merged["task.misalignment.seed_a"] == merged["task.misalignment.seed_b"]).all()


def test_a_real_reduction_is_found_with_its_interval_and_scipys_p(tmp_path):
    df = sweep(12)
    text = findings_markdown(df, tmp_path, command="python -m compliant_docking.results.findings X")
    fr3 = df[df["robot"] == "fr3"]
    a = fr3.loc[fr3["controller"] == "impedance", "first_strike_force_N"].to_numpy()
    b = fr3.loc[fr3["controller"] == "hqp", "first_strike_force_N"].to_numpy()
    p = wilcoxon(b - a).pvalue  # 12 pairs all lower: the exact p = 2/2^12
    assert p == pytest.approx(2 / 4096)
    answer = text.split("## Design")[0]
    # first strike: lower with hqp, median paired difference about −2.5 N (half of −5 ± noise)
    assert "**First strike**: lower with hqp" in answer and f"p = {p:.2g}," in answer
    assert (
        "**Cost in success**: 100 % docked with impedance, 83 % with hqp (2 draws only impedance docked, 0 only hqp; McNemar p = 0.5)"
        in answer
    )
    assert "`abc123` (72 jobs) (clean tree)" in text and "results.findings X" in text


def test_no_effect_is_said_to_be_no_significant_difference(tmp_path):
    # 8 draws, not 12: the verdicts are the same, and scipy's exact Wilcoxon on 12 draws with
    # no effect costs 10 s (its exact null distribution, not this module's work)
    text = findings_markdown(sweep(8, effect=False), tmp_path)
    assert "**First strike**: no significant difference" in text
    assert "**Peak axial force** (raw, per step): no significant difference" in text
    assert (
        "**Filtered peak force** (the " in text and "docking gate judges): no significant difference" in text
    )
    assert "**not reproduced**" in text  # −81 % lies far outside an interval around 0


def test_the_fr3_docking_time_carries_its_timestep_caveat(tmp_path):
    """The FR3's docking-time difference is not converged in the timestep (docs/contact.md,
    "Convergence"): the answer says so beside the number, and only for the FR3."""
    df = sweep(12)
    answer = findings_markdown(df, tmp_path).split("## Design")[0]
    _, caveat = answer.split("**Cost in docking time**")[1].split("\n")[:2]
    assert "not converged in the timestep" in caveat and "p 0.75" in caveat
    assert "0.5–0.9 s" in caveat and "docs/contact.md" in caveat
    iiwa = findings_markdown(df, tmp_path, robot="iiwa14").split("## Design")[0]
    assert "not converged in the timestep" not in iiwa


def test_the_command_refuses_a_sweep_without_the_controllers(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    with pytest.raises(SystemExit):
        main([str(tmp_path / "empty")])
    assert "no finished jobs" in capsys.readouterr().err


def test_the_sensitivity_section_puts_the_verdicts_and_cells_side_by_side(tmp_path):
    """Before: no effect; after: hqp 5 N softer. The section says the verdict changed and
    gives every cell's success and medians before → after."""
    from compliant_docking.results.findings import sensitivity_markdown

    before, after = sweep(8, effect=False), sweep(8)  # 8 draws: see the test above
    after.loc[(after["controller"] == "impedance") & (after["task.misalignment.seed"] == 0), "success"] = (
        False
    )
    text = "\n".join(sensitivity_markdown(before, after, tmp_path, "fr3", "impedance", "hqp"))
    rows = {line.split("|")[1].strip() + line.split("|")[2].strip(): line for line in text.splitlines()
            if line.startswith("| before") or line.startswith("| after")}  # fmt: skip
    assert rows["beforefirst-strike force"].rstrip("| ").endswith("no")
    assert rows["afterfirst-strike force"].rstrip("| ").endswith("yes")
    imp = after[(after["robot"] == "fr3") & (after["controller"] == "impedance")]
    median = float(imp["filtered_peak_axial_force_N"].median())
    cell = next(line for line in text.splitlines() if line.startswith("| impedance"))
    assert "8/8 → 7/8" in cell and f"→ {median:.3g}" in cell


def test_the_command_writes_beside_the_sweep_and_the_docs_only_when_asked(tmp_path, monkeypatch, capsys):
    """Before: the README's command rewrote the tracked docs/findings.md, which flipped
    ``git_dirty`` in every later run's provenance."""
    from compliant_docking.results import findings

    sweep = tmp_path / "sweep"
    sweep.mkdir()
    frame = pd.DataFrame({"robot": ["fr3"], "controller": ["hqp"], "trajectory": ["quintic"]})
    monkeypatch.setattr(findings, "load_runs", lambda path: frame)
    monkeypatch.setattr(findings, "findings_markdown", lambda *args: "# the finding\n")
    written: dict = {}
    monkeypatch.setattr(
        "compliant_docking.run.files.atomic_write_text", lambda path, text: written.update({Path(path): text})
    )
    assert main([str(sweep)]) == 0
    assert written == {sweep / "findings.md": "# the finding\n"}
    mine = tmp_path / "mine" / "findings.md"
    assert main([str(sweep), "--out", str(mine)]) == 0 and mine in written
    capsys.readouterr()
    assert main([str(sweep), "--out", "-"]) == 0 and capsys.readouterr().out == "# the finding\n\n"
    assert main([str(sweep), "--docs"]) == 0
    assert REPO_ROOT / "docs" / "findings.md" in written and len(written) == 3
