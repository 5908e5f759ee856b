"""Run directories → pandas: :func:`load_runs` and the sweep helpers built on it.

``load_runs(path)`` finds every job directory under ``path`` (one run directory, a
sweep directory, nested trees, or all of ``runs/``) and returns one row per finished
job (see :func:`load_runs` for the columns). A directory is a *job directory* when it
holds a ``metrics.json`` or a ``.hydra/`` folder; it is *finished* when its
``metrics.json`` is a valid JSON object (the runner writes it last and atomically).
Unfinished ones (no ``metrics.json``: still running, or the worker crashed) and broken
ones (invalid JSON) are skipped with a :class:`RunSkippedWarning`, never an exception.

Light on purpose (pandas, PyYAML, Hydra's override parser): no MuJoCo, no Pinocchio.
"""

from __future__ import annotations

import json
import os
import re
import warnings
from collections.abc import Iterable
from datetime import datetime
from pathlib import Path

import pandas as pd

from compliant_docking.run.rundir import (
    CONFIG_FILE,
    HYDRA_DIR,
    IDENTITY_GROUPS,
    MULTIRUN_FILE,
    find_job_dirs,
    flatten,
    read_metrics,
    read_overrides,
)

#: columns every frame of :func:`load_runs` has, first, in this order
BASE_COLUMNS = ("run_dir", "job", "status", "error", "success")
#: the column listing the keys each job overrode (comma-joined; configurations differ in these)
OVERRIDDEN = "overridden"
#: prefix of a config leaf whose dotted name is already a metrics.json key
CONFIG_PREFIX = "config."
#: the config groups whose choice names a job (also recorded in metrics.json)
GROUPS = (*IDENTITY_GROUPS, "experiment")


class RunSkippedWarning(UserWarning):
    """A job directory without a finished metrics.json was skipped."""


# --------------------------------------------------------------------------- load_runs
def load_runs(path: str | os.PathLike = "runs") -> pd.DataFrame:
    """One row per finished job directory under ``path``.

    Columns, in this order:

    - ``run_dir`` (absolute path, str) and ``job`` (the directory's name);
    - ``status`` ("ok", "incomplete", "failed", "interrupted"), ``error`` (None or one line),
      ``success`` (bool, or None for runs without a gate);
    - one column per command-line override of any job, named by its key without
      Hydra's prefixes: ``controller``, ``robot``, ``target.geometry.radial_clearance``,
      ``task.misalignment.seed``, ``experiment``, … (NaN/None where a job did not set it
      and has no composed config);
    - every key of metrics.json: the config choices (``robot``, ``controller``,
      ``trajectory``, … always set, whether overridden or not), ``overrides`` (the job's
      overrides, space-separated), the docking metrics (``peak_axial_force_N``, …),
      seat errors, the drawn misalignment (``misalignment_x_m``, ``misalignment_y_m``,
      ``misalignment_lateral_m``, ``misalignment_yaw_deg``, ``misalignment_tilt_deg``,
      ``misalignment_seed``), timing, controller diagnostics. JSON null becomes None/NaN;
    - ``overridden``: the keys the job overrode, comma-joined (what
      :func:`~compliant_docking.results.tables.configuration_keys` looks at);
    - every leaf of the job's resolved config (``.hydra/config.yaml``) as a dotted column:
      ``controller.k``, ``physics.timestep``, ``target.geometry.radial_clearance``,
      ``task.misalignment.x_range``, … in the config's units (SI unless the key names
      another: conf/'s comments); lists as their JSON text (``[-0.002, 0.002]``).
      A leaf overridden on the command line fills the override's column (the resolved
      value, the same number); a leaf whose name is a metrics.json key gets the prefix
      ``config.``. Jobs without a composed config (a run made by ``runner.execute``
      alone) have NaN/None there.

    Where an override and a metrics.json key share a name (``controller``), the
    metrics.json value (the choice the job used) is kept; they agree.

    Directories without a finished metrics.json are skipped with a
    :class:`RunSkippedWarning`. ``path`` must exist (FileNotFoundError otherwise); no
    job found gives an empty frame with the base columns.
    """
    rows: list[dict] = []
    override_keys: list[str] = []
    metric_keys: list[str] = []
    config_keys: list[str] = []
    for job_dir in find_job_dirs(path):
        record, problem = read_metrics(job_dir)
        if record is None:
            warnings.warn(f"skipping {job_dir}: {problem}", RunSkippedWarning, stacklevel=2)
            continue
        overrides = read_overrides(job_dir)
        row: dict = {"run_dir": str(job_dir.resolve()), "job": job_dir.name}
        row.update(overrides)
        row.update(record)
        row[OVERRIDDEN] = ",".join(overrides) or None
        leaves: dict = {}
        for key, value in config_leaves(job_dir).items():
            if key in record or key in BASE_COLUMNS or key == OVERRIDDEN:
                key = f"{CONFIG_PREFIX}{key}"  # never shadows a metric (none is dotted today)
            leaves[key] = value
        row.update(leaves)
        rows.append(row)
        _extend_unique(override_keys, overrides)
        _extend_unique(metric_keys, record)
        _extend_unique(config_keys, leaves)
    columns = list(BASE_COLUMNS)
    _extend_unique(columns, override_keys)
    _extend_unique(columns, metric_keys)
    _extend_unique(columns, [OVERRIDDEN] if rows else [])
    _extend_unique(columns, config_keys)
    frame = pd.DataFrame(rows, columns=columns)
    for column in frame.columns:  # JSON numbers with nulls: numeric columns with NaN
        if frame[column].dtype == object and column not in ("success",):
            frame[column] = _maybe_numeric(frame[column])
    return frame


