"""The jamming map of a ``+experiment=jamming_map`` sweep, with Whitney's boundaries drawn over it.

    python -m compliant_docking.results.jamming_map SWEEP_DIR --out DIR

Writes ``jamming_map.png`` (success per cell of x offset × tilt, rows robots, columns
controllers, the theory's funnel-mouth, chamfer, two-point and wedging boundaries over it)
and ``jamming_map.md`` / ``jamming_map.csv`` (per cell: docked/jobs, the success rate with
its Wilson 95 % interval, and the theory's region at the cell's centre). docs/jamming_map.md.

A cell is the pair of ranges a job drew from (``task.misalignment.x_range``,
``task.misalignment.tilt_deg_range``: the preset's strata); jobs without those ranges are
binned on the drawn values (1 mm × 1°). The boundaries are those of the sweep's own plug,
socket and friction (the first job's ``.hydra/config.yaml``;
:mod:`compliant_docking.evaluation.map_boundaries`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd

import compliant_docking.results.figures.common as common
from compliant_docking.evaluation.map_boundaries import MapBoundaries
from compliant_docking.results.load import load_runs
from compliant_docking.results.stats import wilson

X_KEY, TILT_KEY = "misalignment_x_m", "misalignment_tilt_deg"
X_RANGE, TILT_RANGE = "task.misalignment.x_range", "task.misalignment.tilt_deg_range"
#: the bins of jobs without a drawn range: x [m], tilt [deg]
BIN_X, BIN_TILT = 0.001, 1.0


def boundaries_of(run_dir: str | Path) -> MapBoundaries:
    """The boundaries of the plug, socket and sliding friction a run was configured with."""
    from omegaconf import OmegaConf

    from compliant_docking.config.geometry import PlugGeometry, SocketGeometry

    cfg = OmegaConf.load(Path(run_dir) / ".hydra" / "config.yaml")
    plug = PlugGeometry(**OmegaConf.to_container(cfg.tool.geometry, resolve=True))  # type: ignore[arg-type]
    socket = SocketGeometry(**OmegaConf.to_container(cfg.target.geometry, resolve=True))  # type: ignore[arg-type]
    return MapBoundaries.for_interface(plug, socket, float(cfg.target.contact.friction[0]))


def _cell_bounds(df: pd.DataFrame, key: str, range_key: str, width: float) -> pd.DataFrame:
    """Per job the [low, high] of its cell along one error: its drawn range, else its bin."""
    if range_key in df:
        ranges = df[range_key].map(lambda v: json.loads(v) if isinstance(v, str) else None)
        if ranges.notna().all():
            return pd.DataFrame(ranges.tolist(), index=df.index, columns=["low", "high"]).astype(float)
    low = np.floor(pd.to_numeric(df[key], errors="coerce") / width + 1e-9) * width
    return pd.DataFrame({"low": low, "high": low + width}, index=df.index)


def cell_table(df: pd.DataFrame, bounds: MapBoundaries) -> pd.DataFrame:
    """One row per robot × controller × cell: ``x_low_mm``, ``x_high_mm``, ``tilt_low_deg``,
    ``tilt_high_deg``, ``jobs``, ``docked``, ``success_rate`` with ``wilson_low``/``_high``
    (a failed job counts as not docked) and ``theory`` (:meth:`MapBoundaries.region` at the
    cell's centre; "mixed: a, b" when its corners disagree)."""
    x = _cell_bounds(df, X_KEY, X_RANGE, BIN_X) * 1e3
    tilt = _cell_bounds(df, TILT_KEY, TILT_RANGE, BIN_TILT)
    frame = pd.DataFrame(
        {
            "robot": df["robot"].astype(str) if "robot" in df else "",
            "controller": df["controller"].astype(str) if "controller" in df else "",
            "x_low_mm": x["low"].round(6), "x_high_mm": x["high"].round(6),
            "tilt_low_deg": tilt["low"].round(6), "tilt_high_deg": tilt["high"].round(6),
            "docked": (df["success"] == True).astype(int),  # noqa: E712
        }
    )  # fmt: skip
    keys = ["robot", "controller", "x_low_mm", "x_high_mm", "tilt_low_deg", "tilt_high_deg"]
    cells = frame.groupby(keys, sort=True)["docked"].agg(jobs="size", docked="sum").reset_index()
    intervals = [wilson(int(k), int(n)) for k, n in zip(cells["docked"], cells["jobs"])]
    cells["success_rate"] = cells["docked"] / cells["jobs"]
    cells["wilson_low"] = [low for low, _ in intervals]
    cells["wilson_high"] = [high for _, high in intervals]
    cells["theory"] = [_region(bounds, *row) for row in cells[keys[2:]].itertuples(index=False)]
    return cells


def _region(bounds: MapBoundaries, x_low: float, x_high: float, t_low: float, t_high: float) -> str:
    centre = bounds.region(1e-3 * (x_low + x_high) / 2, (t_low + t_high) / 2)
    corners = {bounds.region(1e-3 * x, t) for x in (x_low, x_high) for t in (t_low, t_high)}
    others = sorted(corners - {centre})
    return centre if not others else f"mixed: {', '.join([centre, *others])}"


def _curves(bounds: MapBoundaries, tilts: np.ndarray):
    """(label, style, [(x_mm, tilt_deg) curves]) of the boundaries over ``tilts``."""
    funnel = np.array([bounds.funnel_limits(t) for t in tilts]) * 1e3
    chamfer = np.array([bounds.chamfer_limits(t) for t in tilts]) * 1e3
    return [
        ("funnel mouth (capture)", {"color": "k", "lw": 1.1}, [(funnel[:, 0], tilts), (funnel[:, 1], tilts)]),
        ("chamfer meets the lip", {"color": "C0", "lw": 0.9, "ls": "--"},
         [(chamfer[:, 0], tilts), (chamfer[:, 1], tilts)]),
    ]  # fmt: skip


def jamming_map_figure(cells: pd.DataFrame, bounds: MapBoundaries, out_dir: str | Path | None = None,
                       stem: str = "jamming_map", title: str = "jamming map"):  # fmt: skip
    """The cells' success rates (colour, docked/jobs written in each) per robot (rows) and
    controller (columns), with the theory's boundaries drawn over them."""
    plt = common.comparison_style()
    rows = list(dict.fromkeys(cells["robot"]))
    cols = list(dict.fromkeys(cells["controller"]))
    x_edges = np.unique(np.r_[cells["x_low_mm"], cells["x_high_mm"]])
    t_edges = np.unique(np.r_[cells["tilt_low_deg"], cells["tilt_high_deg"]])
    width = 2.6 * len(cols) + 0.7
    text = (
        f"{int(cells['jobs'].sum())} jobs; cells: docked/jobs, colour = success rate (red 0, green 1). "
        f"Theory (Whitney, our geometry), upright: funnel mouth ±{bounds.funnel_capture_m * 1e3:.2f} mm, "
        f"chamfer ±{bounds.chamfer_capture_m * 1e3:.2f} mm (both move by −height·sin θ with the tilt); "
        f"two-point contact before the seat above {bounds.two_point_tilt_deg:.2f}°; wedging above "
        f"{_deg(bounds.wedging_tilt_deg)} (c/μ: {_deg(bounds.wedging_tilt_small_angle_deg)}). "
        "A boundary outside the axes is not drawn."
    )
    lines = textwrap.wrap(text, int(30 * width))
    below = 0.1 * len(lines) + 0.35  # the note, then the legend above it [in]
    height = 2.1 * len(rows) + 0.95 + below
    fig, axes = plt.subplots(len(rows), len(cols), figsize=(width, height), squeeze=False, sharex=True,
                             sharey=True)  # fmt: skip
    fig.subplots_adjust(left=0.55 / width, right=1 - 0.1 / width, bottom=(0.6 + below) / height, top=1 - 0.4 / height,
                        wspace=0.12, hspace=0.3)  # fmt: skip
    tilts = np.linspace(t_edges[0], t_edges[-1], 101)
    for r, robot in enumerate(rows):
        for c, controller in enumerate(cols):
            ax = axes[r][c]
            own = cells[(cells["robot"] == robot) & (cells["controller"] == controller)]
            rate = np.full((len(t_edges) - 1, len(x_edges) - 1), np.nan)
            for cell in own.itertuples(index=False):
                i = int(np.searchsorted(x_edges, cell.x_low_mm))
                j = int(np.searchsorted(t_edges, cell.tilt_low_deg))
                rate[j, i] = cell.success_rate
                ax.text((cell.x_low_mm + cell.x_high_mm) / 2, (cell.tilt_low_deg + cell.tilt_high_deg) / 2,
                        f"{cell.docked}/{cell.jobs}", ha="center", va="center", fontsize=common.FONT - 1.5,
                        color="0.15")  # fmt: skip
            ax.pcolormesh(
                x_edges, t_edges, rate, cmap="RdYlGn", vmin=0.0, vmax=1.0, alpha=0.55, shading="flat"
            )
            for label, style, curves in _curves(bounds, tilts):
                shown = [(xs, ts) for xs, ts in curves if np.any((xs >= x_edges[0]) & (xs <= x_edges[-1]))]
                for k, (xs, ts) in enumerate(shown):
                    ax.plot(xs, ts, label=label if k == 0 else None, **style)
            for value, label, style in (
                (bounds.two_point_tilt_deg, "two-point contact before the seat (rigid)", {"color": "C3", "ls": "-."}),
                (bounds.wedging_tilt_deg, "wedging (l < μd)", {"color": "C4", "ls": ":"}),
            ):  # fmt: skip
                if t_edges[0] <= value <= t_edges[-1]:
                    ax.axhline(value, lw=1.0, label=label, **style)
            ax.set_xlim(x_edges[0], x_edges[-1])
            ax.set_ylim(t_edges[0], t_edges[-1])
            ax.set_title(" · ".join(v for v in (robot, controller) if v) or "all runs")
            if r == len(rows) - 1:
                ax.set_xlabel("seat offset x [mm] (the tilt leans towards +x)")
            if c == 0:
                ax.set_ylabel("socket tilt [deg]")
    handles: dict = {}
    for ax in axes.flat:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    fig.legend(list(handles.values()), list(handles), loc="lower center", ncols=2,
               bbox_to_anchor=(0.5, (below - 0.25) / height))  # fmt: skip
    common.note(fig, lines)
    fig.suptitle(title)
    common.save_figure(fig, out_dir, stem)
    return fig


def _deg(value: float) -> str:
    return "never" if math.isinf(value) else f"{value:.2f}°"


def cell_markdown(cells: pd.DataFrame) -> str:
    """The cell table as Markdown (rates and intervals in %)."""
    lines = ["| robot | controller | x [mm] | tilt [deg] | docked/jobs | success [Wilson 95 %] | theory |",
             "|---|---|---|---|---|---|---|"]  # fmt: skip
    for c in cells.itertuples(index=False):
        lines.append(
            f"| {c.robot} | {c.controller} | {c.x_low_mm:g} … {c.x_high_mm:g} | {c.tilt_low_deg:g} … "
            f"{c.tilt_high_deg:g} | {c.docked}/{c.jobs} | {100 * c.success_rate:.0f} % "
            f"[{100 * c.wilson_low:.0f}, {100 * c.wilson_high:.0f}] | {c.theory} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from compliant_docking.run import interrupt

    return interrupt.handled("jamming_map", lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    parser = argparse.ArgumentParser(prog="python -m compliant_docking.results.jamming_map",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("sweep", type=Path, help="the sweep directory (+experiment=jamming_map)")
    parser.add_argument(
        "--out", type=Path, default=None, help="where to write the files (default: the sweep)"
    )
    parser.add_argument("--stem", default="jamming_map", help="the files' name (default: jamming_map)")
    args = parser.parse_args(argv)
    if not args.sweep.is_dir():
        parser.error(f"{args.sweep} is not a directory")
    df = load_runs(args.sweep)
    if df.empty or X_KEY not in df or TILT_KEY not in df:
        parser.error(f"{args.sweep} holds no finished docking jobs with a drawn misalignment")
    bounds = boundaries_of(df["run_dir"].iloc[0])
    cells = cell_table(df, bounds)
    out = args.out or args.sweep
    out.mkdir(parents=True, exist_ok=True)
    from compliant_docking.run.files import atomic_write_text

    jamming_map_figure(cells, bounds, out, args.stem)
    cells.to_csv(out / f"{args.stem}.csv", index=False)
    atomic_write_text(out / f"{args.stem}.md", cell_markdown(cells))
    print(f"wrote {out / args.stem}.png, .md, .csv ({len(cells)} cells, {int(cells['jobs'].sum())} jobs); "
          f"command: python -m compliant_docking.results.jamming_map {' '.join(sys.argv[1:] if argv is None else argv)}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
