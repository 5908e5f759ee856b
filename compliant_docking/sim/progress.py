"""A run's console progress, with a sense of time: how far, how fast, how long still.

In a terminal (stderr a tty) a bar over the simulated seconds, updated once per
simulated second, with the real-time factor and the time left; it is cleared at the end
(the summary follows). In a log (stderr redirected, a batch job) plain lines, one at each
quarter of the run::

    simulated 4.5 / 18.0 s (25 %) · 3.1× real time · about 4 s left

``task.progress=false`` shows neither.
"""

from __future__ import annotations

import sys
import time

#: the plain lines' marks, as fractions of the run
LOG_MARKS = (0.25, 0.5, 0.75)
#: characters of the terminal's bar
BAR_WIDTH = 30


def duration_text(seconds: float) -> str:
    """``7 s``, ``2 min 05 s``, ``1 h 03 min``: whole units, never cut inside a number."""
    seconds = max(int(round(seconds)), 0)
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60:02d} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60:02d} min"


class RunProgress:
    """The progress of one run's loop; :meth:`update` is called every few steps with the
    step index, :meth:`done` at the end."""

    def __init__(self, n_steps: int, dt: float, enabled: bool):
        self.enabled = enabled
        self.n_steps, self.dt = n_steps, dt
        self.every = max(int(round(1.0 / dt)), 1)  # one update per simulated second
        self.tty = sys.stderr.isatty()
        self.start = time.perf_counter()
        self.marks = [m for m in (int(f * n_steps) for f in LOG_MARKS) if m > 0]
        self.bar = enabled and self.tty  # a bar redrawn in place (\r) in a terminal

    def update(self, k: int) -> None:
        if not self.enabled:
            return
        if self.bar:
            if k % self.every == 0 and k:
                pace = self.pace(k, time.perf_counter() - self.start)
                filled = min(int(BAR_WIDTH * k / self.n_steps), BAR_WIDTH)  # a held reference runs on
                sys.stderr.write(
                    f"\r  simulating {k * self.dt:.1f}/{self.n_steps * self.dt:.1f} s "
                    f"|{'█' * filled}{' ' * (BAR_WIDTH - filled)}| {pace}   "
                )
                sys.stderr.flush()
        elif self.marks and k >= self.marks[0]:
            while self.marks and k >= self.marks[0]:
                self.marks.pop(0)
            sys.stderr.write(self.line(k, time.perf_counter() - self.start) + "\n")
            sys.stderr.flush()

    def line(self, k: int, elapsed: float) -> str:
        """The plain progress line after step ``k``, ``elapsed`` wall seconds in."""
        done, total = k * self.dt, self.n_steps * self.dt
        return (
            f"  simulated {done:.1f} / {total:.1f} s ({100 * k / self.n_steps:.0f} %) · "
            f"{self.pace(k, elapsed)}"
        )

    def pace(self, k: int, elapsed: float) -> str:
        """``3.1× real time · about 4 s left`` after step ``k``, ``elapsed`` wall seconds in:
        the end of the plain line and of the terminal's bar."""
        done, total = k * self.dt, self.n_steps * self.dt
        rate = done / max(elapsed, 1e-9)
        if rate <= 0:
            left = "time left unknown"
        else:
            seconds = (total - done) / rate
            left = f"about {duration_text(seconds)} left" if seconds >= 0.5 else "under a second left"
        return f"{rate:.1f}× real time · {left}"

    def done(self) -> None:
        if self.bar:
            sys.stderr.write("\r" + " " * (BAR_WIDTH + 80) + "\r")  # cleared: the summary follows
            sys.stderr.flush()
            self.bar = False
