"""``+logger=mlflow``: every job logged to MLflow (conf/logger/mlflow.yaml, docs/logger.md).

A Hydra callback, :class:`MlflowCallback`, beside the sweep callback:

- a single run is one MLflow run in the experiment (``experiment``, default
  ``compliant-docking``);
- a sweep (``-m``, also a tuning study) is one parent run, created by the launching
  process when the sweep starts (and found again by its sweep directory when the sweep
  is resumed), with one child run per job, logged by the worker that ran the job;
- each job's run holds its full resolved config as parameters (dotted keys:
  ``controller.k``, ``task.misalignment.seed``, …), every number of its metrics.json
  as a metric (``success`` as 1/0), the other fields as tags (status, error, options,
  provenance), and its artefacts: ``figures/``, the video, ``summary.txt``,
  ``metrics.json``, the composed config (and the time series with ``timeseries=true``);
- the parent run gets the sweep's summary files and figures (and a tuning study's best
  parameters and trials table) when the sweep ends.

Where: ``tracking_uri``, else the environment's ``MLFLOW_TRACKING_URI``, else the local
file store ``runs/mlruns`` (MLflow 3 keeps its file store in maintenance mode and asks for
``MLFLOW_ALLOW_FILE_STORE=true``, which this callback sets for that store only).
Logging never fails a job or a sweep: a run that cannot be logged prints one line.
A tracking server that cannot be reached costs seconds, not minutes: the launching
process asks it once (:func:`unreachable`, :data:`PROBE_TIMEOUT_S`) and turns logging
off for the command with one line when it does not answer; MLflow's own HTTP timeout and
retries are bounded (:data:`HTTP_DEFAULTS`, unless the environment sets them), and a
process whose logging fails to connect stops trying for its later jobs.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from compliant_docking.run import rundir
from compliant_docking.sweep.progress import emit
from compliant_docking.sweep.session import SweepSession

#: the default local store, relative to the working directory (the repository root)
DEFAULT_STORE = Path("runs") / "mlruns"
#: tag naming the sweep directory of a parent run (how a resumed sweep finds its parent)
SWEEP_TAG = "compliant_docking.sweep_dir"
JOB_TAG = "compliant_docking.job_dir"
#: MLflow's limits: values per log_batch call, characters per param / tag value
BATCH, PARAM_CHARS, TAG_CHARS = 100, 6000, 5000
#: files of a sweep directory logged with its parent run (summaries, tuning outputs)
SWEEP_FILES = (
    "summary.md",
    "summary.csv",
    "comparison.csv",
    "paired.csv",
    "best_params.yaml",
    "trials.csv",
)
SWEEP_FOLDERS = ("comparison", "tuning", "pareto")
#: seconds the launching process waits for a tracking server's answer before tracking is off
PROBE_TIMEOUT_S = 5.0
#: MLflow's HTTP client settings used unless the environment sets them: its defaults (120 s
#: per request, 7 retries with doubling back-off) cost about 4 minutes per call to a server
#: that does not answer
HTTP_DEFAULTS = {"MLFLOW_HTTP_REQUEST_TIMEOUT": "10", "MLFLOW_HTTP_REQUEST_MAX_RETRIES": "2"}
#: ``requests``' errors for a server that cannot be reached or does not answer (by name:
#: requests is MLflow's dependency, not ours)
CONNECTION_ERRORS = ("ConnectionError", "ConnectTimeout", "ReadTimeout", "Timeout")
#: MLflow tracking URIs this process could not reach (no more attempts for its later jobs)
_UNREACHABLE: set[str] = set()


class LoggerUnavailable(RuntimeError):
    """MLflow is not installed: the message says how to install it."""


def unreachable(uri: str) -> str | None:
    """Why the tracking server at ``uri`` cannot be reached (one request, at most
    :data:`PROBE_TIMEOUT_S`), or None: it answered (any HTTP status), or ``uri`` is not an
    HTTP server (a file or database store is checked when it is used)."""
    import urllib.error
    import urllib.request

    if not uri.startswith(("http://", "https://")):
        return None
    try:
        with urllib.request.urlopen(f"{uri.rstrip('/')}/health", timeout=PROBE_TIMEOUT_S):
            return None
    except urllib.error.HTTPError:  # an answer: the server is there
        return None
    except (urllib.error.URLError, OSError, ValueError) as exc:
        reason = getattr(exc, "reason", exc)
        return f"{type(reason).__name__}: {reason}" if str(reason) else type(reason).__name__


def param_text(value: Any) -> str:
    """A config value as MLflow parameter text: JSON for lists and null, else str."""
    text = json.dumps(value) if isinstance(value, (list, dict)) or value is None else str(value)
    return text[:PARAM_CHARS]


class MlflowCallback(Callback):
    """See the module docstring. ``experiment``: the MLflow experiment; ``tracking_uri``:
    the store (null: ``MLFLOW_TRACKING_URI`` or ``runs/mlruns``); ``artifacts``: log the
    job's files; ``timeseries``: also its timeseries.parquet (a few MB a run)."""

    def __init__(self, experiment: str, tracking_uri: str | None, artifacts: bool, timeseries: bool) -> None:
        self.experiment = str(experiment)
        self.tracking_uri = tracking_uri
        self.artifacts = bool(artifacts)
        self.timeseries = bool(timeseries)
        self.uri: str | None = None  # resolved in the launching process, carried to the workers
        self.parent_run_id: str | None = None
        self.off = False  # the store did not answer: nothing is logged (carried to the workers)

    # ------------------------------------------------------------------ the store
    def resolve_uri(self) -> str:
        if self.tracking_uri:
            return str(self.tracking_uri)
        if os.environ.get("MLFLOW_TRACKING_URI"):
            return os.environ["MLFLOW_TRACKING_URI"]
        return (Path.cwd() / DEFAULT_STORE).resolve().as_uri()

    def client(self):
        from compliant_docking.extras import MissingExtra, require

        try:
            require("logger", "mlflow.tracking")
        except MissingExtra as exc:
            raise LoggerUnavailable(str(exc)) from None
        from mlflow.tracking import MlflowClient

        uri = self.uri or self.resolve_uri()
        if uri.startswith("file:") or "://" not in uri:
            os.environ.setdefault("MLFLOW_ALLOW_FILE_STORE", "true")  # MLflow 3: maintenance mode
        for name, value in HTTP_DEFAULTS.items():
            os.environ.setdefault(name, value)
        return MlflowClient(tracking_uri=uri)

    def _reachable(self) -> bool:
        """Ask the store once (launching process); False, said in one line, when it does not
        answer: logging is then off for this command (``self.uri`` None, carried to the jobs)."""
        why = unreachable(self.uri) if self.uri else None
        if why is None:
            return True
        emit(
            f"mlflow: logging off: {self.uri} did not answer within {PROBE_TIMEOUT_S:g} s ({why}); "
            "the results are in the run directories as always"
        )
        self.uri, self.off = None, True
        return False

    def experiment_id(self, client) -> str:
        found = client.get_experiment_by_name(self.experiment)
        if found is not None:
            return found.experiment_id
        try:
            return client.create_experiment(self.experiment)
        except Exception:  # another worker created it meanwhile
            found = client.get_experiment_by_name(self.experiment)
            if found is None:
                raise
            return found.experiment_id

    # ------------------------------------------------------------------ launching process
    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        self.uri = self.resolve_uri()
        self._reachable()

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        self.uri = self.resolve_uri()
        if not self._reachable():
            return
        try:
            client = self.client()
            experiment_id = self.experiment_id(client)
            sweep_dir = Path(str(config.hydra.sweep.dir)).resolve()
            self.parent_run_id = self._parent(client, experiment_id, sweep_dir, config)
            SweepSession.current().after_finish.append(self._finish_parent)
            emit(f"mlflow: sweep → run {self.parent_run_id} of experiment {self.experiment!r} at {self.uri}")
        except Exception as exc:  # logging must never stop a sweep
            emit(f"mlflow: logging off for this sweep ({type(exc).__name__}: {exc})")
            self.parent_run_id = None
            self.uri = None

    def _parent(self, client, experiment_id: str, sweep_dir: Path, config: DictConfig) -> str:
        """The sweep's parent run: the one of an earlier start of this sweep directory
        (a resumed sweep or tuning study), else a new one."""
        quoted = str(sweep_dir).replace("'", "\\'")
        found = client.search_runs(
            [experiment_id], filter_string=f"tags.`{SWEEP_TAG}` = '{quoted}'", max_results=1
        )
        if found:
            run_id = found[0].info.run_id
            client.update_run(run_id, status="RUNNING")
            return run_id
        overrides = " ".join(str(o) for o in config.hydra.overrides.task)
        tags = {SWEEP_TAG: str(sweep_dir), "overrides": overrides[:TAG_CHARS], "kind": "sweep"}
        sweeper = str(OmegaConf.select(config, "hydra.sweeper._target_", default="") or "")
        tags["sweeper"] = sweeper.rsplit(".", 1)[-1]
        run = client.create_run(experiment_id, run_name=_sweep_name(sweep_dir), tags=tags)
        return run.info.run_id

    def _finish_parent(self, outcome) -> None:
        """When the sweep is summarised: its files, counts and status on the parent run."""
        if self.parent_run_id is None:
            return
        try:
            client = self.client()  # first: says how to install MLflow when it is missing
            from mlflow.entities import Metric

            sweep_dir = Path(outcome.sweep_dir)
            for name in SWEEP_FILES:
                if (sweep_dir / name).is_file():
                    client.log_artifact(self.parent_run_id, str(sweep_dir / name))
            for folder in SWEEP_FOLDERS:
                if (sweep_dir / folder).is_dir():
                    client.log_artifacts(self.parent_run_id, str(sweep_dir / folder), folder)
            now = int(time.time() * 1000)
            counts = {
                "jobs": outcome.jobs,
                "ok": outcome.ok,
                "failed": outcome.failed,
                "docked": outcome.docked,
            }
            client.log_batch(
                self.parent_run_id, metrics=[Metric(k, float(v), now, 0) for k, v in counts.items()]
            )
            client.set_terminated(self.parent_run_id, "KILLED" if outcome.aborted else "FINISHED")
        except Exception as exc:  # logging never changes a sweep's outcome
            emit(f"mlflow: could not finish the sweep's run ({type(exc).__name__}: {exc})")

    # ------------------------------------------------------------------ the job's process
    def on_job_end(self, config: DictConfig, job_return: Any, **kwargs: Any) -> None:
        from compliant_docking.sweep import resume

        if self.off or getattr(job_return, "_return_value", None) == resume.SKIPPED:
            return  # logging is off (said once), or a resumed sweep kept this job: logged when it ran
        out_dir = Path(str(config.hydra.runtime.output_dir))
        uri = self.uri or self.resolve_uri()
        if uri in _UNREACHABLE:
            return  # an earlier job of this process said so
        try:
            run_id = self.log_job(out_dir, _task_config(config, job_return))
            if self.parent_run_id is None:  # a single run: say where it went
                emit(f"mlflow: run {run_id} of experiment {self.experiment!r} at {uri}")
        except Exception as exc:  # logging never fails a job
            if _is_connection_error(exc):
                _UNREACHABLE.add(uri)
                emit(
                    f"mlflow: could not log {out_dir.name}: {uri} does not answer ({type(exc).__name__}); "
                    "no more attempts from this process"
                )
            else:
                emit(f"mlflow: could not log {out_dir.name} ({type(exc).__name__}: {exc})")

    def log_job(self, out_dir: Path, cfg: dict) -> str:
        """Log one finished job directory as a run (a child of the sweep's); its id."""
        client = self.client()  # first: says how to install MLflow when it is missing
        from mlflow.entities import Metric, Param, RunTag

        experiment_id = self.experiment_id(client)
        record, problem = rundir.read_metrics(out_dir)
        record = record or {"status": "failed", "error": problem}
        tags = {JOB_TAG: str(out_dir.resolve()), "kind": "job"}
        if self.parent_run_id:
            tags["mlflow.parentRunId"] = self.parent_run_id
        run = client.create_run(experiment_id, run_name=out_dir.name, tags=tags, start_time=_millis(record))
        run_id = run.info.run_id
        now = int(time.time() * 1000)
        metrics, text = [], []
        for key, value in record.items():
            if isinstance(value, bool):
                metrics.append(Metric(key, float(value), now, 0))
            elif isinstance(value, (int, float)):
                metrics.append(Metric(key, float(value), now, 0))
            elif value is not None:
                text.append(RunTag(key, str(value)[:TAG_CHARS]))
        params = [Param(k, param_text(v)) for k, v in rundir.flatten(cfg).items()]
        for i in range(0, max(len(params), len(metrics), len(text)), BATCH):
            client.log_batch(
                run_id, metrics=metrics[i : i + BATCH], params=params[i : i + BATCH], tags=text[i : i + BATCH]
            )
        if self.artifacts:
            self._artifacts(client, run_id, out_dir)
        status = "FAILED" if record.get("status") == "failed" else "FINISHED"
        client.set_terminated(run_id, status)
        return run_id

    def _artifacts(self, client, run_id: str, out_dir: Path) -> None:
        from compliant_docking.viz.render import VIDEO_FILE

        files = [rundir.METRICS_FILE, rundir.SUMMARY_FILE, VIDEO_FILE]
        if self.timeseries:
            files.append(rundir.TIMESERIES_FILE)
        for name in files:
            if (out_dir / name).is_file():
                client.log_artifact(run_id, str(out_dir / name))
        if (out_dir / rundir.FIGURES_DIR).is_dir():
            client.log_artifacts(run_id, str(out_dir / rundir.FIGURES_DIR), rundir.FIGURES_DIR)
        config_file = out_dir / rundir.HYDRA_DIR / rundir.CONFIG_FILE
        if config_file.is_file():
            client.log_artifact(run_id, str(config_file), "hydra")


