"""Run directories → pandas tables: :func:`load_runs`, the Table-10 comparison, sweep summaries.

``load_runs(path)`` finds every job directory under ``path`` (one run directory, a
sweep directory, nested trees, or all of ``runs/``) and returns one row per finished
job (see :func:`load_runs` for the columns). A directory is a *job directory* when it
holds a ``metrics.json`` or a ``.hydra/`` folder; it is *finished* when its
``metrics.json`` is a valid JSON object (the runner writes it last and atomically).
Unfinished ones (no ``metrics.json``: still running, or the worker crashed) and broken
ones (invalid JSON) are skipped with a :class:`RunSkippedWarning`, never an exception.

:func:`comparison_table` turns the rows into the Table-10 comparison (one column per
configuration, rows grouped into contact safety, internal safety, tracking accuracy,
seat and outcome); :func:`write_summary` writes ``summary.parquet``, ``summary.csv``
(one row per job), ``comparison.csv`` and ``summary.md`` (the comparison for a person).

Light on purpose (pandas, PyYAML, Hydra's override parser): no MuJoCo, no Pinocchio.
"""

from __future__ import annotations

import json
import math
import os
import re
import warnings
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd
import yaml

from compliant_docking.files import atomic_write

METRICS_FILE = "metrics.json"
HYDRA_DIR = ".hydra"
OVERRIDES_FILE = "overrides.yaml"
#: files written by :func:`write_summary`
SUMMARY_FILES = ("summary.parquet", "summary.csv", "comparison.csv", "summary.md")
#: columns every frame of :func:`load_runs` has, first, in this order
BASE_COLUMNS = ("run_dir", "job", "status", "error", "success")
#: the config groups whose choice names a job (also recorded in metrics.json)
GROUPS = ("robot", "controller", "trajectory", "tool", "target", "physics", "task", "experiment")


class RunSkippedWarning(UserWarning):
    """A job directory without a finished metrics.json was skipped."""


# --------------------------------------------------------------------------- finding runs
def find_job_dirs(path: str | os.PathLike) -> list[Path]:
    """Every job directory under ``path`` (``path`` itself included), in natural order.

    A job directory holds a ``metrics.json`` or a ``.hydra/`` folder. Hidden folders
    and the sub-folders of a job directory (``figures/``, ``.hydra/``) are not searched.
    """
    root = Path(path)
    if root.is_file():
        root = root.parent
    if not root.is_dir():
        raise FileNotFoundError(f"no such directory: {root}")
    found: list[Path] = []
    for current, dirs, files in os.walk(root):
        here = Path(current)
        if METRICS_FILE in files or HYDRA_DIR in dirs:
            found.append(here)
            dirs[:] = []  # a job directory holds no other jobs
            continue
        dirs[:] = [d for d in dirs if not d.startswith(".")]
    return sorted(found, key=_natural_key)


def _natural_key(path: Path) -> list:
    """Sort key: digit runs compare as numbers (job 10 after job 9)."""
    return [int(part) if part.isdigit() else part
            for part in re.split(r"(\d+)", str(path))]


def read_metrics(job_dir: Path) -> tuple[dict | None, str | None]:
    """The job's metrics.json as a dict, or (None, why it cannot be read)."""
    path = Path(job_dir) / METRICS_FILE
    if not path.is_file():
        return None, "no metrics.json (the job is still running, or its process died)"
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        return None, f"metrics.json is not valid JSON (half-written?): {exc}"
    if not isinstance(record, dict):
        return None, "metrics.json is not a JSON object"
    return record, None


def read_overrides(job_dir: Path) -> dict[str, Any]:
    """The job's command-line overrides (``.hydra/overrides.yaml``) as {key: value}.

    Keys lose Hydra's ``+``/``++``/``~`` prefixes (``+experiment=x`` → ``experiment``);
    values are parsed as Hydra does (``0.0004`` → float, ``hqp`` → str); lists and
    dicts stay as their override text (``[0,0,-0.1]``) so a column keeps one type.
    """
    path = Path(job_dir) / HYDRA_DIR / OVERRIDES_FILE
    if not path.is_file():
        return {}
    try:
        lines = yaml.safe_load(path.read_text(encoding="utf-8")) or []
    except (OSError, yaml.YAMLError):
        return {}
    if not isinstance(lines, list):
        return {}
    return dict(parse_override(str(line)) for line in lines)


