"""The run directory: the names of its files, and their readers and writers (the one place).

A job directory (docs/run_directory.md) holds::

    metrics.json        flat JSON object, written last and atomically: its presence means
                        "finished"; status, error, success, the metrics, provenance
    timeseries.parquet  one row per control step (columns: compliant_docking.sim.telemetry)
    summary.txt         the console summary
    figures/            per-run figures (PNG + PDF)
    mujoco.log          MuJoCo's warnings, when there were any
    .hydra/             Hydra's composed config, its own config and the overrides

Every writer here replaces its file atomically (temporary name, then rename); readers
never raise for what they find on disk, they say why a file cannot be read.
"""

from __future__ import annotations

import json
import os
import random
import re
import shutil
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml

from compliant_docking.evaluation.registry import finite_or_none
from compliant_docking.run.files import atomic_write, atomic_write_text, temporary_name

if TYPE_CHECKING:
    import pandas as pd

METRICS_FILE = "metrics.json"
TIMESERIES_FILE = "timeseries.parquet"
SUMMARY_FILE = "summary.txt"
FIGURES_DIR = "figures"
MUJOCO_LOG_FILE = "mujoco.log"  # MuJoCo's warnings, when there were any
HYDRA_DIR = ".hydra"
CONFIG_FILE = "config.yaml"  # in HYDRA_DIR: the job's composed config
OVERRIDES_FILE = "overrides.yaml"  # in HYDRA_DIR: the job's command-line overrides
#: the config groups whose choice names a job in its record (metrics.json)
IDENTITY_GROUPS = (
    "robot",
    "controller",
    "trajectory",
    "tool",
    "target",
    "physics",
    "task",
    "sensor",
    "model_error",
    "dynamics",
)
#: the sweep directory's record of the sweep (Hydra writes it)
MULTIRUN_FILE = "multirun.yaml"
#: statuses of a job that did not finish its simulation: never docked, whatever else its record says
FAILED_STATUSES = ("failed", "interrupted")


# --------------------------------------------------------------------------- metrics.json
def clean_record(record: dict) -> dict:
    """The record with numpy scalars as Python numbers and non-finite numbers as None."""
    return {
        k: finite_or_none(v) if isinstance(v, (float, np.floating, np.integer)) else v
        for k, v in record.items()
    }


def consistent(record: dict) -> dict:
    """The record with ``success`` false when its status is failed or interrupted: a job that
    did not finish never counts as docked (the one rule of every writer and reader)."""
    if record.get("status") in FAILED_STATUSES and record.get("success") is not False:
        return {**record, "success": False}
    return record


def write_metrics(job_dir: Path, record: dict) -> None:
    """metrics.json: a flat JSON object; non-finite numbers become null."""
    text = json.dumps(clean_record(consistent(record)), indent=2, allow_nan=False) + "\n"
    atomic_write_text(Path(job_dir) / METRICS_FILE, text)


def read_metrics(job_dir: Path) -> tuple[dict | None, str | None]:
    """The job's metrics.json as a dict, or (None, why it cannot be read). A failed or
    interrupted job reads as not docked even when its file says otherwise (:func:`consistent`)."""
    path = Path(job_dir) / METRICS_FILE
    if not path.is_file():
        return None, "no metrics.json (the job is still running, or its process died)"
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        return None, f"metrics.json is not valid JSON (half-written?): {exc}"
    if not isinstance(record, dict):
        return None, "metrics.json is not a JSON object"
    return consistent(record), None


