"""Is an outcome converged in a numerical setting? Pair the jobs of one or more sweeps that
differ only in that setting and compare what they concluded.

    python -m compliant_docking.results.convergence SWEEP_DIR [SWEEP_DIR ...] --vary physics.timestep

A *setting* is any config key (``physics.timestep``, ``target.contact.solref``, …): the
jobs are paired on every other key that any of them overrode (controller, robot, planner,
the misalignment's seed, …), and each pair must hold the setting's two values, a (the
first value in the order the jobs were found: the first sweep's) and b. For every
configuration cell and overall the command reports, over the pairs:

- **outcome agreement**: the share of pairs with the same docked / not-docked verdict
  (``success``), with the pairs that differ listed;
- **seat agreement**: the largest change of the seat's depth and lateral errors;
- **the gate's force**: the median and largest relative change of the filtered peak
  axial force, |b − a| / max(a, 1 N) (a floor of 1 N, so that a few tenths of a newton
  on a plug that barely touched do not count as a large relative change), and the same
  for the raw per-step peak, for contrast.

The presets ``timestep_convergence`` and ``contact_stiffness`` (conf/experiment/) run the
controller comparison's draws at two values of the setting; docs/contact.md reports what
they gave.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from compliant_docking import exit_codes
from compliant_docking.results.load import OVERRIDDEN, load_runs
from compliant_docking.results.tables import _markdown_grid

#: forces below this count as this in a relative change [N]
FORCE_FLOOR_N = 1.0
#: columns compared between the two members of a pair
FORCES = ("filtered_peak_axial_force_N", "peak_axial_force_N")
SEAT = ("seat_depth_error_m", "seat_lateral_error_m")
#: how a configuration cell is named (the first of these that vary)
CELL_KEYS = ("robot", "controller", "trajectory")


@dataclass(frozen=True)
class Pairs:
    """The paired jobs: one row per pair, columns ``<metric>_a`` / ``<metric>_b`` and the
    pairing keys; ``values`` are the setting's two values (a, b)."""

    setting: str
    values: tuple[str, str]
    keys: list[str]
    frame: pd.DataFrame


def _text(value) -> str:
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    return value if isinstance(value, str) else json.dumps(value)


def pair_jobs(runs: pd.DataFrame, setting: str) -> Pairs:
    """Pair the jobs of ``runs`` (:func:`~compliant_docking.results.load.load_runs`) that
    differ only in ``setting``; raises ValueError when they cannot be paired."""
    if setting not in runs.columns:
        raise ValueError(
            f"--vary {setting}: no job has that setting; the settings here include "
            f"{', '.join(c for c in runs.columns if '.' in c)[:400]}."
        )
    runs = runs.assign(_setting=runs[setting].map(_text))
    values = list(dict.fromkeys(runs["_setting"]))
    if len(values) != 2:
        raise ValueError(f"--vary {setting}: the jobs must hold exactly two values of it; found {values}.")
    keys = sorted(
        {k for joined in runs[OVERRIDDEN].dropna() for k in str(joined).split(",") if k and k != setting}
        & set(runs.columns)
    )
    identity = runs[keys].map(_text).agg(" ".join, axis=1) if keys else pd.Series("", index=runs.index)
    runs = runs.assign(_identity=identity)
    a = runs[runs["_setting"] == values[0]].drop_duplicates("_identity").set_index("_identity")
    b = runs[runs["_setting"] == values[1]].drop_duplicates("_identity").set_index("_identity")
    common = a.index.intersection(b.index)
    if common.empty:
        raise ValueError(
            f"--vary {setting}: no job at {values[0]} has a twin at {values[1]} "
            f"(paired on {', '.join(keys) or 'nothing'})."
        )
    columns = [c for c in ("success", "status", *FORCES, *SEAT) if c in runs.columns]
    frame = a.loc[common, keys].copy()
    for c in columns:
        frame[f"{c}_a"], frame[f"{c}_b"] = a.loc[common, c], b.loc[common, c]
    frame["job_a"], frame["job_b"] = a.loc[common, "job"], b.loc[common, "job"]
    return Pairs(setting, (values[0], values[1]), keys, frame.reset_index(drop=True))


