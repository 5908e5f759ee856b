"""The signals that stop a command, and holding them while something must be finished.

SIGINT (Ctrl-C), SIGTERM (``kill``, Slurm's ``scancel``) and SIGHUP (the terminal closed)
stop a run or a sweep the same way: the command line's handler (:func:`raise_stop`)
raises :class:`Stopped`, a ``KeyboardInterrupt`` carrying the signal's number, so every
place that handles Ctrl-C handles them all; the run records itself as "interrupted"
(run/runner.py), a sweep stops its workers and summarises what finished, and the command
exits ``128 + signal number`` (130, 143, 129) without a traceback.

Some stretches must not be cut short. :func:`hold` makes the three signals wait (they are
noted, not acted on) and :func:`release` acts on the first one that came:

- from the moment a run's directory is claimed until its runner is ready to record an
  interruption (Hydra writes ``.hydra/`` and the libraries are imported meanwhile): a
  signal there used to leave a directory without a record, or an import error;
- while a run's record or a sweep's summary is written (:func:`deferred`).

This module is imported early by the command line: keep it free of heavy imports (a
handler must never import a module that may be half imported).
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Callable, Iterator

from compliant_docking import exit_codes

#: the signals that stop a command
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: how a record names each
NAMES = {int(signal.SIGINT): "SIGINT (Ctrl-C)", int(signal.SIGTERM): "SIGTERM", int(signal.SIGHUP): "SIGHUP"}


class Stopped(KeyboardInterrupt):
    """The command is stopped by signal ``signum``."""

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__()
        self.signum = int(signum)


def signum_of(exc: BaseException) -> int:
    """The signal an interruption came from (a plain KeyboardInterrupt: SIGINT)."""
    return int(getattr(exc, "signum", signal.SIGINT))


def exit_status(exc: BaseException) -> int:
    """``128 + signal number``: 130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP."""
    return exit_codes.interrupted(signum_of(exc))


def name(signum: int) -> str:
    return NAMES.get(signum, f"signal {signum}")


#: the stop signals this process received through :func:`raise_stop`, in order
_received: list[int] = []


def raise_stop(signum: int, frame) -> None:
    """The command line's handler of every signal in :data:`SIGNALS`."""
    _received.append(signum)
    raise Stopped(signum)


def forget() -> None:
    """A new command starts: no stop signal received yet (a process may run several)."""
    _received.clear()


def received() -> int | None:
    """The first stop signal this process received (None: none): an error raised after it
    comes from code the signal cut short, and the command line reports the stop instead."""
    return _received[0] if _received else None


def handled(command: str, main: Callable[[], int]) -> int:
    """Run ``main``, the body of a command other than the simulation's (report, findings,
    interface), with the stop signals handled as the simulation's are: one line on stderr,
    exit status 128 + signal number, no traceback. Those commands write each file
    atomically, so a stop leaves every file as it was or whole."""
    previous = {s: signal.signal(s, raise_stop) for s in SIGNALS} if _main_thread() else {}
    try:
        return main()
    except KeyboardInterrupt as exc:
        print(f"{command}: stopped by {name(signum_of(exc))}", file=sys.stderr, flush=True)
        return exit_status(exc)
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


# --------------------------------------------------------------------------- holding
_held: dict[int, object] | None = None  # the handlers to put back, while held
_pending: list[int] = []


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def hold() -> None:
    """Note the signals instead of acting on them until :func:`release` (main thread only;
    elsewhere Python cannot change handlers, and a second hold changes nothing)."""
    global _held
    if _held is not None or not _main_thread():
        return
    _pending.clear()
    _held = {s: signal.signal(s, lambda signum, frame: _pending.append(signum)) for s in SIGNALS}


def release(*, stop: bool = True) -> None:
    """Put the handlers back; then, if a signal came while they were held and ``stop``,
    raise :class:`Stopped` for the first one."""
    global _held
    if _held is None:
        return
    for signum, handler in _held.items():
        signal.signal(signum, handler)  # type: ignore[arg-type]
    _held = None
    came = list(_pending)
    _pending.clear()
    _received.extend(came)
    if came and stop:
        raise Stopped(came[0])


@contextlib.contextmanager
def deferred() -> Iterator[list[int]]:
    """Hold the signals for the ``with`` block (which must not be cut short: a record, a
    summary); the yielded list holds the ones that came, for the caller to act on after."""
    if _held is not None or not _main_thread():  # held already, or not ours to hold
        yield []
        return
    hold()
    came: list[int] = []
    try:
        yield came
    finally:
        came.extend(_pending)
        release(stop=False)
