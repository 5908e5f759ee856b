"""Provenance of a run: what produced it, where and when (flat keys of metrics.json).

:func:`collect` returns the keys every ``metrics.json`` carries (docs/run_directory.md):

- ``config_hash``: :func:`config_hash` of the job's composed config;
- ``started_at``: when the job started, ISO 8601 local time with its UTC offset
  (``2025-06-01T14:03:12.345+02:00``), from :func:`now_iso`;
- ``host``: the machine's host name;
- ``git_commit``, ``git_dirty``: the commit of the checkout the package runs from and
  whether its tree differs from it (``git status``: changed, staged or untracked files,
  ignored ones excepted); both null when the package does not run from a git checkout
  (an installed wheel) or git is not available;
- ``version_python``, ``version_mujoco``, ``version_pin``, ``version_proxsuite``,
  ``version_numpy``, ``version_hydra_core``, ``version_compliant_docking``: the installed
  versions (null for a package that is not installed).

The versions and the git state are computed once per process and cached: sweep workers
are reused between jobs, and the code a process runs is the code it imported at its
start. Cost, measured on the 2-core VM: about 10 ms for the first job of a process
(versions from distribution metadata, no import: 4-9 ms; one ``git status``: 3-5 ms),
then about 1 ms per job (the config hash) — against jobs of seconds. ``git`` runs with
``--no-optional-locks``, so it never writes to the repository (no index refresh) and
concurrent workers do not contend for its lock.

**The config hash** (:func:`config_hash`) identifies what a job computes: the SHA-256
of the job's composed config — resolved (interpolations replaced by their values,
enums by their names), Hydra's own node left out — as canonical JSON (sorted keys, no
spaces), first 16 hex digits. Left out because they change how a job reports, not what
it computes (:data:`HASH_EXCLUDED`): ``hydra`` (where and how the job was launched: the
sweep directory, the launcher, the job number), ``task.progress`` (the console
progress line) and ``figures`` (whether the job draws its per-run figures, which
``python -m compliant_docking.report --runs`` can draw later from the time series) and
``output`` (how much of the time series is saved: the metrics are the same). Everything else counts, ``render`` included (a video adds files and
keys to the run directory). The hash covers the config, not the code: files the config
names (the robots' MJCF) and the package itself are tracked by ``git_commit``,
``git_dirty`` and the versions.
"""

from __future__ import annotations

import functools
import hashlib
import json
import platform
import socket
import subprocess
from datetime import datetime
from importlib import metadata
from pathlib import Path

#: dotted config keys left out of :func:`config_hash` (see the module docstring)
HASH_EXCLUDED = ("hydra", "task.progress", "figures", "output")
#: hex digits of the SHA-256 kept in ``config_hash`` (64 bits)
HASH_DIGITS = 16
#: ``version_<key>`` → the distribution whose installed version it records (None: Python)
VERSIONED = {
    "python": None,
    "mujoco": "mujoco",
    "pin": "pin",
    "proxsuite": "proxsuite",
    "numpy": "numpy",
    "hydra_core": "hydra-core",
    "compliant_docking": "compliant-docking",
}
#: metrics.json keys that differ between two runs of one config on one machine: the
#: timing and the start time (the reproducibility test compares everything else)
VOLATILE_KEYS = frozenset(
    {"started_at", "wall_time_s", "loop_wall_time_s", "real_time_factor", "video_render_time_s"}
)
#: where git_commit is read: the folder above the package, which is a git checkout when
#: the package runs from one (an editable install); an installed wheel's is site-packages,
#: never a checkout, so its runs record no commit
REPO_ROOT = Path(__file__).resolve().parents[2]
#: seconds allowed for ``git status`` before giving up (null git fields)
GIT_TIMEOUT_S = 10.0


def now_iso() -> str:
    """The current local time, ISO 8601 with milliseconds and the UTC offset."""
    return datetime.now().astimezone().isoformat(timespec="milliseconds")


def config_hash(cfg) -> str | None:
    """The 16-hex-digit hash of a composed config (module docstring); None if it cannot
    be resolved (a job whose config does not resolve fails anyway)."""
    from enum import Enum

    from omegaconf import OmegaConf

    data: dict = {}
    try:
        for key in cfg:  # top level one by one: Hydra's node is never resolved
            if key in HASH_EXCLUDED:
                continue
            value = cfg[key]
            if OmegaConf.is_config(value):
                value = OmegaConf.to_container(value, resolve=True, enum_to_str=True)
            data[key] = value.name if isinstance(value, Enum) else value
    except Exception:
        return None
    for dotted in HASH_EXCLUDED:
        *parents, last = dotted.split(".")
        node: dict | None = data
        for part in parents:
            node = node.get(part) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node.pop(last, None)
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True, default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:HASH_DIGITS]


@functools.cache
def versions() -> dict[str, str | None]:
    """``{"version_python": "3.11.7", "version_mujoco": …}``; computed once per process."""
    out: dict[str, str | None] = {}
    for key, dist in VERSIONED.items():
        if dist is None:
            out[f"version_{key}"] = platform.python_version()
            continue
        try:
            out[f"version_{key}"] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[f"version_{key}"] = None
    return out


@functools.cache
def git_state() -> dict[str, str | bool | None]:
    """``{"git_commit": sha or None, "git_dirty": bool or None}`` of the checkout the
    package runs from; both None outside a git checkout. Computed once per process."""
    none: dict[str, str | bool | None] = {"git_commit": None, "git_dirty": None}
    if not (REPO_ROOT / ".git").exists():  # a directory, or a file in a worktree
        return none
    try:
        proc = subprocess.run(
            [
                "git",
                "--no-optional-locks",
                "-C",
                str(REPO_ROOT),
                "status",
                "--porcelain=v2",
                "--branch",
                "--untracked-files=normal",
            ],
            capture_output=True,
            text=True,
            timeout=GIT_TIMEOUT_S,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):  # no git, or it hung
        return none
    if proc.returncode != 0:  # e.g. "dubious ownership": another user's checkout
        return none
    commit, dirty = None, False
    for line in proc.stdout.splitlines():
        if line.startswith("# branch.oid "):
            oid = line.split()[2]
            commit = oid if oid != "(initial)" else None
        elif line and not line.startswith("#"):
            dirty = True
    return {"git_commit": commit, "git_dirty": dirty if commit is not None else None}


@functools.cache
def host() -> str:
    return socket.gethostname()


def collect(cfg, *, started_at: str) -> dict:
    """The provenance keys of one job (module docstring), in their metrics.json order."""
    return {
        "config_hash": config_hash(cfg),
        "started_at": started_at,
        "host": host(),
        **git_state(),
        **versions(),
    }


if __name__ == "__main__":  # python -m compliant_docking.run.provenance: this process's values
    import time

    tic = time.perf_counter()
    values = {**git_state(), **versions(), "host": host()}
    print(json.dumps(values, indent=2))
    print(f"(collected in {1e3 * (time.perf_counter() - tic):.1f} ms)")