def parse_override(text: str) -> tuple[str, Any]:
    """One override string → (key, value); see :func:`read_overrides`."""
    try:
        from hydra.core.override_parser.overrides_parser import OverridesParser

        override = OverridesParser.create().parse_override(text)
        key = override.key_or_group
        if override.package:
            key = f"{key}@{override.package}"
        if override.is_delete():
            return key, None
        value = override.value()
        if isinstance(value, (list, dict)) or not _is_scalar(value):
            value = override.get_value_element_as_str()
        return key, value
    except Exception:  # not Hydra syntax (hand-written file): split at the first '='
        key, _, value = text.partition("=")
        return key.lstrip("+~"), value


def _is_scalar(value) -> bool:
    return value is None or isinstance(value, (bool, int, float, str))


# --------------------------------------------------------------------------- load_runs
def load_runs(path: str | os.PathLike = "runs") -> pd.DataFrame:
    """One row per finished job directory under ``path``.

    Columns, in this order:

    - ``run_dir`` (absolute path, str) and ``job`` (the directory's name);
    - ``status`` ("ok", "incomplete", "failed"), ``error`` (None or one line),
      ``success`` (bool, or None for runs without a gate);
    - one column per command-line override of any job, named by its key without
      Hydra's prefixes: ``controller``, ``robot``, ``target.geometry.radial_clearance``,
      ``task.misalignment.seed``, ``experiment``, … (NaN/None where a job did not set it);
    - every key of metrics.json: the config choices (``robot``, ``controller``,
      ``trajectory``, … always set, whether overridden or not), ``overrides`` (the job's
      overrides, space-separated), the Table-10 metrics (``peak_axial_force_N``, …),
      seat errors, the drawn misalignment (``misalignment_x_m``, …), timing, controller
      diagnostics. JSON null becomes None/NaN.

    Where an override and a metrics.json key share a name (``controller``), the
    metrics.json value (the choice the job used) is kept; they agree.

    Directories without a finished metrics.json are skipped with a
    :class:`RunSkippedWarning`. ``path`` must exist (FileNotFoundError otherwise); no
    job found gives an empty frame with the base columns.
    """
    rows: list[dict] = []
    override_keys: list[str] = []
    metric_keys: list[str] = []
    for job_dir in find_job_dirs(path):
        record, problem = read_metrics(job_dir)
        if record is None:
            warnings.warn(f"skipping {job_dir}: {problem}", RunSkippedWarning, stacklevel=2)
            continue
        overrides = read_overrides(job_dir)
        row = {"run_dir": str(job_dir.resolve()), "job": job_dir.name}
        row.update(overrides)
        row.update(record)
        rows.append(row)
        _extend_unique(override_keys, overrides)
        _extend_unique(metric_keys, record)
    columns = list(BASE_COLUMNS)
    _extend_unique(columns, override_keys)
    _extend_unique(columns, metric_keys)
    frame = pd.DataFrame(rows, columns=columns)
    for column in frame.columns:  # JSON numbers with nulls: numeric columns with NaN
        if frame[column].dtype == object and column not in ("success",):
            frame[column] = _maybe_numeric(frame[column])
    return frame


def _extend_unique(target: list[str], keys: Iterable[str]) -> None:
    seen = set(target)
    for key in keys:
        if key not in seen:
            target.append(key)
            seen.add(key)


def _maybe_numeric(column: pd.Series) -> pd.Series:
    values = column.dropna()
    if len(values) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                           for v in values):
        return pd.to_numeric(column, errors="coerce")
    return column


# --------------------------------------------------------------------------- comparison
@dataclass(frozen=True)
class Row:
    """One row of the Table-10 comparison."""

    section: str
    key: str  # metrics.json key
    label: str  # with unit
    scale: float = 1.0  # metrics.json unit → shown unit


