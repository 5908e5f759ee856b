"""The OmegaConf resolvers the config files use, registered when the config layer is
imported (every process that composes or runs a job imports it: the launching process,
the sweep's workers, submitit's job processes).

``${job_dir:${hydra.job.num},${hydra.job.override_dirname}}`` (``hydra.sweep.subdir`` in
conf/config.yaml) names a sweep job's directory: Hydra's ``<job number>_<overrides>``, as
it always was, unless a part of it would be longer than a file name may be
(:data:`NAME_BYTES`, the usual file-system limit): then the first overrides are kept and a
hash of the whole name ends it (``12_controller.k=50,robot.max_torque=[…...3f9a2c1b7d4e``),
so the name stays unique, the same on every run of the sweep (a resume finds it again),
and readable. The job's full overrides are in its ``.hydra/overrides.yaml`` and in
``metrics.json`` (``overrides``).
"""

from __future__ import annotations

import hashlib

from omegaconf import OmegaConf

#: the longest file name most file systems take (NAME_MAX, bytes)
NAME_BYTES = 255
#: the length of a shortened job name (bytes): room below the limit
SHORT_BYTES = 200
#: hex digits of the hash that ends a shortened name
HASH_DIGITS = 12


def job_dir(num: int | str, override_dirname: str | None) -> str:
    """The directory name of sweep job ``num`` whose overrides read ``override_dirname``."""
    name = f"{num}_{override_dirname or ''}"
    if all(len(part.encode()) <= NAME_BYTES for part in name.split("/")):
        return name
    digest = hashlib.sha256(name.encode()).hexdigest()[:HASH_DIGITS]
    keep = SHORT_BYTES - len(digest) - 3
    prefix = name.replace("/", "_").encode()[:keep].decode(errors="ignore")  # whole characters only
    return f"{prefix}...{digest}"


def register() -> None:
    """Register the resolvers (idempotent)."""
    if not OmegaConf.has_resolver("job_dir"):
        OmegaConf.register_new_resolver("job_dir", job_dir)
