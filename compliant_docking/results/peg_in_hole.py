"""Whitney's quasi-static theory against the arm-free compliance rig (docs/peg_in_hole.md).

    python -m compliant_docking.results.peg_in_hole --out docs/figures        # every case
    python -m compliant_docking.results.peg_in_hole --out /tmp/pih --quick    # four cases

For each case of :data:`CASES` (our plug and socket, our contact parameters with the
case's friction, the support of :data:`SUPPORT`) the rig
(:mod:`compliant_docking.sim.compliance_rig`) drives the plug down the socket's axis at
:data:`SPEED` from just above the first contact the theory predicts to 1 mm above the
seat, three times: at the timestep of the runs (1 ms), at half the speed (quasi-static
check) and at half the timestep (convergence check).  Each run is averaged over bins of
the tip's depth (:data:`BIN`; the contact chatters at ~100 Hz, so the mean, not a sample,
is the quasi-static force).  The quasi-static limit is estimated from the two speeds by
Richardson extrapolation, F₀ = 2 F(v/2) − F(v) (the dynamic part of the force is linear
in the speed), and compared with the theory
(:func:`compliant_docking.evaluation.insertion_statics.insertion_curve`) phase by phase:
the chamfer-crossing force ratio, the lateral force while crossing, the one-point
insertion force, the depth where two-point contact starts (the first bin in which most
steps touch both sides of the bore), the two-point force (raw, and with the clearance
widened by the contact penetration the rig measured), and wedging.  Jamming
(:data:`JAMMING`, not with ``--quick``): the rig pushed with a constant force against the
depth where the theory needs more than that force.

Writes ``peg_in_hole_<group>.png`` (theory against simulation, force against depth, per
case), ``peg_in_hole.md`` (the per-case table and the agreement summary) and
``peg_in_hole.csv`` (the per-case metrics).
"""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from compliant_docking.config.store import default_interface
from compliant_docking.evaluation.insertion_statics import (
    CROSSING,
    ONE_POINT,
    TWO_POINT,
    WEDGED,
    InsertionCurve,
    insertion_curve,
)
from compliant_docking.evaluation.peg_in_hole import PegInHole, crossing_force_ratio
from compliant_docking.results.figures.peg_in_hole import draw
from compliant_docking.sim.compliance_rig import (
    Push,
    Ramp,
    Support,
    critically_damp,
    interface_rig,
    push_insertion,
    ramp_insertion,
)

#: the support: the FR3's impedance gains (conf/robot_controller/fr3_impedance.yaml: 300
#: N/m; conf/controller/impedance.yaml: 25 N·m/rad), critically damped
LATERAL_STIFFNESS, ANGULAR_STIFFNESS = 300.0, 25.0
#: drive speed [m/s], timestep [s], depth bin [m]
SPEED, TIMESTEP, BIN = 0.005, 0.001, 0.0005
#: the runs stop 1 mm above the seat (the theory has no floor) or when the drive pushes
#: with more than this [N] (a wedged or jammed plug)
END_HEIGHT, MAX_FORCE = 0.001, 50.0
#: bins within this distance [m] of a theory phase change are left out of its metrics
EDGE = 0.00075


@dataclass(frozen=True)
class Case:
    """One insertion: rest errors of the tip (lateral error along +x [m], tilt about y
    [deg], positive leaning the tip towards -x), compliance centre height above the tip
    [m], friction, and the socket/plug discretisation (``fine``: 64 sectors, 128-gon)."""

    name: str
    group: str
    lateral_error: float = 0.0
    tilt_deg: float = 0.0
    compliance_height: float = 0.0
    friction: float = 0.3
    fine: bool = False