#: the Table-10 rows (seed DockingMetrics), grouped, with display units
TABLE10: tuple[Row, ...] = (
    Row("contact safety", "peak_axial_force_N", "peak axial force [N]"),
    Row("contact safety", "peak_wrench_norm_N", "peak wrench norm [N]"),
    Row("contact safety", "steady_axial_force_N", "steady axial force [N]"),
    Row("contact safety", "steady_wrench_norm_N", "steady wrench norm [N]"),
    Row("internal safety", "max_joint_pos_pct", "max joint position use [%]"),
    Row("internal safety", "max_joint_vel_pct", "max joint speed use [%]"),
    Row("internal safety", "min_manipulability", "min manipulability [-]"),
    Row("tracking accuracy", "pos_tracking_rms_m", "position RMS [mm]", 1e3),
    Row("tracking accuracy", "ori_tracking_rms_rad", "orientation RMS [deg]", 180.0 / math.pi),
    Row("tracking accuracy", "final_lateral_error_m", "final lateral error [mm]", 1e3),
    Row("tracking accuracy", "final_orientation_error_rad", "final orientation error [deg]",
        180.0 / math.pi),
    Row("seat (true socket pose)", "seat_depth_error_m", "depth error [mm]", 1e3),
    Row("seat (true socket pose)", "seat_lateral_error_m", "lateral error [mm]", 1e3),
    Row("seat (true socket pose)", "seat_tilt_deg", "tilt [deg]"),
    Row("run", "wall_time_s", "wall time [s]"),
    Row("run", "real_time_factor", "loop speed [× real time]"),
)
SUCCESS_SECTION = "success"
#: keys that repeat a configuration rather than define one
REPEAT_KEYS = re.compile(r"(^|\.)seed$")
#: overrides that change how a job reports, not what it simulates
COSMETIC_KEYS = frozenset({"task.progress"})


def configuration_keys(df: pd.DataFrame) -> list[str]:
    """The columns that tell the configurations of ``df`` apart.

    Candidates are the config choices (``robot``, ``controller``, …, ``experiment``)
    and the dotted override columns (``controller.k``, ``task.misalignment.x_range``;
    metrics.json keys are never dotted); kept are those whose value varies across the
    rows, except repeat keys (any ``…seed``): repeats of one configuration are pooled
    (success rate, means), and cosmetic keys (``task.progress``).
    """
    if df.empty:
        return []
    candidates = [g for g in GROUPS if g in df.columns]
    candidates += [c for c in df.columns if "." in c and c not in candidates]
    return [c for c in candidates
            if not REPEAT_KEYS.search(c) and c not in COSMETIC_KEYS
            and df[c].astype(str).nunique(dropna=False) > 1]


def _short(key: str, keys: list[str]) -> str:
    last = key.rsplit(".", 1)[-1]
    clash = sum(1 for k in keys if k.rsplit(".", 1)[-1] == last) > 1
    return key if clash else last


