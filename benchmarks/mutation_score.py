"""Mutation score of the tests: introduce one deliberate bug at a time into the metrics,
the gates, the sensor chain, the control laws and the provenance, and see whether the
tests that guard that code fail.

Each mutation is a text replacement in one source file (it must match exactly once).
The code under test is a copy of the checkout in a temporary directory (the checkout is
never touched); each mutation is applied to the copy, the listed test files run there
with ``pytest -x`` (stop at the first failure), and the file is restored. A mutation is
*killed* when pytest reports a failing test, *survived* when every test passes.

    python benchmarks/mutation_score.py                 # every mutation, a Markdown table
    python benchmarks/mutation_score.py --only M1 G5    # some of them
    python benchmarks/mutation_score.py --list          # what each one does
    python benchmarks/mutation_score.py --ref main      # the tests and code of a commit

``--ref`` takes the tree of a commit instead of the working tree (mutations whose text
is not in that tree are reported as n/a). Run from the repository root with the
project's interpreter (``.venv/bin/python``); it takes about 4 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

DOCKING = "compliant_docking/evaluation/docking.py"
CONTACT = "compliant_docking/evaluation/contact.py"
TRACKING = "compliant_docking/evaluation/tracking_gate.py"
SENSOR = "compliant_docking/sim/sensor.py"
IMPEDANCE = "compliant_docking/control/impedance.py"
SE3_LIE = "compliant_docking/control/se3_lie.py"
HQP_KERNEL = "compliant_docking/control/hqp/kernel.py"
SE3_KERNEL = "compliant_docking/control/se3_kernel.py"
KERNEL_BLOCKS = "compliant_docking/control/kernel_blocks.py"
BASE = "compliant_docking/control/base.py"
SHAPING = "compliant_docking/control/shaping.py"
INTEGRAL = "compliant_docking/control/integral.py"
PROVENANCE = "compliant_docking/run/provenance.py"
RUNNER = "compliant_docking/run/runner.py"
TABLES = "compliant_docking/results/tables.py"

METRIC_TESTS = ("tests/evaluation/test_docking.py", "tests/run/test_runner.py")
GATE_TESTS = (
    "tests/evaluation/test_docking.py",
    "tests/evaluation/test_contact.py",
    "tests/run/test_runner.py",
)
CONTACT_TESTS = ("tests/evaluation/test_contact.py",)
TRACKING_TESTS = ("tests/evaluation/test_tracking_gate.py",)
SENSOR_TESTS = ("tests/sim/test_sensor.py", "tests/control/test_impedance.py")
LAW_TESTS = (
    "tests/control/test_transients.py",
    "tests/control/test_impedance.py",
    "tests/control/test_base.py",
    "tests/control/test_se3_lie.py",
    "tests/control/test_hqp.py",
    "tests/sim/test_robots.py",
)
PROVENANCE_TESTS = ("tests/run/test_provenance.py",)
CLI_TESTS = ("tests/run/test_cli.py",)
RESULTS_TESTS = ("tests/results/test_load.py",)


@dataclass(frozen=True)
class Mutation:
    key: str
    path: str
    old: str
    new: str
    what: str
    tests: tuple[str, ...]


MUTATIONS = (
    # ---------------------------------------------------------------- docking metrics
    Mutation(
        "M1",
        DOCKING,
        "np.min(manipulability)",
        "np.max(manipulability)",
        "maximum instead of minimum manipulability",
        METRIC_TESTS,
        True,
    ),
    Mutation(
        "M2",
        DOCKING,
        "_max_pct(np.abs(v), np.asarray(velocity_limits, dtype=float))",
        "_max_pct(np.abs(v), 2.0 * np.asarray(velocity_limits, dtype=float))",
        "velocity % against twice the limit",
        METRIC_TESTS,
        True,
    ),
    Mutation(
        "M3",
        DOCKING,
        "lateral = pos_err - np.outer(pos_err @ axis, axis)",
        "lateral = pos_err",
        "lateral error not projected off the axis",
        METRIC_TESTS,
        True,
    ),
    Mutation(
        "M4",
        DOCKING,
        "final_orientation_error_rad=np.mean(ori_norm[steady])",
        "final_orientation_error_rad=np.mean(ori_norm)",
        "final orientation error over the whole run",
        METRIC_TESTS,
        True,
    ),
    Mutation(
        "M5",
        DOCKING,
        'np.sqrt(np.mean(ts["pos_error"].to_numpy() ** 2))',
        'np.mean(ts["pos_error"].to_numpy())',
        "position RMS replaced by the mean",
        METRIC_TESTS,
        True,
    ),
    Mutation(
        "M6",
        DOCKING,
        "np.sqrt(np.mean(ori_norm**2))",
        "np.mean(ori_norm)",
        "orientation RMS replaced by the mean",
        METRIC_TESTS,
        True,
    ),
    Mutation(
        "M7",
        DOCKING,
        "steady_axial_force_N=np.mean(axial[steady])",
        "steady_axial_force_N=np.mean(axial)",
        "steady axial force over the whole run",
        METRIC_TESTS,
    ),
    Mutation(
        "M8",
        DOCKING,
        "np.max(np.abs(axial))",
        "np.max(axial)",
        "peak axial force ignores pulls",
        METRIC_TESTS,
    ),
    Mutation(
        "M9",
        DOCKING,
        "wrench_norm = np.linalg.norm(ts[WRENCH]",
        "wrench_norm = np.linalg.norm(ts[FORCE]",
        "wrench norm of the force alone",
        METRIC_TESTS,
    ),
    Mutation(
        "M10",
        DOCKING,
        "half_range = (upper - lower) / 2",
        "half_range = upper - lower",
        "joint position use against the full range",
        METRIC_TESTS,
    ),
    Mutation(
        "M11",
        DOCKING,
        "    axis = axis / np.linalg.norm(axis)\n    t = ",
        "    t = ",
        "docking axis not normalised",
        METRIC_TESTS,
    ),
    Mutation(
        "M12",
        DOCKING,
        "return t >= t[-1] - window",
        "return t <= t[0] + window",
        "steady window at the start of the run",
        METRIC_TESTS,
    ),
    Mutation(
        "M13",
        DOCKING,
        "(ts[POSITION].to_numpy() - seat.translation) @ seat.rotation",
        "(ts[POSITION].to_numpy() - seat.translation)",
        "seat offsets not in the seat frame",
        METRIC_TESTS,
    ),
    Mutation(
        "M14",
        DOCKING,
        "cos_tilt = np.clip(-(plug_axis",
        "cos_tilt = np.clip((plug_axis",
        "tilt measured against the wrong end of the axis",
        METRIC_TESTS,
    ),
    Mutation(
        "M15",
        DOCKING,
        "depth_error_m=finite_or_none(depth[steady].max())",
        "depth_error_m=finite_or_none(depth[steady].mean())",
        "seat depth: mean instead of the maximum",
        METRIC_TESTS,
    ),
    Mutation(
        "M16",
        DOCKING,
        "float(t[seated[0]])",
        "float(t[seated[-1]])",
        "seated time: the last instead of the first",
        METRIC_TESTS,
    ),
    Mutation(
        "M17",
        DOCKING,
        "return np.sqrt(np.maximum(np.linalg.det(gram), 0.0)) if len(q)",
        "return np.maximum(np.linalg.det(gram), 0.0) if len(q)",
        "manipulability without the square root",
        METRIC_TESTS,
    ),
    # ---------------------------------------------------------------- docking gate
    Mutation(
        "G1",
        DOCKING,
        "            gate.peak_force_budget_N,\n",
        "            np.inf,\n",
        "peak-force check removed",
        GATE_TESTS,
        True,
    ),
    Mutation(
        "G2",
        DOCKING,
        "            gate.tilt_tolerance_deg,\n",
        "            np.inf,\n",
        "tilt check removed",
        GATE_TESTS,
        True,
    ),
    Mutation(
        "G3",
        DOCKING,
        "        elif value > limit:",
        "        elif value > 3 * limit:",
        "every tolerance × 3",
        GATE_TESTS,
        True,
    ),
    Mutation(
        "G4",
        DOCKING,
        "            gate.depth_tolerance_m,\n",
        "            np.inf,\n",
        "depth check removed",
        GATE_TESTS,
        True,
    ),
    Mutation(
        "G5",
        DOCKING,
        "            gate.lateral_tolerance_m,\n",
        "            np.inf,\n",
        "lateral check removed",
        GATE_TESTS,
    ),
    Mutation(
        "G6",
        DOCKING,
        "        elif value > limit:",
        "        elif value >= limit:",
        "a value at the tolerance fails",
        GATE_TESTS,
    ),
    Mutation(
        "G7",
        DOCKING,
        "if value is None or not np.isfinite(value):",
        "if value is None:",
        "a NaN passes the gate",
        GATE_TESTS,
    ),
    Mutation(
        "G8",
        DOCKING,
        "        elif seat.key_yaw_deg > key_yaw_limit_deg:",
        "        elif seat.key_yaw_deg > 3 * key_yaw_limit_deg:",
        "key-yaw tolerance × 3",
        GATE_TESTS,
    ),
    Mutation(
        "G9",
        DOCKING,
        "                gate.max_contact_events_per_s,\n",
        "                np.inf,\n",
        "contact-chatter check removed",
        GATE_TESTS,
    ),
    Mutation(
        "G10",
        DOCKING,
        "max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean)",
        "max(float(gate.max_force_std_N), float(gate.max_force_std_ratio) * mean) * 3",
        "force-spread limit × 3",
        GATE_TESTS,
    ),
    # ---------------------------------------------------------------- contact metrics
    Mutation(
        "K1",
        CONTACT,
        "        state = max(first - 1, 0)",
        "        state = first",
        "first contact read on the row after the state that found it",
        CONTACT_TESTS,
    ),
    Mutation(
        "K2",
        CONTACT,
        "    free = np.flatnonzero(contacts[start:stop] <= 0)",
        "    free = np.flatnonzero(contacts[start:stop] < 0)",
        "first strike never ends at the first opening",
        CONTACT_TESTS,
    ),
    Mutation(
        "K3",
        CONTACT,
        "    return int(np.count_nonzero(np.diff(touching)))",
        "    return int(np.count_nonzero(np.diff(touching) > 0))",
        "make/break events count the makes only",
        CONTACT_TESTS,
    ),
    # ---------------------------------------------------------------- tracking gate
    Mutation(
        "T1",
        TRACKING,
        "float(np.sqrt(np.mean(p * p)))",
        "float(np.mean(p))",
        "segment position RMS replaced by the mean",
        TRACKING_TESTS,
    ),
    Mutation(
        "T2",
        TRACKING,
        '            saturation = float(np.mean(ts.loc[window, "torque_saturated"]',
        '            saturation = float(np.mean(ts.loc[:, "torque_saturated"]',
        "saturation ratio over the whole run",
        TRACKING_TESTS,
    ),
    Mutation(
        "T3",
        TRACKING,
        '    at_most("max contacts", metrics.max_contacts, "max_contacts", 1.0, "")\n',
        "",
        "contacts not judged",
        TRACKING_TESTS,
    ),
    Mutation(
        "T4",
        TRACKING,
        "elif _finite(limit) and value > limit:",
        "elif _finite(limit) and value > 3 * limit:",
        "tracking thresholds × 3",
        TRACKING_TESTS,
    ),
    Mutation(
        "T5",
        TRACKING,
        "        if value is not None and not _finite(value):\n            failures.append",
        "        if False:\n            failures.append",
        "a non-finite statistic passes",
        TRACKING_TESTS,
    ),
    Mutation(
        "T6",
        TRACKING,
        "window = (t >= min(s[1] for s in segments)) & (t < max(s[2] for s in segments))",
        "window = t >= min(s[1] for s in segments)",
        "the hold after the motion is judged",
        TRACKING_TESTS,
    ),
    # ---------------------------------------------------------------- sensor chain
    Mutation(
        "S1",
        SENSOR,
        "out[3:] -= weight_moment.dot",
        "out[3:] += weight_moment.dot",
        "weight-moment sign flipped",
        SENSOR_TESTS,
        True,
    ),
    Mutation("S2", SENSOR, "            out[:3] -= weight\n", "", "tool weight not removed", SENSOR_TESTS),
    Mutation(
        "S3",
        SENSOR,
        "r = -(tool.sensor.actInv(tool.tcp)).translation",
        "r = (tool.sensor.actInv(tool.tcp)).translation",
        "moment moved to the TCP with the wrong lever",
        SENSOR_TESTS,
    ),
    Mutation(
        "S4",
        SENSOR,
        "to_tcp = -np.block(",
        "to_tcp = np.block(",
        "reaction instead of the wrench on the tool",
        SENSOR_TESTS,
    ),
    # ---------------------------------------------------------------- control laws
    Mutation(
        "C1",
        IMPEDANCE,
        "D = np.array([d] * 3 + [d_rot] * 3, dtype=float)",
        "D = np.array([0.5 * d] * 3 + [d_rot] * 3, dtype=float)",
        "impedance damping halved",
        LAW_TESTS,
        True,
    ),
    Mutation(
        "C2",
        IMPEDANCE,
        "D = np.array([d] * 3 + [d_rot] * 3, dtype=float)",
        "D = np.array([d] * 3 + [0.5 * d_rot] * 3, dtype=float)",
        "impedance rotational damping halved",
        LAW_TESTS,
    ),
    Mutation(
        "C3",
        IMPEDANCE,
        "W_inv = 1.0 / np.array([m] * 3",
        "W_inv = 0.5 / np.array([m] * 3",
        "impedance apparent mass doubled",
        LAW_TESTS,
    ),
    Mutation(
        "C4",
        IMPEDANCE,
        "K = np.array([k] * 3 + [k_rot] * 3, dtype=float)",
        "K = np.array([0.9 * k] * 3 + [k_rot] * 3, dtype=float)",
        "impedance stiffness −10 %",
        LAW_TESTS,
    ),
    Mutation(
        "C5",
        IMPEDANCE,
        "            force -= wrench\n",
        "",
        "the push counted twice (no −Jᵀw, as the research code)",
        LAW_TESTS,
    ),
    Mutation(
        "C6",
        IMPEDANCE,
        "        a += JMinv.dot(bv)\n",
        "",
        "null-space damping leaks into the task",
        LAW_TESTS,
    ),
    Mutation(
        "C7",
        SE3_LIE,
        "self.D = _matrix(D_diag if D is None else D",
        "self.D = 0.5 * _matrix(D_diag if D is None else D",
        "SE(3) impedance damping halved",
        LAW_TESTS,
    ),
    Mutation(
        "C8",
        SE3_LIE,
        "self.K = _matrix(K_diag if K is None else K",
        "self.K = 0.9 * _matrix(K_diag if K is None else K",
        "SE(3) impedance stiffness −10 %",
        LAW_TESTS,
    ),
    Mutation(
        "C9",
        HQP_KERNEL,
        "one_minus_alpha = 1.0 / (1.0 + math.exp(x))",
        "one_minus_alpha = 1.0 / (1.0 + math.exp(-x))",
        "HQP stiffness rises with force (α for 1 − α)",
        LAW_TESTS,
    ),
    Mutation(
        "C10",
        HQP_KERNEL,
        "return min(max(one_minus_alpha, K_min_ratio), 1.0)",
        "return min(one_minus_alpha, 1.0)",
        "HQP K_min clip removed",
        LAW_TESTS,
    ),
    Mutation(
        "C11",
        HQP_KERNEL,
        "            DK[i, j] *= ws[W_SQRT_S]\n",
        "            DK[i, j] *= 0.5 * ws[W_SQRT_S]\n",
        "HQP damping halved",
        LAW_TESTS,
    ),
    Mutation(
        "C12",
        BASE,
        "        x *= self.f\n",
        "        x *= -self.f\n",
        "friction feed-forward against the motion",
        LAW_TESTS,
    ),
    Mutation(
        "C13",
        SHAPING,
        "        c = np.minimum(mu * (1.0 / self.ratio), 1.0)",
        "        c = np.minimum(mu * self.ratio, 1.0)",
        "apparent-inertia floor at 1/ratio instead of ratio",
        ("tests/control/test_shaping.py",),
    ),
    Mutation(
        "C14",
        INTEGRAL,
        "        if f0 * f0 + f1 * f1 + f2 * f2 > self.freeze_sq:",
        "        if False:",
        "integral action never frozen in contact",
        ("tests/control/test_integral.py",),
    ),
    Mutation(
        "C15",
        BASE,
        "            x = tau_pre - bias",
        "            x = tau_pre + 0.0 * bias",
        "torque_unbiased ignores the bias torques",
        LAW_TESTS,
    ),
    # the compiled steps: each is checked against a numpy evaluation
    Mutation(
        "C16",
        KERNEL_BLOCKS,
        "        out[i] = math.tanh(x) * f[i] + b[i] * v[i]",
        "        out[i] = -math.tanh(x) * f[i] + b[i] * v[i]",
        "compiled friction feed-forward against the motion",
        ("tests/control/test_kernel_blocks.py", *LAW_TESTS),
    ),
    Mutation(
        "C17",
        SE3_KERNEL,
        "        tau[c] = s + h[c] - bn * mv",
        "        tau[c] = s + h[c] + bn * mv",
        "compiled SE(3) step: null-space damping pumps energy in",
        ("tests/control/test_se3_kernel.py", *LAW_TESTS),
    ),
    Mutation(
        "C18",
        HQP_KERNEL,
        "                a_null[i] += gain * direction[i]",
        "                a_null[i] -= gain * direction[i]",
        "compiled HQP step: singularity avoidance steers toward the singularity",
        ("tests/control/test_hqp_kernel.py", *LAW_TESTS),
    ),
    # ---------------------------------------------------------------- provenance, exit status
    Mutation(
        "P1",
        PROVENANCE,
        "            dirty = True",
        "            dirty = False",
        "git_dirty never true",
        PROVENANCE_TESTS,
        True,
    ),
    Mutation(
        "P2",
        PROVENANCE,
        'commit = oid if oid != "(initial)" else None',
        "commit = oid[::-1]",
        "git_commit not HEAD",
        PROVENANCE_TESTS,
    ),
    Mutation(
        "R2",
        TABLES,
        "means = values.groupby(by, sort=False).mean()",
        "means = values.groupby(by, sort=False).median()",
        "comparison table: median instead of the mean",
        RESULTS_TESTS,
    ),
    Mutation(
        "R3",
        TABLES,
        'totals["success rate"] = totals["docked"] / totals["jobs"]',
        'totals["success rate"] = totals["docked"] / (totals["jobs"] - totals["failed"])',
        "success rate over the jobs that did not fail",
        RESULTS_TESTS,
    ),
    Mutation(
        "R1",
        RUNNER,
        "EXIT_SUCCESS, EXIT_FAILED, EXIT_GATE = 0, 1, 3",
        "EXIT_SUCCESS, EXIT_FAILED, EXIT_GATE = 0, 1, 1",
        "a gate failure exits 1",
        CLI_TESTS,
    ),
)


def source_tree(ref: str | None, into: Path) -> None:
    """The checkout's files (tracked and untracked, not ignored), or the tree of ``ref``."""
    if ref is None:
        listed = (
            subprocess.run(
                ["git", "-C", str(ROOT), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                capture_output=True,
                check=True,
            )
            .stdout.decode()
            .split("\0")
        )
        for name in filter(None, listed):
            src = ROOT / name
            if src.is_file():
                (into / name).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(src, into / name)
    else:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(into)], input=archive.stdout, check=True)


