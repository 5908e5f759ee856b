"""MuJoCo's warnings go to the run that caused them, never to ``MUJOCO_LOG.TXT``.

MuJoCo's default warning handler prints a warning (e.g. "Nan, Inf or huge value in QACC"
when a simulation diverges) and appends it to ``MUJOCO_LOG.TXT`` in the working
directory — the repository root, where the untracked file would make every later run
record ``git_dirty: true``. :func:`captured` installs MuJoCo's user warning callback
(``mujoco.set_mju_user_warning``) for the duration of a run and collects the messages;
the runner writes them to the run directory (``mujoco.log``) and counts them in
``metrics.json`` (``mujoco_warnings``). ``MUJOCO_LOG.TXT`` is also git-ignored, for
scripts that step MuJoCo outside a run.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import mujoco

#: messages kept per run (a diverging run can warn at every step)
MAX_MESSAGES = 100


@contextlib.contextmanager
def captured() -> Iterator[list[str]]:
    """Collect MuJoCo's warnings into the yielded list (at most :data:`MAX_MESSAGES`; later
    ones are counted in a last line) instead of printing them and writing MUJOCO_LOG.TXT."""
    messages: list[str] = []
    dropped = [0]

    def keep(message: str) -> None:
        if len(messages) < MAX_MESSAGES:
            messages.append(str(message).strip())
        else:
            dropped[0] += 1

    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(keep)
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)
        if dropped[0]:
            messages.append(f"… and {dropped[0]} more warnings")