def _format_value(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "default"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def configuration_labels(df: pd.DataFrame, keys: list[str] | None = None) -> pd.Series:
    """A readable label per row: the values of :func:`configuration_keys`, ' · '-joined.

    Config choices show their value alone (``fr3 · hqp``), other keys as
    ``short_key=value`` (``radial_clearance=0.0004``). With nothing varying, every row
    is labelled by its choices ``robot · controller · trajectory``.
    """
    keys = configuration_keys(df) if keys is None else keys
    if not keys:
        keys = [g for g in ("robot", "controller", "trajectory") if g in df.columns]

    def label(row) -> str:
        parts = []
        for key in keys:
            value = _format_value(row.get(key))
            parts.append(value if key in GROUPS else f"{_short(key, keys)}={value}")
        return " · ".join(parts) or str(row.get("job"))

    return df.apply(label, axis=1) if len(df) else pd.Series([], dtype=object)


def comparison_table(df: pd.DataFrame, keys: list[str] | None = None) -> pd.DataFrame:
    """The Table-10 comparison: one column per configuration, rows (section, metric).

    Metrics are the mean over the finished jobs of a configuration (repeats: seeds),
    in display units (mm, deg, N, %); the ``success`` section holds ``jobs``,
    ``failed`` (status failed), ``docked`` (success true) and ``success rate``
    (docked / jobs). Columns keep the order in which configurations first appear.
    """
    labels = configuration_labels(df, keys)
    order = list(dict.fromkeys(labels))
    index = pd.MultiIndex.from_tuples(
        [(r.section, r.label) for r in TABLE10]
        + [(SUCCESS_SECTION, name) for name in ("jobs", "failed", "docked", "success rate")],
        names=["section", "metric"])
    table = pd.DataFrame(index=index, columns=order, dtype=float)
    for name in order:
        group = df[labels == name]
        for row in TABLE10:
            values = pd.to_numeric(group.get(row.key), errors="coerce") if row.key in group else None
            mean = values.mean() if values is not None and values.notna().any() else np.nan
            table.loc[(row.section, row.label), name] = mean * row.scale
        docked = int((group["success"] == True).sum()) if "success" in group else 0  # noqa: E712
        table.loc[(SUCCESS_SECTION, "jobs"), name] = len(group)
        table.loc[(SUCCESS_SECTION, "failed"), name] = int((group["status"] == "failed").sum())
        table.loc[(SUCCESS_SECTION, "docked"), name] = docked
        table.loc[(SUCCESS_SECTION, "success rate"), name] = docked / len(group) if len(group) else np.nan
    return table


def _cell(value, metric: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if metric in ("jobs", "failed", "docked"):
        return f"{int(value)}"
    if metric == "success rate":
        return f"{100 * value:.0f} %"
    if value != 0 and (abs(value) >= 1e5 or abs(value) < 1e-3):
        return f"{value:.3e}"
    return f"{value:.4g}" if abs(value) >= 100 else f"{value:.3f}"


def _markdown_grid(header: list[str], rows: list[list[str]], align_right: bool = True) -> str:
    """A pipe table with padded cells (readable as plain text in a terminal)."""
    widths = [max(len(header[i]), *(len(r[i]) for r in rows)) if rows else len(header[i])
              for i in range(len(header))]
    line = lambda cells: "| " + " | ".join(  # noqa: E731
        c.ljust(w) if i == 0 or not align_right else c.rjust(w)
        for i, (c, w) in enumerate(zip(cells, widths))) + " |"
    rule = "|" + "|".join(("-" * (w + 2)) if i == 0 or not align_right else ("-" * (w + 1) + ":")
                          for i, w in enumerate(widths)) + "|"
    return "\n".join([line(header), rule, *(line(r) for r in rows)])


def comparison_markdown(table: pd.DataFrame) -> str:
    """The comparison as a Markdown pipe table, sections as bold rows."""
    header = ["metric", *map(str, table.columns)]
    rows: list[list[str]] = []
    section = None
    for (sec, metric), values in table.iterrows():
        if sec != section:
            rows.append([f"**{sec}**", *[""] * len(table.columns)])
            section = sec
        rows.append([metric, *(_cell(v, metric) for v in values)])
    return _markdown_grid(header, rows)


def jobs_markdown(df: pd.DataFrame) -> str:
    """One line per job: name, status, docked, peak axial force, wall time, reason."""
    header = ["job", "status", "docked", "peak axial force [N]", "wall time [s]", "error / gate"]
    rows = []
    for _, r in df.iterrows():
        success = r.get("success")
        docked = "n/a" if success is None or (isinstance(success, float) and math.isnan(success)) \
            else ("yes" if bool(success) else "no")
        reason = r.get("error") if isinstance(r.get("error"), str) else r.get("gate_failures")
        reason = reason if isinstance(reason, str) else ""
        rows.append([str(r["job"]), str(r["status"]), docked, _cell(r.get("peak_axial_force_N"), ""),
                     _cell(r.get("wall_time_s"), ""), reason.replace("|", "/")])
    return _markdown_grid(header, rows, align_right=False)


@dataclass(frozen=True)
class Counts:
    """Outcome of a set of jobs."""

    jobs: int
    ok: int  # status ok
    incomplete: int
    failed: int  # status failed
    docked: int  # success true
    unfinished: int = 0  # job directories without a finished metrics.json

    def line(self) -> str:
        text = (f"{self.jobs + self.unfinished} jobs: {self.ok} succeeded, "
                f"{self.failed + self.unfinished} failed, {self.docked} docked")
        extra = []
        if self.incomplete:
            extra.append(f"{self.incomplete} incomplete")
        if self.unfinished:
            extra.append(f"{self.unfinished} without metrics.json (crashed or cut short)")
        return text + (f" ({', '.join(extra)})" if extra else "")


def counts(df: pd.DataFrame, unfinished: int = 0) -> Counts:
    status = df["status"] if "status" in df else pd.Series([], dtype=object)
    success = df["success"] if "success" in df else pd.Series([], dtype=object)
    return Counts(jobs=len(df), ok=int((status == "ok").sum()),
                  incomplete=int((status == "incomplete").sum()),
                  failed=int((status == "failed").sum()),
                  docked=int((success == True).sum()),  # noqa: E712
                  unfinished=unfinished)


def summary_markdown(df: pd.DataFrame, title: str, unfinished: list[Path] | None = None) -> str:
    """summary.md: counts, the Table-10 comparison and the list of jobs."""
    unfinished = unfinished or []
    parts = [f"# {title}", "",
             f"{counts(df, len(unfinished)).line()}. Written "
             f"{datetime.now().isoformat(timespec='seconds')} by compliant_docking.results; "
             "rebuild with `python -m compliant_docking.report PATH`.", ""]
    if len(df):
        keys = configuration_keys(df)
        pooled = [c for c in df.columns if REPEAT_KEYS.search(c) and df[c].nunique() > 1]
        note = ("Mean over the jobs of each configuration" +
                (f" (repeats over {', '.join(pooled)} pooled)" if pooled else "") +
                "; configurations differ in: " + (", ".join(keys) or "nothing (one configuration)") + ".")
        parts += ["## Comparison (Table 10)", "", note, "",
                  comparison_markdown(comparison_table(df, keys)), ""]
        parts += ["## Jobs", "", jobs_markdown(df), ""]
    if unfinished:
        parts += ["## Without a finished metrics.json", ""]
        parts += [f"- `{p}`" for p in unfinished] + [""]
    return "\n".join(parts)


def arrow_safe(df: pd.DataFrame) -> pd.DataFrame:
    """A copy whose object columns hold one type each (mixed → str), for Parquet."""
    out = df.copy()
    for column in out.columns:
        if out[column].dtype != object:
            continue
        types = {type(v) for v in out[column].dropna()}
        if len(types) > 1 and not types <= {int, float}:
            if types <= {bool, type(None)}:
                continue
            out[column] = out[column].map(lambda v: None if v is None else str(v))
    return out


def write_summary(df: pd.DataFrame, out_dir: str | os.PathLike, *, title: str | None = None,
                  unfinished: list[Path] | None = None) -> dict[str, Path]:
    """Write summary.parquet, summary.csv (one row per job), comparison.csv and summary.md.

    Each file is written under a temporary name and renamed. Returns {name: path}.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    title = title or f"Runs in {out.name}"
    paths = {name: out / name for name in SUMMARY_FILES}
    safe = arrow_safe(df)
    atomic_write(paths["summary.parquet"], lambda p: safe.to_parquet(p, index=False))
    atomic_write(paths["summary.csv"], lambda p: df.to_csv(p, index=False))
    table = comparison_table(df) if len(df) else pd.DataFrame()
    atomic_write(paths["comparison.csv"], lambda p: table.to_csv(p))
    text = summary_markdown(df, title, unfinished)
    atomic_write(paths["summary.md"], lambda p: p.write_text(text + "\n", encoding="utf-8"))
    return paths


def scan(path: str | os.PathLike) -> tuple[pd.DataFrame, list[Path]]:
    """``load_runs(path)`` without warnings, and the job directories it skipped."""
    skipped = [d for d in find_job_dirs(path) if read_metrics(d)[0] is None]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RunSkippedWarning)
        return load_runs(path), skipped


def newest_sweep(root: str | os.PathLike = "runs/multirun") -> Path | None:
    """The most recently modified sweep directory (one holding multirun.yaml) under ``root``."""
    root = Path(root)
    if not root.is_dir():
        return None
    sweeps = [p.parent for p in root.rglob("multirun.yaml")]
    return max(sweeps, key=lambda p: p.stat().st_mtime) if sweeps else None
