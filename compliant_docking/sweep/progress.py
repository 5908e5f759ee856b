"""Console progress of a sweep: one line per finished job, with a running count.

With the joblib launcher each worker prints the line of the job it just ran
(:meth:`compliant_docking.sweep.callback.SweepCallback.on_job_end`); with submitit every job
prints into its own log file, so the launching process polls the sweep directory and
prints the lines itself (:class:`ProgressWatcher`).

This module is imported by the launching process and every job: keep it light.
"""

from __future__ import annotations

import threading
from pathlib import Path

from compliant_docking.run.rundir import METRICS_FILE, read_metrics

#: how often :class:`ProgressWatcher` looks for finished jobs [s]
POLL_INTERVAL_S = 2.0


def emit(text: str) -> None:
    """Print one line of sweep output, flushed at once (workers share the console)."""
    print(text, flush=True)


def display(path: Path) -> str:
    """The path relative to the working directory when it lies below it."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def finished_rank(out_dir: Path, sweep_dir: Path, depth: int = 1) -> int:
    """The job's place among the finished jobs of the sweep: how many metrics.json files
    ``depth`` levels below ``sweep_dir`` were written no later than its own (by
    modification time, then path). Unlike a plain count, two workers finishing at the
    same moment still get different numbers."""

    def key(path: Path) -> tuple[int, str]:
        try:
            return path.stat().st_mtime_ns, str(path)
        except OSError:  # replaced while we looked
            return 0, str(path)

    own = key(Path(out_dir) / METRICS_FILE)
    return sum(1 for p in Path(sweep_dir).glob("*/" * depth + METRICS_FILE) if key(p) <= own)


def job_line(out_dir: Path, sweep_dir: Path, total: int | None, done: int | None = None) -> str:
    """``[3/6] 2_controller=hqp,robot=fr3 · ok · docked · peak 12.3 N · 4.2 s``.

    ``done``: the running count; by default the job's rank among the finished jobs.
    """
    record, problem = read_metrics(out_dir)
    try:
        depth = len(out_dir.resolve().relative_to(sweep_dir).parts)
    except ValueError:
        depth = 1
    if done is None:
        done = finished_rank(out_dir, sweep_dir, depth)
    count = f"[{done}/{total}]" if total else f"[{done} done]"
    if record is None:
        return f"{count} {out_dir.name} · {problem}"
    status = record.get("status")
    success = record.get("success")
    docked = {True: "docked", False: "not docked", None: "no gate"}.get(success, str(success))
    parts = [f"{count} {out_dir.name}", "FAILED" if status == "failed" else str(status)]
    if status != "failed":
        parts.append(docked)
        peak = record.get("peak_axial_force_N")
        parts.append("peak n/a" if peak is None else f"peak {peak:.1f} N")
    wall = record.get("wall_time_s")
    parts.append("n/a" if wall is None else f"{wall:.1f} s")
    if status == "failed" and record.get("error"):
        parts.append(str(record["error"])[:160])
    return " · ".join(parts)


class ProgressWatcher:
    """Prints the progress line of every job that finishes while the sweep runs.

    A daemon thread of the launching process polls ``<sweep>/*/metrics.json`` (the
    depth of the sweep's job directories) every ``interval_s``; a file that is new, or
    rewritten since the sweep started (a rerun job of a resumed sweep), gets its line
    from :func:`job_line`. :meth:`stop` polls a last time.
    """

    def __init__(
        self, sweep_dir: Path, total: int | None, interval_s: float = POLL_INTERVAL_S, depth: int = 1
    ) -> None:
        self.sweep_dir = Path(sweep_dir)
        self.total = total
        self.interval_s = float(interval_s)
        self.pattern = "*/" * depth + METRICS_FILE
        self._seen = self._snapshot()
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, name="sweep-progress", daemon=True)

    def _snapshot(self) -> dict[Path, int]:
        found = {}
        for path in self.sweep_dir.glob(self.pattern):
            try:
                found[path] = path.stat().st_mtime_ns
            except OSError:  # replaced while we looked
                pass
        return found

    def start(self) -> ProgressWatcher:
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            self.poll()

    def poll(self) -> None:
        """Print the lines of the jobs finished since the last poll."""
        with self._lock:
            now = self._snapshot()
            new = sorted((p for p, mtime in now.items() if self._seen.get(p) != mtime), key=lambda p: now[p])
            self._seen = now
            for i, path in enumerate(new):  # oldest first, with a running count
                try:
                    done = len(now) - (len(new) - 1 - i)
                    emit(job_line(path.parent, self.sweep_dir.resolve(), self.total, done))
                except Exception as exc:  # progress must never stop a sweep
                    emit(f"(progress line failed: {exc})")

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=10)
        self.poll()