def run_tests(tree: Path, tests: tuple[str, ...], timeout: float) -> tuple[str, str, float]:
    """('killed' | 'survived' | 'error', detail, seconds) of pytest -x on ``tests`` in ``tree``."""
    present = [t for t in tests if (tree / t).exists()]
    if not present:
        return "n/a", "no such test files", 0.0
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": str(tree)}
    started = time.perf_counter()
    try:
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "pytest",
                "-x",
                "-q",
                "-p",
                "no:cacheprovider",
                "-m",
                "not slow",
                *present,
            ],
            cwd=tree,
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
        )
    except subprocess.TimeoutExpired:
        return "killed", "timed out", time.perf_counter() - started
    seconds = time.perf_counter() - started
    failed = re.findall(r"^(?:FAILED|ERROR) (.+?)(?: - .*)?$", proc.stdout, re.M)
    if proc.returncode == 0:
        return "survived", "", seconds
    if proc.returncode == 1 and failed:
        return "killed", failed[0], seconds
    return "error", (failed[0] if failed else proc.stdout.strip().splitlines()[-1:] or [""])[0], seconds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--only", nargs="*", help="mutation keys (default: all)")
    parser.add_argument("--list", action="store_true", help="list the mutations and exit")
    parser.add_argument("--ref", help="a commit whose tree to mutate (default: the working tree)")
    parser.add_argument("--timeout", type=float, default=900.0, help="per mutation [s]")
    parser.add_argument("--out", type=Path, help="also write the Markdown table here")
    args = parser.parse_args(argv)
    chosen = [m for m in MUTATIONS if not args.only or m.key in args.only]
    if args.list:
        for m in chosen:
            print(f"{m.key:4} {m.path}: {m.what}")
        return 0
    rows = []
    with tempfile.TemporaryDirectory(prefix="mutation_") as tmp:
        tree = Path(tmp)
        source_tree(args.ref, tree)
        where = subprocess.run(
            [sys.executable, "-c", "import compliant_docking; print(compliant_docking.__file__)"],
            cwd=tree,
            capture_output=True,
            text=True,
            env={**os.environ, "PYTHONPATH": str(tree)},
        ).stdout.strip()
        if not where.startswith(str(tree)):
            sys.exit(f"the copy does not import its own package (got {where!r})")
        for m in chosen:
            target = tree / m.path
            original = target.read_text(encoding="utf-8") if target.is_file() else ""
            if original.count(m.old) != 1:
                rows.append((m, "n/a", f"text found {original.count(m.old)}×", 0.0))
            else:
                target.write_text(original.replace(m.old, m.new), encoding="utf-8")
                try:
                    rows.append((m, *run_tests(tree, m.tests, args.timeout)))
                finally:
                    target.write_text(original, encoding="utf-8")
            m_, status, detail, seconds = rows[-1]
            print(f"{m.key:4} {status:8} {seconds:6.1f} s  {m.what}  {detail}", flush=True)
    judged = [r for r in rows if r[1] in ("killed", "survived", "error")]
    killed = sum(r[1] in ("killed", "error") for r in judged)
    lines = [
        "| key | file | mutation | result | caught by | s |",
        "|---|---|---|---|---|---:|",
        *(
            f"| {m.key} | {Path(m.path).name} | {m.what} | {status} | "
            f"{detail.replace('|', '/')} | {seconds:.0f} |"
            for m, status, detail, seconds in rows
        ),
        "",
        f"Score: {killed}/{len(judged)} killed",
    ]
    table = "\n".join(lines)
    print("\n" + table)
    if args.out:
        args.out.write_text(table + "\n", encoding="utf-8")
    return 0 if killed == len(judged) else 1


if __name__ == "__main__":
    sys.exit(main())