CASES = (
    *(Case(f"lateral {e:g} mm", "lateral", lateral_error=e * 1e-3) for e in (1, 2, 3, 6)),
    *(Case(f"lateral 2 mm, μ {mu:g}", "friction", lateral_error=0.002, friction=mu) for mu in (0.1, 0.6)),
    *(
        Case(f"tilt {t:g}°, L_g {1e3 * lg:g} mm", "tilt", tilt_deg=t, compliance_height=lg)
        for lg in (0.0, 0.1, 0.2)
        for t in (1.0, 2.0, 3.0)
    ),
    *(
        Case(f"tilt 2° + 1 mm, L_g {1e3 * lg:g} mm", "tilt + lateral", 0.001, 2.0, lg)
        for lg in (0.0, 0.1, 0.2)
    ),
    *(Case(f"tilt 5°, μ {mu:g}", "wedging", tilt_deg=5.0, friction=mu) for mu in (0.3, 0.6)),
    Case("lateral 2 mm, fine", "reference", lateral_error=0.002, fine=True),
    Case("tilt 2°, fine", "reference", tilt_deg=2.0, fine=True),
    Case("tilt 3°, L_g 200 mm, fine", "reference", tilt_deg=3.0, compliance_height=0.2, fine=True),
)
#: jamming under a limited push: (case, push [N]); the push drive approaches at PUSH_SPEED
JAMMING = (("tilt 3°, L_g 0 mm", 5.0), ("tilt 3°, L_g 200 mm", 5.0), ("tilt 5°, μ 0.6", 5.0))
PUSH_SPEED, PUSH_TIME = 0.005, 20.0
#: ``--quick``: one case per phase
QUICK = ("lateral 3 mm", "tilt 3°, L_g 200 mm", "tilt 5°, μ 0.6", "lateral 2 mm, fine")


def interface(case: Case):
    """(plug, socket, contact) of ``case``: the default interface with its friction and
    discretisation."""
    plug, socket, contact = default_interface()
    contact = replace(contact, friction=(case.friction, *contact.friction[1:]))
    if case.fine:
        plug, socket = replace(plug, segments=128), replace(socket, sectors=64)
    return plug, socket, contact


def theory(case: Case, *, widen: float = 0.0) -> InsertionCurve:
    """The theory's curve for ``case`` on a 0.05 mm drive grid from the mouth to 1 mm above
    the seat; ``widen`` [m] is added to the bore radius."""
    plug, socket, _ = interface(case)
    peg = PegInHole.for_interface(
        plug,
        socket,
        lateral_stiffness=LATERAL_STIFFNESS,
        angular_stiffness=ANGULAR_STIFFNESS,
        compliance_height=case.compliance_height,
        friction=case.friction,
        lateral_error=case.lateral_error,
        tilt_deg=case.tilt_deg,
    )
    peg = replace(peg, bore_radius=peg.bore_radius + widen)
    end = socket.insertion_depth - END_HEIGHT
    return insertion_curve(peg, np.arange(-socket.funnel_depth, end + 1e-9, 5e-5))


def simulate(
    case: Case, *, speed: float = SPEED, timestep: float = TIMESTEP, end_depth: float | None = None
) -> pd.DataFrame:
    """One rig run of ``case``, averaged per depth bin: depth [m] (tip below the lip, the
    bin's mean), F_z, F_x [N] (contact force on the plug), tilt [rad], tip_x [m],
    two_sided (fraction of the bin's steps touching both sides of the bore), penetration
    [m] (mean over steps of the deepest contact on each side, summed over the sides),
    steps, and the run's ``stopped`` reason in the frame's attrs."""
    plug, socket, contact = interface(case)
    first = theory(case).first_contact()
    start_depth = max(-socket.funnel_depth - 0.002, first - 0.0015)
    support = Support(LATERAL_STIFFNESS, 0.0, ANGULAR_STIFFNESS, 0.0, case.compliance_height, twist=False)
    rig = interface_rig(
        plug,
        socket,
        contact,
        start_gap=-socket.funnel_depth - start_depth,
        support=support,
        drive=Ramp(speed),
        offset=case.lateral_error,
        tilt_deg=case.tilt_deg,
        timestep=timestep,
    )
    critically_damp(rig)
    end = socket.insertion_depth - END_HEIGHT if end_depth is None else end_depth
    trace = ramp_insertion(rig, end_height=socket.insertion_depth - end, max_force=MAX_FORCE)
    depth = socket.insertion_depth - trace.tip_height
    steps = np.arange(len(depth))
    both = np.zeros(len(depth))
    deepest = np.zeros((len(depth), 2))
    rows = trace.contacts
    if len(rows):
        step, side, dist = rows[:, 0].astype(int), np.sign(-rows[:, 6]), rows[:, 9]
        for k, s in enumerate((1.0, -1.0)):
            on = side == s
            np.minimum.at(deepest[:, k], step[on], dist[on])
        both = ((deepest[:, 0] < 0) & (deepest[:, 1] < 0)).astype(float)
    frame = pd.DataFrame(
        {
            "depth": depth,
            "F_z": trace.force[:, 2],
            "F_x": trace.force[:, 0],
            "tilt": trace.tilt,
            "tip_x": trace.tip_x,
            "two_sided": both,
            "penetration": -deepest.sum(axis=1),
            "steps": 1,
            "bin": np.floor(depth / BIN).astype(int),
        },
        index=steps,
    )
    binned = frame.groupby("bin").agg({**{c: "mean" for c in frame.columns[:-2]}, "steps": "sum"})
    binned = binned[binned["steps"] >= 5].reset_index(drop=True)
    binned.attrs["stopped"] = trace.stopped
    binned.attrs["max_depth"] = float(depth.max())
    return binned


