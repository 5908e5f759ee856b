"""The directories of a sweep's jobs: each inside the sweep's, one per job (the sweep guard
checks them before anything is created); the sweep directory a job belongs to.

**Job directories** (:func:`job_dir_problems`): ``hydra.sweep.subdir`` names each job's
directory relative to the sweep's; every job's must lie strictly inside the sweep
directory (no absolute path, no ``..`` out of it), and no two jobs may share one or nest
one in the other: a constant ``hydra.sweep.subdir`` made every job write the same
directory, and a rerun in a resumed sweep empties the job's directory.

The run or sweep directory itself is claimed by compliant_docking/run/directories.py.
"""

from __future__ import annotations

import os
from pathlib import Path

from omegaconf import DictConfig, OmegaConf, read_write


def sweep_dir_of(hydra_cfg) -> Path:
    """The sweep directory of a job, absolute: a relative ``hydra.sweep.dir`` is taken from
    the directory the command started in (``hydra.runtime.cwd``), also in a job that
    ``hydra.job.chdir=true`` moved into its own directory."""
    path = Path(str(hydra_cfg.sweep.dir))
    if not path.is_absolute():
        path = Path(str(OmegaConf.select(hydra_cfg, "runtime.cwd") or os.getcwd())) / path
    return path.resolve()


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