def config_leaves(job_dir: Path) -> dict:
    """Every leaf of the job's ``.hydra/config.yaml`` as {dotted key: value} ({} without one);
    lists (and lists of lists) as their JSON text, so that a column holds one kind of value;
    an interpolation of another key (``${tool.geometry.radius}``) replaced by its value."""
    path = Path(job_dir) / HYDRA_DIR / CONFIG_FILE
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return {}
    try:
        import yaml

        loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml: ~10× faster
        data = yaml.load(text, Loader=loader)  # noqa: S506 (a safe loader)
    except Exception:
        return {}
    leaves = flatten(data) if isinstance(data, dict) else {}
    out = {k: json.dumps(v) if isinstance(v, (list, tuple)) else v for k, v in leaves.items()}
    for _ in range(4):  # resolve ${other.key} (Hydra saves the config unresolved); chains too
        pending = {k: v for k, v in out.items() if isinstance(v, str) and _REFERENCE.fullmatch(v)}
        resolved = {k: out[v[2:-1]] for k, v in pending.items() if v[2:-1] in out}
        if not resolved:
            break
        out.update(resolved)
    return out


#: an interpolation of another key of the same config: ``${tool.geometry.radius}``
_REFERENCE = re.compile(r"\$\{[A-Za-z_][\w.]*\}")


def _extend_unique(target: list[str], keys: Iterable[str]) -> None:
    seen = set(target)
    for key in keys:
        if key not in seen:
            target.append(key)
            seen.add(key)


def _maybe_numeric(column: pd.Series) -> pd.Series:
    values = column.dropna()
    if len(values) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return pd.to_numeric(column, errors="coerce")
    return column


def scan(path: str | os.PathLike) -> tuple[pd.DataFrame, list[Path]]:
    """``load_runs(path)`` without warnings, and the job directories it skipped."""
    skipped = [d for d in find_job_dirs(path) if read_metrics(d)[0] is None]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RunSkippedWarning)
        return load_runs(path), skipped


#: a sweep directory named by Hydra's default: runs/multirun/<date>/<time>[_<preset>]
_DATE = re.compile(r"\d{4}-\d{2}-\d{2}")
_TIME = re.compile(r"(\d{2})-(\d{2})-(\d{2})(?:_|$)")


def sweep_started(sweep_dir: str | os.PathLike) -> datetime:
    """When a sweep started: the date and time in its name (``<date>/<time>[_<preset>]``,
    ``conf/config.yaml``); for a directory named otherwise, the modification time of its
    ``multirun.yaml`` (Hydra writes it when the sweep starts), else of the directory.

    Never the directory's own modification time when the name has one: writing a report
    into an old sweep must not make it new.
    """
    path = Path(sweep_dir)
    match = _TIME.match(path.name)
    if match and _DATE.fullmatch(path.parent.name):
        try:
            return datetime.strptime(f"{path.parent.name} {':'.join(match.groups())}", "%Y-%m-%d %H:%M:%S")
        except ValueError:  # e.g. 2025-13-01: not a date after all
            pass
    stamp = path / MULTIRUN_FILE if (path / MULTIRUN_FILE).exists() else path
    return datetime.fromtimestamp(stamp.stat().st_mtime)


def newest_sweep(root: str | os.PathLike = "runs/multirun") -> Path | None:
    """The sweep directory (one holding multirun.yaml) under ``root`` that started last,
    by :func:`sweep_started` (the time in its name); None when there is none."""
    root = Path(root)
    if not root.is_dir():
        return None
    sweeps = [p.parent for p in root.rglob(MULTIRUN_FILE)]
    return max(sweeps, key=lambda p: (sweep_started(p), str(p))) if sweeps else None


def locate_runs(path: str | os.PathLike, base: str | os.PathLike | None = None) -> Path:
    """A directory of runs named as the sweep printed it: absolute paths as they are,
    relative ones from the working directory, else from ``base`` (the notebook in
    ``analysis/`` passes the checkout's root, where the commands run, so
    ``runs/multirun/<date>/<time>`` works from there). Raises FileNotFoundError naming
    every place looked in when none exists."""
    given = Path(path).expanduser()
    if given.is_absolute():
        candidates = [given]
    else:
        candidates = [Path.cwd() / given] + ([Path(base) / given] if base is not None else [])
    for candidate in candidates:
        if candidate.is_dir():
            return candidate.resolve()
    raise FileNotFoundError(
        f"no directory {str(path)!r}: looked in " + " and ".join(str(c) for c in dict.fromkeys(candidates))
    )
