"""Console progress of a sweep: one line per finished job, with a running count.

With the joblib launcher each worker prints the line of the job it just ran
(:meth:`compliant_docking.sweep.callback.SweepCallback.on_job_end`); with submitit every job
prints into its own log file, so the launching process polls the sweep directory and
prints the lines itself (:class:`ProgressWatcher`).

This module is imported by the launching process and every job: keep it light.
"""

from __future__ import annotations

import logging
import os
import sys
import threading
import time
from pathlib import Path

from compliant_docking.run.rundir import FAILED_STATUSES, METRICS_FILE, read_metrics
from compliant_docking.sim.progress import duration_text

#: how often :class:`ProgressWatcher` looks for finished jobs [s]
POLL_INTERVAL_S = 2.0
#: the sweep's count of finished jobs (:func:`next_count`), hidden in the sweep directory
#: while the sweep runs
COUNT_FILE = ".finished_jobs"
COUNT_WIDTH = 20


#: the command-line flag that shows the launchers' per-job launch lines again, and the
#: Hydra override it stands for (conf/hydra/hydra_logging/console.yaml)
VERBOSE_FLAGS = ("-v", "--verbose")
VERBOSE_OVERRIDE = "hydra.hydra_logging.handlers.console.filters=[]"


class LaunchLines(logging.Filter):
    """Leaves out the launchers' per-job launch lines (``\t#<n> : controller=hqp …``: Hydra's
    joblib and submitit launchers and ours log one per job before any job runs), a
    ``logging`` filter named in the Hydra logging config conf/hydra/hydra_logging/console.yaml."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.msg).startswith("\t#")


def verbose_argv(argv: list[str]) -> list[str]:
    """``-v`` / ``--verbose`` replaced by the override that keeps the launch lines."""
    return [VERBOSE_OVERRIDE if arg in VERBOSE_FLAGS else arg for arg in argv]


def emit(text: str) -> None:
    """Print one line of sweep output, flushed at once, in one write: the workers share
    the console, and ``print`` writes the text and its newline separately, so two jobs
    finishing together could join their lines into one."""
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


def display(path: Path) -> str:
    """The path relative to the working directory when it lies below it."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def reset_count(sweep_dir: Path) -> None:
    """Start the sweep's count of finished jobs at 0 (the launching process, before any job);
    the sweep's start time (epoch seconds) follows the count, for the time left."""
    path = Path(sweep_dir) / COUNT_FILE
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"{0:<{COUNT_WIDTH}d}{time.time():.3f}\n")


def started_at(sweep_dir: Path) -> float | None:
    """When the sweep started (epoch seconds, from its count file); None when unknown."""
    try:
        return float(Path(sweep_dir, COUNT_FILE).read_text()[COUNT_WIDTH:].strip())
    except (OSError, ValueError):
        return None


def time_left(started: float | None, done: int | None, total: int | None, now: float | None = None) -> str:
    """``about 1 min 20 s left`` at the sweep's pace so far (its wall time per finished job
    times the jobs still to finish); "" when unknown, finished or under a second."""
    if started is None or not done or not total or done >= total:
        return ""
    left = ((time.time() if now is None else now) - started) / done * (total - done)
    return f"about {duration_text(left)} left" if left >= 0.5 else ""  # "about 0 s" says nothing


def remove_count(sweep_dir: Path) -> None:
    """Remove the count file (the sweep is over)."""
    Path(sweep_dir, COUNT_FILE).unlink(missing_ok=True)


def next_count(sweep_dir: Path) -> int | None:
    """This job's number among the finished jobs of the sweep: 1, 2, … in the order the
    jobs finish, each number given once even when two workers finish together.

    One exclusive lock (``flock``) on ``<sweep>/.finished_jobs`` around reading the count
    and writing it plus one: constant time per job, whatever the sweep's size, and safe
    across processes (and across machines on a file system with POSIX locks, e.g. NFSv4).
    None when the file cannot be locked, or is gone (no count is printed rather than a wrong
    one): the launching process creates it when the sweep starts and removes it when the
    sweep is summarised, so a job that ends later (an aborted sweep's) never recreates it.
    """
    try:
        import fcntl

        fd = os.open(Path(sweep_dir) / COUNT_FILE, os.O_RDWR)
    except (ImportError, OSError):
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)  # released by close(), also if the process dies
        count = int(os.pread(fd, COUNT_WIDTH, 0).decode().strip() or 0) + 1
        os.pwrite(fd, f"{count:<{COUNT_WIDTH}d}".encode(), 0)  # fixed width: no truncation
        return count
    except (OSError, ValueError):
        return None
    finally:
        os.close(fd)


def job_line(out_dir: Path, sweep_dir: Path, total: int | None, done: int | None = None) -> str:
    """``[3/6] 2_controller=hqp,robot=fr3 · finished · docked · peak 12.3 N · 4.2 s`` (status ok
    is "finished": the job ran; whether it docked is the next field); a bouncing hold adds
    ``· 203 contact events/s``, a failed gate its verdict (what failed).

    ``done``: the running count; by default the next number of :func:`next_count`.
    """
    record, problem = read_metrics(out_dir)
    if done is None:
        done = next_count(sweep_dir)
    shown = "?" if done is None else done
    count = f"[{shown}/{total}]" if total else f"[{shown} done]"
    if record is None:
        return f"{count} {out_dir.name} · {problem}"
    status = record.get("status")
    success = record.get("success")
    docked = {True: "docked", False: "not docked", None: "no gate"}.get(success, str(success))
    shown_status = {"failed": "FAILED", "interrupted": "INTERRUPTED", "ok": "finished"}.get(
        str(status), str(status)
    )
    parts = [f"{count} {out_dir.name}", shown_status]
    if status not in FAILED_STATUSES:
        parts.append(docked)
        peak, raw = record.get("filtered_peak_axial_force_N"), record.get("peak_axial_force_N")
        if peak is None:
            parts.append("peak n/a")
        else:  # the force the gate judges, and the raw per-step peak
            parts.append(f"peak {peak:.1f} N" + ("" if raw is None else f" (raw {raw:.1f} N)"))
        events = record.get("steady_contact_events_per_s")
        if events:  # a bouncing hold shows on the progress line
            parts.append(f"{events:.0f} contact events/s")
    wall = record.get("wall_time_s")
    parts.append("n/a" if wall is None else f"{wall:.1f} s")
    left = time_left(started_at(sweep_dir), done, total)
    if left:
        parts.append(left)
    if status in FAILED_STATUSES and record.get("error"):
        parts.append(clauses(str(record["error"])))
    elif success is False and record.get("gate_verdict"):
        parts.append(clauses(str(record["gate_verdict"])))  # what failed
    return " · ".join(parts)


#: about how long the error or verdict on a progress line may be [characters]
REASON_CHARS = 160


def clauses(text: str, limit: int = REASON_CHARS) -> str:
    """``text`` shortened to whole clauses (``; ``-separated, the first always whole) of
    about ``limit`` characters, ending ``; … (+N more)`` when some were left out: never cut
    inside a word or a number ("over the 5" of "over the 50 N budget")."""
    parts = " ".join(text.split()).split("; ")
    kept = parts[:1]
    for part in parts[1:]:
        if len("; ".join([*kept, part])) > limit:
            break
        kept.append(part)
    more = len(parts) - len(kept)
    return "; ".join(kept) + (f"; … (+{more} more)" if more else "")


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
