"""Where a command writes: a run or sweep directory of its own (the guards call
:func:`claim` after every check passed, before anything is created).

**The rule for a run or sweep directory** (README, docs/run_directory.md):

- a **default** name (``runs/<date>/<time>_<robot>_…``, ``runs/multirun/<date>/<time>``)
  has a resolution of one second; when it is taken the command takes the next free
  ``<name>_2``, ``<name>_3``… (``os.mkdir`` is atomic: of two processes exactly one
  creates a name);
- an **explicit** one (``hydra.run.dir=…``, ``hydra.sweep.dir=…``) must be new or empty,
  and must not lie inside another sweep's directory: a second command writing there would
  mix its results with the first's (metrics of one, figures of the other; a summary of
  both; a ``multirun.yaml`` that no longer resumes the first sweep). To reuse one, remove
  it first — there is no overwrite flag, so that nothing is deleted by a command;
- a directory the command **continues** is used as it is: ``resume=<sweep dir>`` (its
  ``multirun.yaml`` is checked against the command, sweep/resume.py) and a tuning study's
  own directory (the study checks what it holds, tune/sweeper.py).

The jobs' directories inside a sweep: compliant_docking/sweep/directories.py.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from omegaconf import DictConfig, OmegaConf, read_write

from compliant_docking.run.rundir import MULTIRUN_FILE

#: largest suffix tried for a taken directory name (``<name>_2`` … ``<name>_999``)
MAX_SUFFIX = 999

#: a path that needs no quotes as the value of a Hydra override
_PLAIN_PATH = re.compile(r"[A-Za-z0-9_/.\-]+")

#: the directories :func:`claim` created in this process (see :func:`release_empty`)
CLAIMED: list[Path] = []


def claim(
    config: DictConfig, kind: str, *, explicit: bool | None = None, continued: bool = False
) -> str | None:
    """Make the run or sweep (``kind``) directory of ``config`` this command's, by the rule
    of the module docstring; why not (one sentence), or None.

    ``explicit``: the directory was named by the user (default: ``hydra.<kind>.dir`` is among
    the command's Hydra overrides); ``continued``: the command continues what the directory
    holds (a resumed sweep, a tuning study). A default name that is taken is replaced in
    ``config`` by the next free one (for a sweep also in the Hydra overrides its jobs
    compose from).
    """
    key = f"hydra.{kind}.dir"
    path = Path(str(OmegaConf.select(config, key)))
    if explicit is None:
        explicit = any(str(o).split("=", 1)[0].lstrip("+") == key for o in config.hydra.overrides.hydra)
    if continued or explicit:
        problem = _writable(path, key)
        if problem is None:
            problem = _inside_a_sweep(path, key)
        if problem is None and not continued:
            problem = _taken(path, key, kind)
        if problem is None and not path.exists():
            path.mkdir(parents=True, exist_ok=True)
            CLAIMED.append(path)
        return problem
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        for n in range(1, MAX_SUFFIX + 1):
            candidate = path if n == 1 else path.with_name(f"{path.name}_{n}")
            try:
                candidate.mkdir()
                break
            except FileExistsError:
                continue
        else:
            return f"{key}: {path} and its {MAX_SUFFIX - 1} numbered variants are all taken; set {key}=<dir>."
    except OSError as exc:
        return (
            f"{key}: cannot create {path}: {exc.strerror or exc}; choose another directory with {key}=<dir>."
        )
    CLAIMED.append(candidate)
    if candidate != path:
        with read_write(config.hydra):
            OmegaConf.update(config, key, str(candidate))
            if kind == "sweep":  # the jobs compose their config again from the overrides
                value = override_value(str(candidate))
                config.hydra.overrides.hydra.append(f"{key}={value or candidate}")
    return None


def _taken(path: Path, key: str, kind: str) -> str | None:
    """Why the explicit directory ``path`` cannot take a new run or sweep (it holds files), or None."""
    if not path.is_dir():
        return None
    held = sorted(p.name for p in path.iterdir())
    if not held:
        return None
    shown = ", ".join(held[:4]) + (f", … ({len(held)} entries)" if len(held) > 4 else "")
    what = "a run" if kind == "run" else "a sweep"
    hint = (
        f"to finish the sweep in it, run that sweep's command with resume={path}; else "
        if (path / MULTIRUN_FILE).is_file() and kind == "sweep"
        else ""
    )
    return (
        f"{key}={path} is not empty ({shown}): {what} writes into a new or empty directory, so that "
        f"its results never mix with earlier ones; {hint}choose another directory or remove this one."
    )


def _inside_a_sweep(path: Path, key: str) -> str | None:
    """Why ``path`` may not be used: it lies inside another sweep's directory (whose summary
    and resume would count what this command writes), or None."""
    resolved = path.resolve()
    for parent in resolved.parents:
        if (parent / MULTIRUN_FILE).is_file():
            return (
                f"{key}={path} lies inside the sweep directory {parent}: that sweep's summary and "
                "resume would take this command's results for its own; choose a directory outside it."
            )
    return None


def release_empty() -> None:
    """Remove the directories this process claimed that stayed empty (a command refused or
    stopped after the claim): a refused command leaves nothing behind. A directory with
    anything in it stays."""
    while CLAIMED:
        path = CLAIMED.pop()
        try:
            path.rmdir()  # only an empty directory
        except OSError:
            pass


def _writable(path: Path, key: str) -> str | None:
    """Why the directory setting ``key`` = ``path`` cannot be written, as a refusal, or None."""
    problem = write_problem(path)
    return None if problem is None else f"{key}={path}: {problem}; choose another directory with {key}=<dir>."


def write_problem(path: Path) -> str | None:
    """Why nothing can be written at ``path`` (existing, or to be created), or None. Tried
    for real (a probe directory created and removed in ``path`` or its nearest existing
    parent): permission bits do not tell for root or a read-only file system."""
    import tempfile

    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"{existing} is not a directory"
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".write-probe-", dir=existing))
    except OSError as exc:
        return f"cannot write in {existing} ({exc.strerror or exc})"
    return None


def override_value(path: str) -> str | None:
    """``path`` as the value of a Hydra override (quoted when it needs to be); None when
    it cannot be written as one (quotes, backslashes or ``$`` in it)."""
    if _PLAIN_PATH.fullmatch(path):
        return path
    if any(c in path for c in "'\\$"):
        return None
    return f"'{path}'"
