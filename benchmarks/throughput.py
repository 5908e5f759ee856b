"""Sweep throughput, as ratios measured in one run: where a job's time goes.

    python benchmarks/throughput.py                    # everything (~5 min on 2 cores)
    python benchmarks/throughput.py --no-presets       # without the three preset sweeps
    python benchmarks/throughput.py --only sweep cli   # some sections only

Sections (each timed here, in this run, so their ratios compare like with like):

- **cli**: the whole default single command ``python -m compliant_docking`` (figures
  included), best and median of ``--repeats``, and its CPU time; ``import
  compliant_docking.cli`` alone (interpreter + Hydra), the start-up floor of a command.
- **bookkeeping**: the per-job cost of a sweep outside the simulation loop, on the
  sweep's own code path: two ``hydra/launcher=basic`` sweeps of 1 and N default jobs,
  each job run one after another in one process; the slope (W_N − W_1)/(N − 1) is what
  one more job costs (composing and validating its config, building the scene, the
  loop, the metrics, the files, Hydra's job files), and bookkeeping = slope − the mean
  loop time. Also in CPU time (slope of the commands' CPU time − the loop's CPU time,
  measured in this process), which other work on the machine does not inflate.
- **sweep**: a ``--jobs``-job default sweep on 2 joblib workers: wall time, Σ
  ``loop_wall_time_s`` and the loop share Σ loop / (2 × wall) (acceptance ≥ 0.5), the
  time outside the jobs (wall − Σ wall_time_s / 2), the sweep's CPU time and the loops'
  part of it; plus the end-of-sweep summary (files, comparison figures) timed alone.
- **loop**: real-time factor and loop / physics-only replay per robot × controller
  (best of ``--repeats``; benchmarks/loop_speed.py's measurement).
- **presets**: wall time and loop share of each ``+experiment=`` sweep (one run each).

The machine is a shared 2-core VM: absolute times move with its load (printed first and
last); ratios measured in one run, and CPU times, are what to compare.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "benchmarks"))

SECTIONS = ("cli", "bookkeeping", "sweep", "loop", "presets")
PRESETS = ("controller_comparison", "misalignment", "clearance")
#: the targets of a sweep's overhead
LOOP_SHARE_TARGET = 0.5
BOOKKEEPING_TARGET_S = 0.3
CLI_TARGET_S = 3.0


def command(args: list[str]) -> tuple[float, float]:
    """(wall, CPU) [s] of ``python -m compliant_docking ARGS``; exit status 1 stops the
    benchmark. CPU is the user + system time of the command and of every process it
    waited for (its workers)."""
    before = _children_cpu()
    start = time.perf_counter()
    result = subprocess.run(
        [sys.executable, "-m", "compliant_docking", *args], cwd=REPO, capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    if result.returncode == 1:
        raise SystemExit(
            f"command failed: {' '.join(args)}\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}"
        )
    return wall, _children_cpu() - before


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def loop_cpu(repeats: int) -> float:
    """CPU time [s] of the default run's simulation loop in this process (least of
    ``repeats``): what the loop of a job costs, which its wall time hides on a busy machine."""
    from compliant_docking.config import load_config
    from compliant_docking.sim.simulate import prepare

    best = float("inf")
    for _ in range(repeats):
        sim = prepare(load_config("task.progress=false"))
        start = time.process_time()
        sim.run()
        best = min(best, time.process_time() - start)
    return best


def records(sweep_dir: Path) -> list[dict]:
    return [json.loads(p.read_text()) for p in sorted(Path(sweep_dir).glob("*/metrics.json"))]


def seeds(n: int) -> str:
    return "task.misalignment.seed=" + ",".join(str(i) for i in range(n))


def verdict(ok: bool) -> str:
    return "met" if ok else "MISSED"


# --------------------------------------------------------------------------- sections
def section_cli(tmp: Path, repeats: int) -> None:
    runs = [command([f"hydra.run.dir={tmp / f'cli{i}'}", "task.progress=false"]) for i in range(repeats)]
    walls = [wall for wall, _ in runs]
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import compliant_docking.cli"], cwd=REPO, check=True)
    imports = time.perf_counter() - start
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", "pass"], cwd=REPO, check=True)
    bare = time.perf_counter() - start
    loop = statistics.mean(
        json.loads((tmp / f"cli{i}" / "metrics.json").read_text())["loop_wall_time_s"] for i in range(repeats)
    )
    best = min(walls)
    figures = sorted(p.name for p in (tmp / "cli0").glob("figures/*"))
    print("\n## whole default command `python -m compliant_docking` (figures included)")
    print(
        f"  best {best:.2f} s, median {statistics.median(walls):.2f} s of {repeats} "
        f"(target ≤ {CLI_TARGET_S:g} s: {verdict(best <= CLI_TARGET_S)}); its loop {loop:.2f} s"
    )
    print(f"  CPU time {min(cpu for _, cpu in runs):.2f} s (least of {repeats})")
    print(f"  start-up: bare interpreter {bare:.2f} s, `import compliant_docking.cli` {imports:.2f} s")
    print(f"  figures: {len(figures)} files ({', '.join(figures) or 'none'})")


def section_bookkeeping(tmp: Path, jobs: int, repeats: int) -> None:
    basic = [
        "hydra/launcher=basic",
        "hydra.callbacks.sweep.progress=false",
        "hydra.callbacks.sweep.figures=false",
    ]
    w1, c1 = command(["-m", seeds(1), *basic, f"hydra.sweep.dir={tmp / 'basic1'}"])
    wn, cn = command(["-m", seeds(jobs), *basic, f"hydra.sweep.dir={tmp / 'basicN'}"])
    recs = records(tmp / "basicN")
    loop = statistics.mean(r["loop_wall_time_s"] for r in recs)
    inside = statistics.mean(r["wall_time_s"] - r["loop_wall_time_s"] for r in recs)
    slope, slope_cpu = (wn - w1) / (jobs - 1), (cn - c1) / (jobs - 1)
    book = slope - loop
    loop_c = loop_cpu(repeats)
    figures = any((tmp / "basicN").glob("*/figures"))
    print(
        f"\n## per-job bookkeeping in a sweep (everything but the loop), {jobs} default jobs in one process"
    )
    print(
        f"  sweep of 1 job {w1:.2f} s, of {jobs} jobs {wn:.2f} s → one more job {slope:.2f} s, its loop {loop:.2f} s"
    )
    print(
        f"  bookkeeping per job {book:.2f} s (target ≤ {BOOKKEEPING_TARGET_S:g} s: "
        f"{verdict(book <= BOOKKEEPING_TARGET_S)}): inside runner.execute {inside:.2f} s, "
        f"Hydra around it (compose, validate, job files) {book - inside:.2f} s"
    )
    print(
        f"  in CPU time: one more job {slope_cpu:.2f} s, its loop {loop_c:.2f} s → "
        f"bookkeeping {slope_cpu - loop_c:.2f} s"
    )
    print(f"  per-job figures in the sweep: {'yes' if figures else 'no'}")


def section_sweep(tmp: Path, jobs: int, repeats: int) -> None:
    out = tmp / "sweep"
    wall, cpu = command(["-m", seeds(jobs), "hydra.launcher.n_jobs=2", f"hydra.sweep.dir={out}"])
    recs = records(out)
    loop = sum(r["loop_wall_time_s"] for r in recs)
    execute = sum(r["wall_time_s"] for r in recs)
    share = loop / (2 * wall)
    loops_cpu = len(recs) * loop_cpu(repeats)
    print(f"\n## {jobs}-job default sweep on 2 workers")
    print(f"  wall {wall:.2f} s, Σ loop {loop:.2f} s, Σ job wall_time_s {execute:.2f} s")
    print(
        f"  loop share Σ loop / (2 × wall) = {share:.3f} (target ≥ {LOOP_SHARE_TARGET}: "
        f"{verdict(share >= LOOP_SHARE_TARGET)})"
    )
    print(
        f"  outside the jobs' execute (start-up, compose, spawn, imports, summary): "
        f"wall − Σ wall_time_s / 2 = {wall - execute / 2:.2f} s"
    )
    print(
        f"  CPU time of the sweep {cpu:.2f} s (all processes), its loops ≈ {loops_cpu:.2f} s "
        f"({loops_cpu / cpu:.0%}); cores kept busy: CPU / (2 × wall) = {cpu / (2 * wall):.2f}"
    )
    from compliant_docking.sweep.outcome import summarise

    with contextlib.redirect_stdout(io.StringIO()):  # its console summary
        start = time.perf_counter()
        summarise(out, figures=False)
        tables = time.perf_counter() - start
        start = time.perf_counter()
        summarise(out, figures=True)
        both = time.perf_counter() - start
    print(
        f"  end-of-sweep summary, again in this process: tables {tables:.2f} s, "
        f"with the comparison figures {both:.2f} s"
    )


def section_loop(repeats: int) -> None:
    from loop_speed import measure

    print(f"\n## loop speed (best of {repeats}): real-time factor, loop/replay")
    print(f"  {'robot':8} {'controller':11} {'RTF':>6} {'loop µs':>8} {'replay µs':>10} {'loop/replay':>12}")
    for robot in ("iiwa14", "fr3"):
        for controller in ("impedance", "hqp", "se3_lie"):
            runs = [measure([f"robot={robot}", f"controller={controller}"]) for _ in range(repeats)]
            rtf, loop_us, replay_us = max(runs, key=lambda r: r[0])
            print(
                f"  {robot:8} {controller:11} {rtf:6.1f} {loop_us:8.1f} {replay_us:10.1f} {loop_us / replay_us:12.2f}"
            )


def section_presets(tmp: Path) -> None:
    print("\n## presets (one run each, 2 workers)")
    for preset in PRESETS:
        out = tmp / f"preset_{preset}"
        wall, cpu = command(["-m", f"+experiment={preset}", f"hydra.sweep.dir={out}"])
        recs = records(out)
        loop = sum(r["loop_wall_time_s"] or 0.0 for r in recs)
        print(
            f"  {preset:22} {len(recs):3d} jobs  {wall:6.1f} s  CPU {cpu:6.1f} s  loop share {loop / (2 * wall):.2f}"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=SECTIONS, default=list(SECTIONS))
    parser.add_argument("--no-presets", action="store_true", help="skip the preset sweeps")
    parser.add_argument("--jobs", type=int, default=16, help="jobs of the default sweep")
    parser.add_argument("--bookkeeping-jobs", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    sections = [s for s in args.only if not (s == "presets" and args.no_presets)]

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True)
    print(
        f"commit {commit.stdout.strip()} · {os.cpu_count()} cores · load average "
        f"{os.getloadavg()[0]:.2f} (1 min) · {time.strftime('%Y-%m-%d %H:%M')}"
    )
    with tempfile.TemporaryDirectory(prefix="throughput_") as name:
        tmp = Path(name)
        for section in sections:
            if section == "cli":
                section_cli(tmp, args.repeats)
            elif section == "bookkeeping":
                section_bookkeeping(tmp, args.bookkeeping_jobs, args.repeats)
            elif section == "sweep":
                section_sweep(tmp, args.jobs, args.repeats)
            elif section == "loop":
                section_loop(args.repeats)
            elif section == "presets":
                section_presets(tmp)
    print(f"\nload average at the end {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