# --------------------------------------------------------------------------- other files
def write_timeseries(job_dir: Path, frame: pd.DataFrame) -> None:
    """timeseries.parquet: no index, zstd-compressed, plain encoding with the float columns
    byte-stream-split. Dictionary encoding (pandas' default) suits repeated values, not
    18 000 distinct floats: without it, writing takes a third of the time (63 → 22 ms
    for a default run) and the file is 38 % smaller; the values are the same, bit for bit."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(frame, preserve_index=False)
    floats = [field.name for field in table.schema if pa.types.is_floating(field.type)]
    atomic_write(
        Path(job_dir) / TIMESERIES_FILE,
        lambda tmp: pq.write_table(
            table, tmp, compression="zstd", use_dictionary=False, use_byte_stream_split=floats or False
        ),
    )


def saved_timeseries(frame: pd.DataFrame, output) -> pd.DataFrame | None:
    """The part of the run's time series that ``output`` (the config's ``output`` node)
    saves: None for ``output.timeseries=false`` (metrics only); every ``output.every``-th
    row (steps 0, N, 2N, …); the float columns as float32 for ``output.precision=float32``.
    The default (true, float64, 1) is ``frame`` itself, bit for bit."""
    if not output.timeseries:
        return None
    every = int(output.every)
    if every > 1:
        frame = frame.iloc[::every].reset_index(drop=True)
    if getattr(output.precision, "name", output.precision) == "float32":
        floats = frame.select_dtypes("float64").columns
        frame = frame.astype(dict.fromkeys(floats, "float32"))
    return frame


def read_timeseries(job_dir: Path, columns: list[str] | None = None) -> pd.DataFrame:
    """The job's time series (all columns, or ``columns``)."""
    import pandas as pd

    return pd.read_parquet(Path(job_dir) / TIMESERIES_FILE, columns=columns)


def has_timeseries(job_dir: Path) -> bool:
    return (Path(job_dir) / TIMESERIES_FILE).is_file()


def write_summary_text(job_dir: Path, text: str) -> None:
    atomic_write_text(Path(job_dir) / SUMMARY_FILE, text.rstrip("\n") + "\n")


def write_figures(job_dir: Path, draw: Callable[[Path], object]) -> None:
    """Draw the figures into a temporary folder of this writer with ``draw(folder)``, then
    put it in place of ``figures/`` (a reader sees the old folder or the new one, never
    half of one; an old folder is first moved aside, then removed)."""
    job_dir = Path(job_dir)
    tmp = temporary_name(job_dir / FIGURES_DIR)
    final = job_dir / FIGURES_DIR
    try:
        draw(tmp)
        for attempt in range(100):  # another writer may put its folder in place meanwhile
            if attempt:
                time.sleep(random.uniform(0.0, 0.01))
            if final.exists():
                aside = temporary_name(final)
                try:
                    os.replace(final, aside)
                except FileNotFoundError:
                    continue
                shutil.rmtree(aside, ignore_errors=True)
            try:
                os.replace(tmp, final)
                return
            except OSError:  # a folder appeared at the final name: move it aside again
                continue
        raise OSError(f"could not put the figures in place in {job_dir}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def write_mujoco_log(job_dir: Path, messages: list[str]) -> None:
    """mujoco.log: MuJoCo's warnings during the run, one per line (compliant_docking/sim/mjlog.py)."""
    atomic_write_text(Path(job_dir) / MUJOCO_LOG_FILE, "".join(f"{m}\n" for m in messages))


#: the first bytes of a figure file of each kind
_MAGIC = {".png": b"\x89PNG\r\n\x1a\n", ".pdf": b"%PDF"}


def artefact_problem(job_dir: Path, record: dict) -> str | None:
    """Why the files of a finished job (its ``metrics.json`` read as ``record``) cannot be
    trusted, or None: the time series must be readable with one row per step, the summary
    present, the video (if the record names one) and the figures non-empty files."""
    import pyarrow.parquet as pq

    job_dir = Path(job_dir)
    path = job_dir / TIMESERIES_FILE
    # the rows saved (output.every, docs/run_directory.md); a record without the key: one a step
    expected = record.get("timeseries_rows", record.get("steps"))
    unit = "rows saved" if record.get("timeseries_rows") not in (None, record.get("steps")) else "steps"
    if "timeseries_rows" in record and expected is None:
        pass  # output.timeseries=false: metrics only, no time series to check
    elif not path.is_file():
        return f"{TIMESERIES_FILE} is missing"
    else:
        try:
            rows = pq.read_table(path).num_rows  # every page: a truncated or corrupt file fails here
        except Exception as exc:
            return f"{TIMESERIES_FILE} cannot be read ({type(exc).__name__}: {_first_line(exc)})"
        if isinstance(expected, int) and rows != expected:
            return f"{TIMESERIES_FILE} has {rows} rows, {METRICS_FILE} says {expected} {unit}"
    if not (job_dir / SUMMARY_FILE).is_file():
        return f"{SUMMARY_FILE} is missing"
    video = record.get("video")
    if isinstance(video, str) and not _nonempty(job_dir / video):
        return f"the video {video} is missing or empty"
    for figure in sorted((job_dir / FIGURES_DIR).glob("*")) if (job_dir / FIGURES_DIR).is_dir() else []:
        magic = _MAGIC.get(figure.suffix)
        if not _nonempty(figure) or (magic and not figure.read_bytes()[: len(magic)] == magic):
            return f"the figure {FIGURES_DIR}/{figure.name} is empty or broken"
    return None


def _nonempty(path: Path) -> bool:
    try:
        return path.stat().st_size > 0
    except OSError:
        return False


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [""])[0][:200]


