"""comparison_table at sweep scale: the pandas groupby against the per-configuration loop
it replaced (kept here as the reference), on a synthetic sweep of ``--jobs`` jobs.

    python benchmarks/comparison_table.py                 # 600 jobs, 60 configurations
    python benchmarks/comparison_table.py --jobs 600 --configs 600

Both tables must be equal (to round-off of the means); the script prints each one's
best time of ``--repeats`` and the ratio.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from compliant_docking.evaluation.registry import compared
from compliant_docking.results.tables import SUCCESS_SECTION, comparison_table, configuration_labels


def loop_table(df: pd.DataFrame, keys=None) -> pd.DataFrame:
    """The implementation before the groupby: one boolean selection per configuration."""
    labels = configuration_labels(df, keys)
    order = list(dict.fromkeys(labels))
    index = pd.MultiIndex.from_tuples(
        [(m.section, m.heading) for m in compared()]
        + [(SUCCESS_SECTION, name) for name in ("jobs", "failed", "docked", "success rate")],
        names=["section", "metric"],
    )
    table = pd.DataFrame(index=index, columns=order, dtype=float)
    for name in order:
        group = df[labels == name]
        for row in compared():
            values = pd.to_numeric(group.get(row.key), errors="coerce") if row.key in group else None
            mean = values.mean() if values is not None and values.notna().any() else np.nan
            table.loc[(row.section, row.heading), name] = mean * row.scale
        docked = int((group["success"] == True).sum()) if "success" in group else 0  # noqa: E712
        table.loc[(SUCCESS_SECTION, "jobs"), name] = len(group)
        table.loc[(SUCCESS_SECTION, "failed"), name] = int((group["status"] == "failed").sum())
        table.loc[(SUCCESS_SECTION, "docked"), name] = docked
        table.loc[(SUCCESS_SECTION, "success rate"), name] = docked / len(group) if len(group) else np.nan
    return table


def synthetic_sweep(jobs: int, configs: int, seed: int = 0) -> pd.DataFrame:
    """``jobs`` rows as load_runs returns them: ``configs`` configurations (controller ×
    controller.k), repeats over a seed, some failed jobs, every compared metric."""
    rng = np.random.default_rng(seed)
    config = np.arange(jobs) % configs
    df = pd.DataFrame(
        {
            "job": [f"{i}_job" for i in range(jobs)],
            "robot": "iiwa14",
            "controller": np.array(["impedance", "hqp", "se3_lie"])[config % 3],
            "trajectory": "quintic",
            "controller.k": 50.0 + config // 3,
            "task.misalignment.seed": np.arange(jobs) // configs,
            "status": np.where(rng.random(jobs) < 0.05, "failed", "ok"),
            "success": rng.random(jobs) < 0.8,
        }
    )
    for m in compared():
        df[m.key] = np.where(df["status"] == "failed", np.nan, rng.random(jobs))
    return df


def best_time(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--jobs", type=int, default=600)
    parser.add_argument("--configs", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    df = synthetic_sweep(args.jobs, args.configs)
    new, old = comparison_table(df), loop_table(df)
    assert list(new.columns) == list(old.columns) and new.index.equals(old.index)
    np.testing.assert_allclose(new.to_numpy(float), old.to_numpy(float), rtol=1e-12, equal_nan=True)
    t_new = best_time(lambda: comparison_table(df), args.repeats)
    t_old = best_time(lambda: loop_table(df), args.repeats)
    print(f"{args.jobs} jobs, {args.configs} configurations, {len(new)} rows: equal tables")
    print(f"loop    {t_old * 1e3:8.1f} ms")
    print(f"groupby {t_new * 1e3:8.1f} ms   ({t_old / t_new:.1f}× faster)")


if __name__ == "__main__":
    main()
