"""The OmegaConf resolvers the config files use, registered when the config layer is
imported (every process that composes or runs a job imports it: the launching process,
the sweep's workers, submitit's job processes).

``${job_dir:${hydra.job.num},${hydra.job.override_dirname}}`` (``hydra.sweep.subdir`` in
conf/config.yaml) names a sweep job's directory, which is also the job's name in the
progress lines, summary.md and ``load_runs`` (``job``): Hydra's ``<job number>_<overrides>``,
with two changes that keep it one short, readable directory name:

- an override whose value is a file path (``tool.mjcf=assets/interfaces/keyed_cad/tool.xml``)
  is named by the file's folder and stem (``tool.mjcf=keyed_cad-tool``; a file without a
  folder: its stem), so the job is one directory, not one level per path component; two
  paths of one job that would read the same get a short hash of the path each
  (``…-tool~3f9a2c``);
- a part longer than a file name may be (:data:`NAME_BYTES`, the usual file-system limit)
  keeps the first overrides and ends with a hash of the whole name
  (``12_controller.k=50,robot.max_torque=[…...3f9a2c1b7d4e``).

Either way the name is unique, the same on every run of the sweep (a resume finds it
again) and readable. The job's full overrides are in its ``.hydra/overrides.yaml`` and in
``metrics.json`` (``overrides``).
"""

from __future__ import annotations

import hashlib
import re
from pathlib import PurePosixPath

from omegaconf import OmegaConf

#: the longest file name most file systems take (NAME_MAX, bytes)
NAME_BYTES = 255
#: the length of a shortened job name (bytes): room below the limit
SHORT_BYTES = 200
#: hex digits of the hash that ends a shortened name
HASH_DIGITS = 12


#: a file path given as an override's value: ``key=`` then text with a ``/`` and no
#: separator of Hydra's override syntax, up to the next override or the end
_PATH_VALUE = re.compile(r"(?<==)([^=,\[\](){}'\"]*/[^=,\[\](){}'\"]*)(?=,|$)")
#: hex digits of the hash that tells two paths of one job apart
PATH_HASH_DIGITS = 6


def _path_label(path: str) -> str:
    """``folder-stem`` of a file path (``assets/interfaces/keyed_cad/tool.xml`` →
    ``keyed_cad-tool``); its stem alone when it has no folder."""
    pure = PurePosixPath(path.rstrip("/"))
    folder = pure.parent.name
    return f"{folder}-{pure.stem}" if folder not in ("", ".", "..") else pure.stem or pure.name


def short_paths(override_dirname: str) -> str:
    """``override_dirname`` with every file path value replaced by its label (module docstring)."""
    paths = _PATH_VALUE.findall(override_dirname)
    labels = [_path_label(p) for p in paths]
    clash = {label for label in labels if labels.count(label) > 1 or not label}

    def label(match: re.Match) -> str:
        path = match.group(1)
        text = _path_label(path)
        if text in clash:
            text += "~" + hashlib.sha256(path.encode()).hexdigest()[:PATH_HASH_DIGITS]
        return text

    return _PATH_VALUE.sub(label, override_dirname)


def job_dir(num: int | str, override_dirname: str | None) -> str:
    """The directory name of sweep job ``num`` whose overrides read ``override_dirname``."""
    name = f"{num}_{short_paths(override_dirname or '')}"
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