def two_point_onset(binned: pd.DataFrame) -> float:
    """Depth [m] of the first bin in which most steps touch both sides of the bore (nan if none)."""
    touching = binned["depth"][binned["two_sided"] >= 0.5]
    return float(touching.iloc[0]) if len(touching) else math.nan


def _quasi_static(base: pd.DataFrame, half: pd.DataFrame) -> pd.DataFrame:
    """Richardson's extrapolation to zero speed on the bins both runs have."""
    merged = base.merge(half, left_index=True, right_index=True, suffixes=("", "_half"))
    out = merged[list(base.columns)].copy()
    for column in ("F_z", "F_x", "tilt", "tip_x"):
        out[column] = 2.0 * merged[f"{column}_half"] - merged[column]
    return out


def _at(curve: InsertionCurve, values: np.ndarray, depth: np.ndarray) -> np.ndarray:
    ok = np.isfinite(curve.depth) & np.isfinite(values) & (np.array(curve.phase) != WEDGED)
    return np.interp(depth, curve.depth[ok], values[ok], left=np.nan, right=np.nan)


def _phase_at(curve: InsertionCurve, depth: np.ndarray) -> np.ndarray:
    """The theory's phase at each depth, '' within EDGE of a phase change."""
    ok = np.isfinite(curve.depth)
    d, phases = curve.depth[ok], np.array(curve.phase)[ok]
    out = []
    for x in depth:
        near = phases[np.abs(d - x) <= EDGE]
        out.append(near[0] if len(near) and (near == near[0]).all() else "")
    return np.array(out)


def _relative(sim: np.ndarray, model: np.ndarray) -> float:
    """Median of |sim − theory| / |theory| [%] (nan when empty)."""
    ok = np.isfinite(sim) & np.isfinite(model) & (np.abs(model) > 1e-9)
    return float(100.0 * np.median(np.abs(sim[ok] - model[ok]) / np.abs(model[ok]))) if ok.any() else math.nan


