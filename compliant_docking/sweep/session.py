"""The state of the sweep a launching process runs, as one explicit object.

The command line (:mod:`compliant_docking.cli`) opens a :class:`SweepSession` around
Hydra's run; Hydra instantiates the sweep callback from the config, and the callback
finds the session through :func:`SweepSession.current` (a context variable: the session
exists exactly while the command runs, and a test can open its own). The session
records what the sweep is (directory, job count, launcher, start time, the submitit
progress watcher) and, at the end, its :class:`~compliant_docking.sweep.outcome.SweepOutcome`;
the command line reads the outcome for its exit status, or summarises an aborted sweep.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path

from compliant_docking.sweep.outcome import SweepOutcome, summarise
from compliant_docking.sweep.progress import ProgressWatcher, remove_count, reset_count

_CURRENT: ContextVar[SweepSession | None] = ContextVar("compliant_docking_sweep", default=None)


@dataclass
class SweepSession:
    """One sweep of the launching process (see the module docstring)."""

    sweep_dir: Path | None = None
    total: int | None = None  # jobs to run, None: unknown
    started: float | None = None  # time.perf_counter() at the start
    independent_jobs: bool = False  # submitit: jobs are processes that outlive the launcher
    watcher: ProgressWatcher | None = None
    outcome: SweepOutcome | None = None
    #: called with the outcome once the sweep is summarised (e.g. the MLflow callback's
    #: parent run, which wants the summary files: Hydra calls the end-of-sweep callbacks
    #: in reverse order, so a callback listed after the sweep callback ends before it)
    after_finish: list[Callable[[SweepOutcome], None]] = field(default_factory=list)
    preloading: threading.Thread | None = None

    @staticmethod
    def current() -> SweepSession:
        """The open session; a new one (opened now) if the command line opened none."""
        session = _CURRENT.get()
        if session is None:
            session = SweepSession()
            _CURRENT.set(session)
        return session

    @classmethod
    @contextlib.contextmanager
    def open(cls) -> Iterator[SweepSession]:
        """A fresh session for the duration of a command."""
        session = cls()
        token = _CURRENT.set(session)
        try:
            yield session
        finally:
            session.stop_watcher()
            session._join_preload()  # never leave an import running into interpreter exit
            _CURRENT.reset(token)

    def begin(self, sweep_dir: Path, total: int | None, *, independent_jobs: bool) -> None:
        """The sweep starts (the callback's ``on_multirun_start``)."""
        self.sweep_dir, self.total = Path(sweep_dir), total
        self.started, self.independent_jobs, self.outcome = time.perf_counter(), independent_jobs, None
        reset_count(self.sweep_dir)  # the jobs number themselves 1, 2, … as they finish

    def preload(self, *, figures: bool) -> None:
        """Import what the summary at the end needs — pandas, and matplotlib when it draws
        the comparison figures: ~0.3 s each — in a background thread while worker
        processes run the jobs (this process only waits for them then), so the end of the
        sweep, when one core has nothing to do, is that much shorter. Not for jobs run in
        this process (hydra/launcher=basic): the thread would slow their loops."""

        def load() -> None:
            try:
                import compliant_docking.results  # noqa: F401  (pandas)

                if figures:
                    from compliant_docking.results import figures as _  # noqa: F401
                    from compliant_docking.viz.style import apply_style

                    apply_style()  # matplotlib and the style
            except Exception:  # the summary imports them itself and reports what fails
                pass

        self.preloading = threading.Thread(target=load, name="sweep-preload", daemon=True)
        self.preloading.start()

    def _join_preload(self) -> None:
        thread, self.preloading = self.preloading, None
        if thread is not None:
            thread.join()

    def watch(self, watcher: ProgressWatcher) -> None:
        self.watcher = watcher.start()

    def stop_watcher(self) -> None:
        watcher, self.watcher = self.watcher, None
        if watcher is not None:
            watcher.stop()

    def finish(
        self, sweep_dir: Path, *, figures: bool, aborted: bool = False, strict: bool = True
    ) -> SweepOutcome:
        """Summarise the sweep (files, console counts) and keep its outcome (``strict``:
        a failed job makes the exit status 1). A signal that comes meanwhile waits until the
        summary is written, then stops the command (run/interrupt.py)."""
        from compliant_docking.run import interrupt
        from compliant_docking.sweep.workers import release_workers

        with interrupt.deferred() as came:
            release_workers()  # every job has returned: the idle workers exit while this summarises
            self.stop_watcher()
            self._join_preload()
            remove_count(Path(sweep_dir))
            known = self.sweep_dir is not None and Path(sweep_dir) == self.sweep_dir
            self.outcome = summarise(
                sweep_dir,
                figures=figures,
                aborted=aborted,
                total=self.total if known else None,
                started=self.started,
                independent_jobs=self.independent_jobs,
                strict=strict,
            )
            for hook in self.after_finish:
                try:
                    hook(self.outcome)
                except Exception as exc:  # a hook never changes the outcome
                    import sys

                    print(f"sweep: {exc}", file=sys.stderr)
        if came:
            raise interrupt.Stopped(came[0])
        return self.outcome

    def discard(self) -> None:
        """The sweep was refused before any job ran (e.g. a tuning set-up that cannot be
        used): nothing to summarise, neither now nor when the command unwinds, and no count
        file left behind."""
        self.stop_watcher()
        if self.sweep_dir is not None:
            remove_count(self.sweep_dir)
        self.sweep_dir, self.total, self.started = None, None, None

    def finish_aborted(self) -> SweepOutcome | None:
        """Summarise a sweep that Hydra aborted (worker crash, Ctrl-C, SIGTERM); None when no
        sweep started or it was summarised already."""
        if self.sweep_dir is None or self.outcome is not None:
            self.stop_watcher()
            return None
        try:
            return self.finish(self.sweep_dir, figures=False, aborted=True)
        except KeyboardInterrupt:  # another signal while it was summarised: written, the command stops
            return self.outcome
        except Exception as exc:  # never mask the original error
            import sys

            print(f"sweep: could not summarise the aborted sweep: {exc}", file=sys.stderr)
            return None