class Renamed(Callback):
    """A deprecated spelling on the command line (``+tracking=mlflow``, now ``+logger=mlflow``):
    one line on stderr when the command starts (the launching process); nothing else changes."""

    def __init__(self, old: str, new: str) -> None:
        self.old, self.new = old, new

    def _say(self) -> None:
        print(
            f'compliant-docking: {self.old} is deprecated: use {self.new} (in this project "tracking" '
            "means path following: trajectory=tracking); the old spelling will be removed.",
            file=sys.stderr,
        )

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        self._say()

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        self._say()


def _is_connection_error(exc: BaseException) -> bool:
    """Whether ``exc``, or an error it arose from (MLflow wraps those of ``requests``), says
    the tracking server could not be reached or did not answer in time."""
    seen: BaseException | None = exc
    while seen is not None:
        if isinstance(seen, (ConnectionError, TimeoutError)) or type(seen).__name__ in CONNECTION_ERRORS:
            return True
        seen = seen.__cause__ or seen.__context__
    return False


def _task_config(config: DictConfig, job_return: Any) -> dict:
    """The job's composed config without Hydra's node, resolved, as plain data."""
    cfg = getattr(job_return, "cfg", None)
    if cfg is None:
        cfg = OmegaConf.masked_copy(config, [str(k) for k in config if k != "hydra"])
    data = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    if isinstance(data, dict):
        data.pop("hydra", None)
        return data
    return {}


def _millis(record: dict) -> int | None:
    from datetime import datetime

    try:
        return int(datetime.fromisoformat(str(record["started_at"])).timestamp() * 1000)
    except (KeyError, TypeError, ValueError):
        return None


def _sweep_name(sweep_dir: Path) -> str:
    """``multirun/2025-06-01/14-03-12`` or ``tune/fr3_impedance``: the sweep's last parts."""
    return "/".join(sweep_dir.parts[-3:]) if "multirun" in sweep_dir.parts else "/".join(sweep_dir.parts[-2:])
