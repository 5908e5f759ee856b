"""Parallel efficiency of a sweep: N default docking runs as one ``-m`` sweep vs one by one.

    python benchmarks/sweep_efficiency.py [--runs 8] [--workers 2] [--repeat 1]

Three wall times of the same N default docking runs, none drawing per-run figures (as
in a sweep; the single commands get ``figures=false`` so all three do the same work):

- **parallel**: one command ``python -m compliant_docking -m task.misalignment.seed=0,…``
  with ``hydra.launcher.n_jobs=WORKERS``, timed from start to exit: interpreter and Hydra
  start-up, config validation, worker spawn and imports, the jobs, and the end-of-sweep
  summary and comparison figures all count. The seed is a no-op here (no misalignment
  range is set), so each job is the default docking run.
- **sequential, commands** (the target's baseline): the N runs as N separate
  ``python -m compliant_docking`` commands, one after another — what running them one
  after another costs a user without ``-m``; each command pays its own start-up.
- **sequential, in-process** (stricter, for diagnosis): the N runs through
  ``compliant_docking.run.runner.execute`` in this one process (config composed with
  ``load_config``), libraries imported once, no start-up per run. Its ratio shows what
  Hydra's and the pool's fixed costs take from the ideal 1/WORKERS.

Prints the wall times and ratio = parallel / sequential for both baselines, and whether
the commands ratio meets the target (≤ 0.6 for 8 runs on 2 workers). With ``--repeat``
the measurements alternate in order; "best" divides the fastest time of each (the one
least disturbed by other work on the machine, as benchmarks/loop_speed.py does), and the
median of the per-repeat ratios is printed beside it. Another process busy on a core
hurts the parallel sweep more than the sequential runs (which leave a core free): the
load average is printed first.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def sequential(runs: int, out: Path) -> float:
    """Wall time [s] of ``runs`` default runs through runner.execute in this process."""
    from compliant_docking.config import load_config
    from compliant_docking.run.runner import execute

    start = time.perf_counter()
    for i in range(runs):
        record = execute(load_config("task.progress=false"), out / f"run_{i}", figures=False, echo=False)
        if record["status"] == "failed":
            raise SystemExit(f"sequential run {i} failed: {record['error']}")
    return time.perf_counter() - start


def commands(runs: int, out: Path) -> float:
    """Wall time [s] of ``runs`` separate single-run commands, one after another."""
    start = time.perf_counter()
    for i in range(runs):
        result = subprocess.run(
            [
                sys.executable,
                "-m",
                "compliant_docking",
                "task.progress=false",
                "figures=false",
                f"hydra.run.dir={out / f'run_{i}'}",
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
        )
        if result.returncode == 1:
            raise SystemExit(f"single run {i} failed:\n{result.stdout[-2000:]}\n{result.stderr[-2000:]}")
    return time.perf_counter() - start


def parallel(runs: int, workers: int, out: Path) -> float:
    """Wall time [s] of one ``-m`` sweep of ``runs`` default runs on ``workers`` processes."""
    seeds = ",".join(str(i) for i in range(runs))
    command = [
        sys.executable,
        "-m",
        "compliant_docking",
        "-m",
        f"task.misalignment.seed={seeds}",
        f"hydra.launcher.n_jobs={workers}",
        f"hydra.sweep.dir={out}",
    ]
    start = time.perf_counter()
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if result.returncode == 1:
        raise SystemExit(
            f"the sweep failed (exit {result.returncode}):\n{result.stdout[-2000:]}\n{result.stderr[-2000:]}"
        )
    return elapsed


def job_walls(out: Path) -> list[float]:
    return [json.loads(p.read_text())["wall_time_s"] for p in sorted(out.rglob("metrics.json"))]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=8)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args()

    load = os.getloadavg()[0]
    print(
        f"machine: {os.cpu_count()} cores, load average {load:.2f} (1 min)"
        + ("  <- busy: expect noisy numbers" if load > 0.5 else "")
    )
    times: dict[str, list[float]] = {"parallel": [], "commands": [], "inprocess": []}
    with tempfile.TemporaryDirectory(prefix="sweep_efficiency_") as tmp:
        for k in range(args.repeat):
            base = Path(tmp) / str(k)
            steps = [
                ("parallel", lambda: parallel(args.runs, args.workers, base / "par")),
                ("commands", lambda: commands(args.runs, base / "cmd")),
                ("inprocess", lambda: sequential(args.runs, base / "seq")),
            ]
            if k % 2:
                steps.reverse()
            t = {name: step() for name, step in steps}
            for name, value in t.items():
                times[name].append(value)
            print(
                f"[{k + 1}/{args.repeat}] parallel {t['parallel']:.1f} s "
                f"(job wall mean {statistics.mean(job_walls(base / 'par')):.2f} s) · "
                f"sequential commands {t['commands']:.1f} s · sequential in-process "
                f"{t['inprocess']:.1f} s (job wall mean {statistics.mean(job_walls(base / 'seq')):.2f} s)"
            )
    target = 0.6

    def ratios(baseline: str) -> tuple[float, float]:
        """(best: the least disturbed times of each, median of the per-repeat ratios)."""
        per_repeat = [p / b for p, b in zip(times["parallel"], times[baseline])]
        return min(times["parallel"]) / min(times[baseline]), statistics.median(per_repeat)

    best, median = ratios("commands")
    print(
        f"\n{args.runs} default docking runs on {args.workers} workers, parallel / sequential wall "
        f"time (ideal {1 / args.workers:.2f}; best = fastest of each over {args.repeat} repeats):"
    )
    print(
        f"  vs {args.runs} separate commands  : best {best:.3f}, median {median:.3f}  "
        f"(target <= {target}) -> {'PASS' if best <= target else 'FAIL'}"
    )
    best_in, median_in = ratios("inprocess")
    print(
        f"  vs in-process execute() : best {best_in:.3f}, median {median_in:.3f}  (stricter: "
        f"no start-up in the baseline)"
    )
    return 0 if best <= target else 1


if __name__ == "__main__":
    sys.exit(main())