def compare(
    case: Case, base: pd.DataFrame, half: pd.DataFrame, fine_step: pd.DataFrame | None = None
) -> dict:
    """The per-case metrics (see the module doc); the timestep change is nan without
    ``fine_step``."""
    qs = _quasi_static(base, half)
    curve = theory(case)
    depth = qs["depth"].to_numpy()
    phase = _phase_at(curve, depth)
    f_z, f_x = qs["F_z"].to_numpy(), qs["F_x"].to_numpy()
    model_z, model_x = _at(curve, curve.insertion_force, depth), _at(curve, curve.lateral_force, depth)
    out: dict = {"case": case.name, "group": case.group}
    crossing = phase == CROSSING
    out["crossing_ratio_sim"] = (
        float(f_z[crossing].sum() / -f_x[crossing].sum()) if crossing.any() else math.nan
    )
    out["crossing_ratio_theory"] = (
        crossing_force_ratio(math.radians(30.0), case.friction) if crossing.any() else math.nan
    )
    out["crossing_Fx_error_N"] = (
        float(np.max(np.abs(f_x - model_x)[crossing])) if crossing.any() else math.nan
    )
    one = phase == ONE_POINT
    out["one_point_Fz_theory_N"] = float(np.mean(model_z[one])) if one.any() else math.nan
    out["one_point_Fz_error_N"] = float(np.max(np.abs(f_z - model_z)[one])) if one.any() else math.nan
    out["one_point_Fz_error_pct"] = _relative(f_z[one], model_z[one])
    onset = np.nanmin(
        [curve.onset(TWO_POINT), curve.onset(WEDGED), math.inf]
    )  # a wedge is two-point contact too
    onset = onset if math.isfinite(onset) else math.nan
    out["two_point_onset_theory_mm"] = 1e3 * onset
    out["two_point_onset_sim_mm"] = 1e3 * two_point_onset(base)
    two = phase == TWO_POINT
    widen = 0.5 * float(qs["penetration"][two].mean()) if two.any() else 0.0
    out["two_point_penetration_um"] = 2e6 * widen
    widened = theory(case, widen=widen) if two.any() else curve
    widened_z = _at(widened, widened.insertion_force, depth)
    out["two_point_Fz_error_pct"] = _relative(f_z[two], model_z[two])
    out["two_point_Fz_widened_error_pct"] = _relative(f_z[two], widened_z[two])
    last = np.flatnonzero(two)[-1:] if two.any() else np.array([], dtype=int)
    out["two_point_Fz_end_N"] = float(f_z[last[0]]) if last.size else math.nan
    out["two_point_Fz_end_theory_N"] = float(model_z[last[0]]) if last.size else math.nan
    out["two_point_Fz_end_widened_N"] = float(widened_z[last[0]]) if last.size else math.nan
    wedge = curve.onset(WEDGED)
    out["wedged_theory_mm"] = 1e3 * wedge
    out["sim_stopped"] = base.attrs["stopped"]
    out["sim_max_depth_mm"] = 1e3 * base.attrs["max_depth"]
    for label, other in (("speed", half), ("timestep", fine_step)):
        if other is None:
            out[f"{label}_change_N"] = out[f"{label}_change_pct"] = math.nan
            continue
        merged = base.merge(other, left_index=True, right_index=True, suffixes=("", "_o"))
        scale = max(1.0, float(np.abs(merged["F_z"]).max()))
        out[f"{label}_change_N"] = float(np.abs(merged["F_z"] - merged["F_z_o"]).max())
        out[f"{label}_change_pct"] = 100.0 * out[f"{label}_change_N"] / scale
    return out


def push_stall(case: Case, push: float) -> dict:
    """Jamming: the theory's stall depth under ``push`` against the rig pushed with it
    (approach at PUSH_SPEED, then PUSH_TIME seconds): where the plug is and how fast it
    still moves."""
    plug, socket, contact = interface(case)
    support = Support(LATERAL_STIFFNESS, 0.0, ANGULAR_STIFFNESS, 0.0, case.compliance_height, twist=False)
    rig = interface_rig(
        plug, socket, contact, support=support, drive=Push(push, PUSH_SPEED),
        offset=case.lateral_error, tilt_deg=case.tilt_deg,
    )  # fmt: skip
    critically_damp(rig)
    result = push_insertion(rig, duration=PUSH_TIME, stall_time=PUSH_TIME)
    return {
        "case": case.name,
        "push_N": push,
        "stall_theory_mm": 1e3 * theory(case).stall_depth(push),
        "sim_depth_mm": 1e3 * (socket.insertion_depth - result.final_tip_height),
        "sim_seated": result.seated,
        "sim_speed_mm_s": 1e3 * abs(float(rig.data.qvel[rig.drive_dof])),
    }