def relative_change(a: pd.Series, b: pd.Series) -> pd.Series:
    """|b − a| / max(a, FORCE_FLOOR_N), NaN where either is missing."""
    a, b = pd.to_numeric(a, errors="coerce"), pd.to_numeric(b, errors="coerce")
    return (b - a).abs() / np.maximum(a, FORCE_FLOOR_N)


def agreement(pairs: Pairs) -> pd.DataFrame:
    """Per configuration cell and overall (the last row, ``all``): pairs, outcome
    agreement, the seat's largest changes, the forces' median and largest relative
    changes."""
    f = pairs.frame
    cells = [k for k in CELL_KEYS if k in f.columns and f[k].nunique() > 1]
    label = f[cells].map(_text).agg(" · ".join, axis=1) if cells else pd.Series("all", index=f.index)

    def row(part: pd.DataFrame) -> dict:
        out = {"pairs": len(part)}
        if "success_a" in part:
            same = part["success_a"].astype(object).eq(part["success_b"].astype(object))
            out["outcome agreement"] = same.mean()
            out["docked a"], out["docked b"] = (
                part["success_a"].eq(True).sum(),
                part["success_b"].eq(True).sum(),
            )
        for c in SEAT:
            if f"{c}_a" in part:
                change = (
                    pd.to_numeric(part[f"{c}_b"], errors="coerce")
                    - pd.to_numeric(part[f"{c}_a"], errors="coerce")
                ).abs()
                out[f"max Δ {c}"] = change.max()
        for c in FORCES:
            if f"{c}_a" in part:
                rel = relative_change(part[f"{c}_a"], part[f"{c}_b"])
                out[f"median rel. Δ {c}"], out[f"max rel. Δ {c}"] = rel.median(), rel.max()
                out[f"share ≤ 20 % {c}"] = (rel <= 0.2).mean()
        return out

    rows = {name: row(part) for name, part in f.groupby(label, sort=True)}
    rows["all"] = row(f)
    return pd.DataFrame.from_dict(rows, orient="index")


def _cell(key: str, value) -> str:
    if value is None or (isinstance(value, float) and np.isnan(value)):
        return "n/a"
    if key.startswith(("outcome", "share")):
        return f"{100 * value:.0f} %"
    if key.startswith("max Δ seat"):
        return f"{1e3 * value:.3f} mm"
    if key.startswith(("median rel", "max rel")):
        return f"{100 * value:.0f} %"
    return f"{int(value)}"


def report(pairs: Pairs) -> str:
    """The markdown report of :func:`agreement` and the pairs whose outcome differs."""
    table = agreement(pairs)
    header = ["cell", *table.columns]
    rows = [[str(name), *(_cell(c, table.loc[name, c]) for c in table.columns)] for name in table.index]
    a, b = pairs.values
    lines = [
        f"# {pairs.setting}: a = {a}, b = {b}",
        "",
        f"{len(pairs.frame)} pairs of jobs that differ only in {pairs.setting} "
        f"(paired on {', '.join(pairs.keys) or 'nothing'}). Relative force changes are "
        f"|b − a| / max(a, {FORCE_FLOOR_N:g} N).",
        "",
        _markdown_grid(header, rows),
    ]
    f = pairs.frame
    if "success_a" in f:
        differ = f[~f["success_a"].astype(object).eq(f["success_b"].astype(object))]
        if len(differ):
            lines += ["", f"Pairs whose outcome differs ({len(differ)}):", ""]
            lines += [f"- {r.job_a}: {r.success_a} at a, {r.success_b} at b" for r in differ.itertuples()]
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m compliant_docking.results.convergence", description=__doc__.splitlines()[0]
    )
    parser.add_argument("sweeps", nargs="+", type=Path, help="sweep directories (their jobs are pooled)")
    parser.add_argument("--vary", required=True, help="the config key whose two values are compared")
    parser.add_argument("--out", type=Path, help="also write the report to this markdown file")
    args = parser.parse_args(argv)
    try:
        runs = pd.concat([load_runs(s) for s in args.sweeps], ignore_index=True)
        text = report(pair_jobs(runs, args.vary))
    except (ValueError, FileNotFoundError) as error:
        print(f"compliant_docking.results.convergence: {error}", file=sys.stderr)
        return exit_codes.REFUSED
    print(text, end="")
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