def read_config(job_dir: Path) -> dict | None:
    """The job's composed config (``.hydra/config.yaml``) as plain data, or None."""
    try:
        data = yaml.safe_load((Path(job_dir) / HYDRA_DIR / CONFIG_FILE).read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError):
        return None
    return data if isinstance(data, dict) else None


def flatten(mapping: Mapping[str, Any] | None, prefix: str = "") -> dict[str, Any]:
    """A nested config as ``{"controller.k": 300.0, …}`` (``{}`` for None): each leaf under
    its dotted key, lists as values, an empty mapping without a leaf. A key written dotted
    (``controller.k:`` in YAML) and the same key nested read the same. The one rule of every
    reader of a config: ``load_runs``' columns, MLflow's parameters, a sweep's ``params`` and
    a tuning study's ``params`` and ``draws``."""
    flat: dict[str, Any] = {}
    for key, value in (mapping or {}).items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            flat.update(flatten(value, f"{name}."))
        else:
            flat[name] = value
    return flat


# --------------------------------------------------------------------------- finding jobs
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
    return sorted(found, key=natural_key)


def natural_key(path: Path) -> list:
    """Sort key: digit runs compare as numbers (job 10 after job 9)."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", str(path))]


# --------------------------------------------------------------------------- overrides
def write_hydra_files(job_dir: Path, config: Any, overrides: list[str]) -> None:
    """``.hydra/config.yaml`` and ``.hydra/overrides.yaml`` as Hydra writes them for a run,
    for a job Hydra did not start (a Gymnasium episode): ``config`` a composed config."""
    from omegaconf import OmegaConf

    folder = Path(job_dir) / HYDRA_DIR
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write_text(folder / CONFIG_FILE, OmegaConf.to_yaml(config))
    atomic_write_text(folder / OVERRIDES_FILE, yaml.safe_dump(list(overrides), default_flow_style=False))


def read_overrides(job_dir: Path) -> dict[str, Any]:
    """The job's command-line overrides (``.hydra/overrides.yaml``) as {key: value}.

    Keys lose Hydra's ``+``/``++``/``~`` prefixes (``+experiment=x`` → ``experiment``);
    values are parsed as Hydra does (``0.0004`` → float, ``hqp`` → str); lists and
    dicts stay as their override text (``[0,0,-0.1]``) so a column keeps one type.
    """
    return dict(parse_override(line) for line in read_override_lines(job_dir))


def read_override_lines(job_dir: Path) -> list[str]:
    """The job's overrides as Hydra wrote them (``.hydra/overrides.yaml``); [] if none."""
    path = Path(job_dir) / HYDRA_DIR / OVERRIDES_FILE
    if not path.is_file():
        return []
    try:
        lines = yaml.safe_load(path.read_text(encoding="utf-8")) or []
    except (OSError, yaml.YAMLError):
        return []
    return [str(line) for line in lines] if isinstance(lines, list) else []


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