def run_case(case: Case) -> tuple[Case, pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """The three runs of ``case``: base, half speed, half timestep."""
    return (
        case,
        simulate(case),
        simulate(case, speed=0.5 * SPEED),
        simulate(case, timestep=0.5 * TIMESTEP),
    )


def _fmt(value: float, digits: int = 3) -> str:
    return (
        "—"
        if value is None or (isinstance(value, float) and not math.isfinite(value))
        else f"{value:.{digits}g}"
    )


def table(metrics: pd.DataFrame) -> str:
    """The per-case table and the agreement summary, as Markdown."""
    lines = [
        "| case | crossing F_z/F_x sim / theory | crossing F_x max error [N] | one-point F_z theory [N], "
        "max error [N] | two-point onset sim / theory [mm] | penetration [µm] | two-point F_z at the "
        "deepest bin sim / theory / widened [N] | two-point median error theory / widened [%] | "
        "wedged (theory) [mm] | sim reached [mm] | speed / timestep change [%] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for _, m in metrics.iterrows():
        lines.append(
            f"| {m['case']} | {_fmt(m['crossing_ratio_sim'])} / {_fmt(m['crossing_ratio_theory'])} | "
            f"{_fmt(m['crossing_Fx_error_N'], 2)} | {_fmt(m['one_point_Fz_theory_N'])}, "
            f"{_fmt(m['one_point_Fz_error_N'], 2)} | "
            f"{_fmt(m['two_point_onset_sim_mm'])} / {_fmt(m['two_point_onset_theory_mm'])} | "
            f"{_fmt(m['two_point_penetration_um'], 2)} | {_fmt(m['two_point_Fz_end_N'])} / "
            f"{_fmt(m['two_point_Fz_end_theory_N'])} / {_fmt(m['two_point_Fz_end_widened_N'])} | "
            f"{_fmt(m['two_point_Fz_error_pct'], 2)} / {_fmt(m['two_point_Fz_widened_error_pct'], 2)} | "
            f"{_fmt(m['wedged_theory_mm'])} | {_fmt(m['sim_max_depth_mm'])} ({m['sim_stopped']}) | "
            f"{_fmt(m['speed_change_pct'], 2)} / {_fmt(m['timestep_change_pct'], 2)} |"
        )
    ratio_error = 100.0 * (metrics["crossing_ratio_sim"] / metrics["crossing_ratio_theory"] - 1.0)
    onset_error = metrics["two_point_onset_sim_mm"] - metrics["two_point_onset_theory_mm"]
    end_error = 100.0 * (metrics["two_point_Fz_end_N"] / metrics["two_point_Fz_end_theory_N"] - 1.0)
    widened_error = 100.0 * (metrics["two_point_Fz_end_N"] / metrics["two_point_Fz_end_widened_N"] - 1.0)
    summary = [
        "",
        "| quantity | agreement over the cases |",
        "|---|---|",
        f"| chamfer-crossing force ratio F_z/F_x | within {_fmt(ratio_error.abs().max(), 2)} % |",
        f"| lateral force while crossing | within {_fmt(metrics['crossing_Fx_error_N'].max(), 2)} N |",
        f"| one-point insertion force | within {_fmt(metrics['one_point_Fz_error_N'].max(), 2)} N |",
        f"| two-point onset depth | sim − theory {_fmt(onset_error.min(), 2)} to "
        f"{_fmt(onset_error.max(), 2)} mm |",
        f"| two-point force at the deepest bin, rigid theory | sim − theory {_fmt(end_error.min(), 2)} to "
        f"{_fmt(end_error.max(), 2)} % |",
        f"| the same, bore widened by the measured penetration | {_fmt(widened_error.min(), 2)} to "
        f"{_fmt(widened_error.max(), 2)} % |",
        f"| speed halved / timestep halved | F_z changes ≤ {_fmt(metrics['speed_change_pct'].max(), 2)} % / "
        f"≤ {_fmt(metrics['timestep_change_pct'].max(), 2)} % of max(1 N, the case's peak) |",
    ]
    return "\n".join(lines + summary) + "\n"


def jamming_table(pushes: pd.DataFrame) -> str:
    """Theory's stall depth under a limited push against where the pushed rig got, as Markdown."""
    lines = [
        f"| case | push [N] | theory stalls at [mm] | sim after {PUSH_TIME:g} s [mm] | still moving at [mm/s] |",
        "|---|---|---|---|---|",
    ]
    for _, row in pushes.iterrows():
        where = "seated" if row["sim_seated"] else _fmt(row["sim_depth_mm"])
        lines.append(
            f"| {row['case']} | {row['push_N']:g} | {_fmt(row['stall_theory_mm'])} | {where} | "
            f"{_fmt(row['sim_speed_mm_s'], 2)} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="directory for the figures and the table")
    parser.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)}")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error(f"--jobs must be at least 1; got {args.jobs}")
    cases = [c for c in CASES if c.name in QUICK] if args.quick else list(CASES)
    with ProcessPoolExecutor(args.jobs) as pool:
        runs = list(pool.map(run_case, cases))
    metrics = pd.DataFrame([compare(*run) for run in runs])
    args.out.mkdir(parents=True, exist_ok=True)
    metrics.to_csv(args.out / "peg_in_hole.csv", index=False)
    text = table(metrics)
    if not args.quick:
        pushes = [push_stall(next(c for c in CASES if c.name == name), push) for name, push in JAMMING]
        text += "\n" + jamming_table(pd.DataFrame(pushes))
    (args.out / "peg_in_hole.md").write_text(text, encoding="utf-8")
    panels = [(case, base, _quasi_static(base, half), theory(case)) for case, base, half, _ in runs]
    for path in draw(panels, args.out):
        print(f"wrote {path}")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
