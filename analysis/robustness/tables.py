"""The tables of docs/robustness.md from a robustness sweep (+experiment=robustness).

    python analysis/robustness/tables.py runs/multirun/<date>/<time>_robustness

Prints markdown: the success rate per controller and condition (sensor × model) with its
Wilson 95 % interval, pooled over the robots and per robot; the paired differences
(same robot, condition and seed) of the success (McNemar), the filtered peak force and
the docking time (Wilcoxon, median difference with its bootstrap interval) for what the
observer buys (hqp_observer − hqp) and for what each condition costs each controller
(condition − exact); and the success against the drawn errors' size.
"""

from __future__ import annotations

import sys

import pandas as pd

from compliant_docking.results import load_runs
from compliant_docking.results.stats import mcnemar, paired, wilson

CONDITIONS = [("ideal", "none"), ("wrist_ft", "none"), ("ideal", "drawn"), ("wrist_ft", "drawn")]
CONDITION_NAMES = {
    ("ideal", "none"): "exact",
    ("wrist_ft", "none"): "wrist F/T",
    ("ideal", "drawn"): "model error",
    ("wrist_ft", "drawn"): "both",
}
METRICS = [
    ("filtered_peak_axial_force_N", "filtered peak force [N]", 1.0),
    ("docking_time_s", "docking time [s]", 1.0),  # seated and staying seated (run_directory.md)
]


def rate(rows: pd.DataFrame) -> str:
    k, n = int((rows["success"] == True).sum()), len(rows)  # noqa: E712
    if n == 0:
        return "–"
    low, high = wilson(k, n)
    return f"{k}/{n} = {100 * k / n:.0f} % [{100 * low:.0f}, {100 * high:.0f}]"


def success_table(df: pd.DataFrame, robots: list[str] | None) -> str:
    controllers = list(dict.fromkeys(df["controller"]))
    head = "| controller | " + " | ".join(CONDITION_NAMES[c] for c in CONDITIONS) + " |"
    lines = [head, "|---" * (len(CONDITIONS) + 1) + "|"]
    for controller in controllers:
        cells = []
        for sensor, model in CONDITIONS:
            sel = (df["controller"] == controller) & (df["sensor"] == sensor) & (df["model_error"] == model)
            if robots:
                sel &= df["robot"].isin(robots)
            cells.append(rate(df[sel]))
        lines.append(f"| {controller} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def pairs(df: pd.DataFrame, a: pd.Series, b: pd.Series) -> tuple[pd.DataFrame, pd.DataFrame]:
    keys = ["robot", "seed"]
    left = df[a].set_index(keys)
    right = df[b].set_index(keys)
    common = left.index.intersection(right.index)
    return left.loc[common], right.loc[common]


def compare(df: pd.DataFrame, a: pd.Series, b: pd.Series, name: str) -> str:
    left, right = pairs(df, a, b)
    docked_a, docked_b = (left["success"] == True).to_numpy(), (right["success"] == True).to_numpy()  # noqa: E712
    only_a, only_b, p = mcnemar(docked_a, docked_b)
    cells = [
        name,
        str(len(left)),
        f"{docked_a.mean() * 100:.0f} → {docked_b.mean() * 100:.0f} % ({only_a}/{only_b}, p = {p:.3g})",
    ]
    for key, _, scale in METRICS:
        result = paired(
            pd.to_numeric(left[key], errors="coerce"), pd.to_numeric(right[key], errors="coerce"), name + key
        )
        if result.n < 2:
            cells.append("–")
            continue
        cells.append(
            f"{result.median_difference * scale:+.2f} [{result.difference_low * scale:+.2f}, "
            f"{result.difference_high * scale:+.2f}] (n = {result.n}, p = {result.p_value:.3g})"
        )
    return "| " + " | ".join(cells) + " |"


def main(path: str) -> None:
    df = load_runs(path)
    df["seed"] = df["task.misalignment.seed"]
    for key in ("sensor", "model_error"):
        df[key] = df[key].fillna("ideal" if key == "sensor" else "none")
    print(f"{len(df)} jobs; {int((df['status'] == 'ok').sum())} finished ok\n")
    print("### Success rate (Wilson 95 % interval), both robots\n")
    print(success_table(df, None))
    for robot in dict.fromkeys(df["robot"]):
        print(f"\n### Success rate, {robot}\n")
        print(success_table(df, [robot]))
    head = (
        "| comparison (b − a) | pairs | success a → b (only a / only b, McNemar p) | "
        + " | ".join(f"{label}: median difference [95 % CI]" for _, label, _ in METRICS)
        + " |"
    )
    rule = "|---" * (3 + len(METRICS)) + "|"
    print("\n### What the observer buys: hqp_observer − hqp (same robot, condition, seed)\n")
    print(head + "\n" + rule)
    for sensor, model in CONDITIONS:
        cond = (df["sensor"] == sensor) & (df["model_error"] == model)
        print(
            compare(
                df,
                cond & (df["controller"] == "hqp"),
                cond & (df["controller"] == "hqp_observer"),
                CONDITION_NAMES[(sensor, model)],
            )
        )
    print("\n### What each condition costs: condition − exact (same controller, robot, seed)\n")
    print(head + "\n" + rule)
    exact = (df["sensor"] == "ideal") & (df["model_error"] == "none")
    for controller in dict.fromkeys(df["controller"]):
        mine = df["controller"] == controller
        for sensor, model in CONDITIONS[1:]:
            cond = (df["sensor"] == sensor) & (df["model_error"] == model)
            print(compare(df, mine & exact, mine & cond, f"{controller}: {CONDITION_NAMES[(sensor, model)]}"))
    print("\n### Failures: the gate's first reason, per controller and condition\n")
    failed = df[df["success"] != True]  # noqa: E712
    reasons = failed["gate_failures"].fillna(failed["error"]).fillna("?").str.split(":").str[0]
    table = failed.assign(reason=reasons).groupby(["controller", "sensor", "model_error", "reason"]).size()
    print(table.to_string())


if __name__ == "__main__":
    main(sys.argv[1])
