"""Where a command writes: a run or sweep directory of its own, and job directories that
stay inside their sweep, one per job (the guard calls these before anything is created).

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

**Job directories** (:func:`job_dir_problems`): ``hydra.sweep.subdir`` names each job's
directory relative to the sweep's; every job's must lie strictly inside the sweep
directory (no absolute path, no ``..`` out of it), and no two jobs may share one or nest
one in the other: a constant ``hydra.sweep.subdir`` made every job write the same
directory, and a rerun in a resumed sweep empties the job's directory.
"""

from __future__ import annotations

import os
from pathlib import Path

from omegaconf import DictConfig, OmegaConf, read_write

#: largest suffix tried for a taken directory name (``<name>_2`` … ``<name>_999``)
MAX_SUFFIX = 999
#: the sweep directory's record of the sweep (Hydra writes it): marks a sweep directory
MULTIRUN_FILE = "multirun.yaml"

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
    ``config`` by the next free one.
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
                config.hydra.overrides.hydra.append(f"{key}={_quoted(str(candidate))}")
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
    """Why ``path`` (existing, or to be created) cannot be written, or None. Tried for real
    (a probe directory created and removed in ``path`` or its nearest existing parent):
    permission bits do not tell for root or a read-only file system."""
    import tempfile

    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"{key}={path}: {existing} is not a directory; choose another directory with {key}=<dir>."
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".write-probe-", dir=existing))
    except OSError as exc:
        return (
            f"{key}={path}: cannot write in {existing} ({exc.strerror or exc}); "
            f"choose another directory with {key}=<dir>."
        )
    return None


def _quoted(path: str) -> str:
    """``path`` as the value of a Hydra override."""
    from compliant_docking.sweep.resume import ResumeError, _override_value

    try:
        return _override_value(path)
    except ResumeError:
        return path


def sweep_dir_of(hydra_cfg) -> Path:
    """The sweep directory of a job, absolute: a relative ``hydra.sweep.dir`` is taken from
    the directory the command started in (``hydra.runtime.cwd``), also in a job that
    ``hydra.job.chdir=true`` moved into its own directory."""
    path = Path(str(hydra_cfg.sweep.dir))
    if not path.is_absolute():
        path = Path(str(OmegaConf.select(hydra_cfg, "runtime.cwd") or os.getcwd())) / path
    return path.resolve()


# --------------------------------------------------------------------------- job directories
def job_subdir(job: DictConfig, num: int) -> str:
    """The directory of job ``num`` relative to its sweep's, as Hydra's ``run_job`` will
    compose it (``hydra.sweep.subdir``, with ``hydra.job.num`` set as the launcher sets it)."""
    with read_write(job.hydra):
        job.hydra.job.num = num
    try:
        return str(OmegaConf.select(job, "hydra.sweep.subdir", throw_on_resolution_failure=True))
    except Exception:  # a subdir that reads ${hydra:…}: resolve it on a copy set as Hydra's config
        import copy

        from hydra.core.hydra_config import HydraConfig

        hydra_config, clone = HydraConfig.instance(), copy.deepcopy(job)
        saved = hydra_config.cfg
        hydra_config.set_config(clone)  # (makes clone.hydra read-only: not the job's own config)
        try:
            return str(OmegaConf.select(clone, "hydra.sweep.subdir"))
        finally:
            hydra_config.cfg = saved


def job_dir_problems(subdirs: dict[int, str]) -> list[str]:
    """Why the jobs' directories (job number → ``hydra.sweep.subdir``) cannot be used: one
    outside the sweep directory, two the same or one inside another; [] when each job has
    a directory of its own inside the sweep."""
    found: list[str] = []
    normal: dict[int, tuple[str, ...]] = {}
    for num, subdir in subdirs.items():
        parts = Path(os.path.normpath(subdir)).parts if subdir else ()
        if not subdir or os.path.isabs(subdir) or not parts or parts[0] in (".", ".."):
            found.append(
                f"hydra.sweep.subdir must name a directory inside the sweep directory (relative, "
                f"without '..' leading out of it); job {num}'s is {subdir!r}."
            )
        else:
            normal[num] = parts
    owner: dict[tuple[str, ...], int] = {}
    for num, parts in sorted(normal.items(), key=lambda item: len(item[1])):
        clash = next((owner[parts[:n]] for n in range(1, len(parts) + 1) if parts[:n] in owner), None)
        if clash is not None:
            how = "the same directory as" if owner.get(parts) == clash else "a directory inside that of"
            found.append(
                f"hydra.sweep.subdir must give every job a directory of its own; job {num} would write "
                f"{how} job {clash} ({'/'.join(parts)!r}): include ${{hydra.job.num}} in it."
            )
            break  # one example is enough
        owner[parts] = num
    return found
