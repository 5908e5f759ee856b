"""Issue 10: are two sets of runs bit-identical? Compares the jobs two sweep directories have
in common (same job directory name, Hydra's job number aside): every timeseries.parquet column by the SHA-256 of its
bytes, and every metrics.json number (timing, provenance and keys only one side has are
listed apart, not compared).

    python analysis/issue10/bitwise.py BEFORE_SWEEP AFTER_SWEEP [--only SUBSTRING ...]

One line per job: "identical" (every common column and metric equal, bit for bit), or the
differing columns with their largest absolute difference and the differing metrics.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import pathlib
import sys

import numpy as np
import pandas as pd

#: metrics that differ from run to run of the same code (timing, provenance)
VOLATILE = {
    "wall_time_s", "loop_wall_time_s", "real_time_factor", "started_at", "host", "git_commit",
    "git_dirty", "version_compliant_docking", "overrides",
}


def column_hashes(path: pathlib.Path) -> dict[str, str]:
    df = pd.read_parquet(path)
    return {c: hashlib.sha256(np.ascontiguousarray(df[c].to_numpy()).tobytes()).hexdigest() for c in df}


def compare(before: pathlib.Path, after: pathlib.Path) -> tuple[bool, str]:
    a, b = pd.read_parquet(before / "timeseries.parquet"), pd.read_parquet(after / "timeseries.parquet")
    ha, hb = column_hashes(before / "timeseries.parquet"), column_hashes(after / "timeseries.parquet")
    notes = []
    if len(a) != len(b):
        notes.append(f"rows {len(a)} → {len(b)}")
    common = [c for c in ha if c in hb]
    differ = [c for c in common if ha[c] != hb[c]]
    for c in differ:
        if len(a) == len(b) and np.issubdtype(a[c].dtype, np.number):
            notes.append(f"{c} (max |Δ| {np.max(np.abs(a[c].to_numpy(float) - b[c].to_numpy(float))):.3g})")
        else:
            notes.append(c)
    only = sorted(set(ha) ^ set(hb))
    ma = json.loads((before / "metrics.json").read_text())
    mb = json.loads((after / "metrics.json").read_text())
    changed = []
    for k in sorted(set(ma) & set(mb) - VOLATILE):
        if ma[k] != mb[k] and not (k == "config_hash"):
            changed.append(f"{k} {ma[k]!r} → {mb[k]!r}")
    same = not differ and len(a) == len(b) and not changed
    text = "identical" if same else "DIFFERS: " + ", ".join(notes + changed)
    text += f" ({len(common)} columns"
    text += f"; columns on one side only: {only})" if only else ")"
    new_keys = sorted(set(mb) - set(ma))
    if new_keys:
        text += f" · {len(new_keys)} new metrics keys"
    return same, text


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=pathlib.Path)
    ap.add_argument("after", type=pathlib.Path)
    ap.add_argument("--only", nargs="*", default=[], help="compare jobs whose name has every substring")
    args = ap.parse_args()
    def by_name(root: pathlib.Path) -> dict[str, pathlib.Path]:
        # the job directory's name without Hydra's job number ("3_controller=…" → "controller=…"),
        # so sweeps over different sets of jobs can be compared
        return {p.parent.name.split("_", 1)[-1]: p.parent for p in root.rglob("metrics.json")}

    before, after = by_name(args.before), by_name(args.after)
    jobs = sorted(j for j in before if j in after and all(s in j for s in args.only))
    identical = 0
    for job in jobs:
        same, text = compare(before[job], after[job])
        identical += same
        print(f"{job}: {text}")
    print(f"{identical}/{len(jobs)} identical")
    return 0 if jobs and identical == len(jobs) else 1


if __name__ == "__main__":
    sys.exit(main())
