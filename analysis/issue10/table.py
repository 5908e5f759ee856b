"""Issue 10: the before/after table from sweep directories (metrics.json, or computed from
timeseries.parquet with compliant_docking.evaluation.contact.contact_metrics for runs made
before the contact metrics existed).

    python analysis/issue10/table.py SWEEP_DIR [...]                 # one row per run
    python analysis/issue10/table.py --compare BEFORE AFTER [PLANNER]  # the notes' tables
"""
from __future__ import annotations

import json
import pathlib
import sys

import numpy as np
import pandas as pd
import pinocchio as pin

from compliant_docking.evaluation.contact import contact_metrics

SEAT = pin.SE3(np.eye(3), np.array([0.55, 0.0, 0.20]))  # the default socket (no misalignment)


def row(run: pathlib.Path) -> dict:
    m = json.loads((run / "metrics.json").read_text())
    if m.get("first_contact_time_s") is None or "steady_force_mean_N" not in m:
        ts = pd.read_parquet(run / "timeseries.parquet")
        m.update(contact_metrics(ts, SEAT, steady_window=2.0, strike_window=0.1))
    return m


def main(paths):
    rows = []
    for p in paths:
        for f in sorted(pathlib.Path(p).rglob("metrics.json")):
            rows.append(row(f.parent))
    df = pd.DataFrame(rows)
    df = df.sort_values(["trajectory", "robot", "controller", "physics"], ascending=[True, False, True, False])
    for _, r in df.iterrows():
        print(f"| {r.robot} | {r.controller} | {r.trajectory} | {r.physics} | "
              f"{r.first_strike_force_N:.1f} | {r.peak_axial_force_N:.1f} | "
              f"{r.steady_force_mean_N:.2f} ± {r.steady_force_std_N:.2f} | "
              f"{r.steady_contact_events_per_s:.1f} | {r.first_contact_lateral_offset_m * 1e3:.2f} | "
              f"{'yes' if r.success else 'no'} |")




def calm(r) -> bool:
    return r.steady_contact_events_per_s <= 5.0 and r.steady_force_std_N <= max(0.5, 0.2 * r.steady_force_mean_N)


def frame(path) -> pd.DataFrame:
    df = pd.DataFrame([row(f.parent) for f in sorted(pathlib.Path(path).rglob("metrics.json"))])
    return df.set_index(["trajectory", "robot", "controller", "physics"])


def compare(before_dir, after_dir, trajectory="quintic"):
    """The notes' before/after table for one planner, and a per-planner summary."""
    before, after = frame(before_dir), frame(after_dir)

    def cells(r):
        return (f"{r.first_strike_force_N:.1f} / {r.peak_axial_force_N:.1f} | "
                f"{r.steady_force_mean_N:.2f} ± {r.steady_force_std_N:.2f} | "
                f"{r.steady_contact_events_per_s:.1f} | {r.first_contact_lateral_offset_m * 1e3:.2f}")

    print("| robot | controller | gravity | before: strike / peak [N] | before: steady force [N] | "
          "before: events/s | before: offset [mm] | before: docked (old gate; new gate) | "
          "after: strike / peak [N] | after: steady force [N] | after: events/s | after: offset [mm] | after: docked |")
    print("|---" * 13 + "|")
    for robot in ("iiwa14", "fr3"):
        for controller in ("impedance", "hqp", "se3_lie"):
            for physics in ("space", "earth"):
                b = before.loc[(trajectory, robot, controller, physics)]
                a = after.loc[(trajectory, robot, controller, physics)]
                old = "yes" if b.success else "no"
                new = "yes" if b.success and calm(b) else "no"
                print(f"| {robot} | {controller} | {physics} | {cells(b)} | {old}; {new} | {cells(a)} | "
                      f"{'yes' if a.success else 'no'} |")
    print()
    print("| planner | before | after |")
    print("|---|---|---|")
    for traj in ("quintic", "twophase", "se3topp"):
        parts = []
        for df in (before, after):
            d = df.loc[traj]
            ok_calm = sum(calm(r) for _, r in d.iterrows())
            docked = int(d.success.sum())
            both = sum(bool(r.success) and calm(r) for _, r in d.iterrows())
            parts.append(f"{ok_calm}/{len(d)} calm (max {d.steady_contact_events_per_s.max():.1f} events/s, "
                         f"worst std {d.steady_force_std_N.max():.2f} N); {docked}/{len(d)} docked by the gate of "
                         f"the run, {both}/{len(d)} docked and calm; max peak {d.peak_axial_force_N.max():.1f} N, "
                         f"max strike {d.first_strike_force_N.max():.1f} N")
        print(f"| {traj} | {parts[0]} | {parts[1]} |")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--compare"]:
        compare(*sys.argv[2:])
    else:
        main(sys.argv[1:])
