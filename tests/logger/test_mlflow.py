"""+logger=mlflow: a sweep logged into a temporary store holds one parent run and one
child run per job with the job's config, metrics and files; a single run; a logger that
cannot log never fails the job; the old spelling +tracking=mlflow still works and says so."""

from __future__ import annotations

import json
import sys

import pytest
import yaml
from omegaconf import OmegaConf

from compliant_docking.logger.mlflow_callback import MlflowCallback, param_text
from compliant_docking.run.rundir import flatten
from tests.helpers import SWEEP_LAUNCHERS, sweep_with

#: two short docking jobs (0.3 s simulated: what is judged is what is logged, not the run)
SHORT = (
    "controller=impedance",
    "trajectory=quintic",
    "trajectory.duration=0.2",
    "task.settle_time=0.1",
    "task.press_duration=0.1",
    "task.progress=false",
)


@pytest.fixture
def store(tmp_path, monkeypatch):
    """A file store of its own (MLflow 3 wants MLFLOW_ALLOW_FILE_STORE for reading it too)."""
    monkeypatch.setenv("MLFLOW_ALLOW_FILE_STORE", "true")
    return (tmp_path / "mlruns").as_uri()


def runs_of(uri: str, experiment: str = "compliant-docking"):
    from mlflow.tracking import MlflowClient

    client = MlflowClient(uri)
    found = client.get_experiment_by_name(experiment)
    assert found is not None, f"no experiment {experiment!r} in {uri}"
    return client, client.search_runs([found.experiment_id])


@pytest.mark.parametrize("launcher", SWEEP_LAUNCHERS)
def test_a_sweep_is_a_parent_run_with_one_child_run_per_job(tmp_path, store, capsys, launcher):
    sweep = tmp_path / "sweep"
    result = sweep_with(
        launcher,
        capsys,
        sweep,
        *SHORT,
        "+logger=mlflow",
        "figures=true,false",  # sweep jobs draw none by default: the first draws them, to log them
        "hydra.callbacks.sweep.figures=false",
        env={"MLFLOW_TRACKING_URI": store},
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "mlflow: could not" not in result.stdout
    jobs = sorted(p for p in sweep.iterdir() if (p / "metrics.json").is_file())
    assert len(jobs) == 2 and all("logger" not in p.name for p in jobs)  # not in the job names

    client, runs = runs_of(store)
    parents = [r for r in runs if "mlflow.parentRunId" not in r.data.tags]
    children = [r for r in runs if "mlflow.parentRunId" in r.data.tags]
    assert len(parents) == 1 and len(children) == 2
    parent = parents[0]
    assert parent.data.tags["compliant_docking.sweep_dir"] == str(sweep.resolve())
    assert parent.data.metrics["jobs"] == 2 and parent.info.status == "FINISHED"
    assert {"summary.md", "summary.csv"} <= {a.path for a in client.list_artifacts(parent.info.run_id)}

    for run in children:
        assert run.data.tags["mlflow.parentRunId"] == parent.info.run_id
        job = next(p for p in jobs if p.name == run.info.run_name)
        record = json.loads((job / "metrics.json").read_text())
        config = OmegaConf.to_container(OmegaConf.load(job / ".hydra" / "config.yaml"), resolve=True)
        # the full resolved config as parameters
        expected = {k: param_text(v) for k, v in flatten(config).items()}
        assert run.data.params == expected
        assert run.data.params["robot.name"] == record["robot"]
        assert run.data.params["figures"] == param_text(job.name.startswith("0_"))
        # every number of metrics.json as a metric, the rest as tags
        assert run.data.metrics["peak_axial_force_N"] == pytest.approx(record["peak_axial_force_N"])
        assert run.data.metrics["success"] == float(record["success"])
        assert run.data.tags["status"] == record["status"] == "ok"
        assert run.data.tags["config_hash"] == record["config_hash"]
        files = {a.path for a in client.list_artifacts(run.info.run_id)}
        assert {"metrics.json", "summary.txt", "hydra"} <= files
        if job.name.startswith("0_"):  # figures=true: its figures are logged
            figures = {a.path for a in client.list_artifacts(run.info.run_id, "figures")}
            assert "figures/contact_force.png" in figures
        else:  # figures=false: none drawn, none logged
            assert "figures" not in files


def job_dir(tmp_path):
    """A finished job directory as the runner leaves it (no simulation needed)."""
    job = tmp_path / "runs" / "2025-06-01" / "14-03-12_fr3_impedance_quintic"
    (job / ".hydra").mkdir(parents=True)
    (job / "figures").mkdir()
    (job / "figures" / "contact_force.png").write_bytes(b"\x89PNG")
    cfg = {
        "controller": {"k": 300.0, "name": "impedance"},
        "task": {"stroke": [0.0, 0.0, -0.18], "init_pos": None},
    }
    (job / ".hydra" / "config.yaml").write_text(yaml.safe_dump(cfg))
    record = {"status": "ok", "error": None, "success": True, "peak_axial_force_N": 33.5, "robot": "fr3"}
    (job / "metrics.json").write_text(json.dumps(record))
    config = OmegaConf.create({**cfg, "hydra": {"runtime": {"output_dir": str(job)}}})
    return job, config, cfg


def test_a_single_run_is_a_run_of_its_own(tmp_path, store, capsys):
    job, config, cfg = job_dir(tmp_path)
    callback = MlflowCallback("compliant-docking", tracking_uri=store, artifacts=True, timeseries=False)
    callback.on_run_start(config)
    callback.on_job_end(config, job_return=None)
    assert "mlflow: run " in capsys.readouterr().out
    _, runs = runs_of(store)
    (run,) = runs
    assert "mlflow.parentRunId" not in run.data.tags
    assert run.data.params == {
        "controller.k": "300.0",
        "controller.name": "impedance",
        "task.stroke": "[0.0, 0.0, -0.18]",
        "task.init_pos": "null",
    }
    assert run.data.metrics == {"success": 1.0, "peak_axial_force_N": 33.5}
    assert run.data.tags["robot"] == "fr3" and run.info.status == "FINISHED"


def test_a_logger_that_cannot_log_says_so_and_never_fails_the_job(tmp_path, monkeypatch, capsys):
    job, config, _ = job_dir(tmp_path)
    monkeypatch.setitem(sys.modules, "mlflow.tracking", None)  # as if MLflow were not installed
    callback = MlflowCallback(
        "x", tracking_uri=(tmp_path / "mlruns").as_uri(), artifacts=True, timeseries=False
    )
    callback.on_run_start(config)
    callback.on_job_end(config, job_return=None)  # does not raise
    out = capsys.readouterr().out
    assert "mlflow: could not log 14-03-12_fr3_impedance_quintic" in out
    assert "pip install -e '.[logger]'" in out


# --------------------------------------------------------------------------- unreachable servers
class _Server:
    """A local TCP server that accepts connections and never answers (or, for a request
    for /health, answers 404): counts the connections it got."""

    def __init__(self, health: bool = False) -> None:
        import socket
        import threading

        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.uri = f"http://127.0.0.1:{self.sock.getsockname()[1]}"
        self.health, self.requests, self.held = health, [], []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            first = conn.recv(4096).decode(errors="replace").split("\r\n", 1)[0]
            self.requests.append(first)
            if self.health and " /health " in first:
                conn.sendall(b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n")
                conn.close()
            else:
                self.held.append(conn)  # never answered

    def close(self) -> None:
        self.sock.close()
        for conn in self.held:
            conn.close()


def _refusing_uri() -> str:
    import socket

    with socket.socket() as sock:  # a port nobody listens on once closed: connections are refused
        sock.bind(("127.0.0.1", 0))
        return f"http://127.0.0.1:{sock.getsockname()[1]}"


@pytest.mark.parametrize("kind", ["refused", "silent"])
def test_an_unreachable_server_turns_logging_off_with_one_line(tmp_path, monkeypatch, capsys, kind):
    """A port that refuses, or a server that never answers: one line when the command starts,
    nothing logged, nothing waited for later (MLflow's own retries took ~4 minutes per call),
    the job's files as they were."""
    from compliant_docking.logger import mlflow_callback

    monkeypatch.setattr(mlflow_callback, "PROBE_TIMEOUT_S", 0.5, raising=False)
    server = _Server() if kind == "silent" else None
    uri = server.uri if server else _refusing_uri()
    try:
        job, config, _ = job_dir(tmp_path)
        before = {p.name: p.read_bytes() for p in job.iterdir() if p.is_file()}
        single = MlflowCallback("x", tracking_uri=uri, artifacts=True, timeseries=False)
        single.on_run_start(config)
        single.on_job_end(config, job_return=None)
        sweep = MlflowCallback("x", tracking_uri=uri, artifacts=True, timeseries=False)
        sweep_config = OmegaConf.create(
            {"hydra": {"sweep": {"dir": str(tmp_path)}, "overrides": {"task": []}}}
        )
        sweep.on_multirun_start(sweep_config)
        sweep.on_job_end(config, job_return=None)
        out = capsys.readouterr().out.splitlines()
        assert len(out) == 2  # one line per command (the single run's, the sweep's), none per job
        for line in out:
            assert line.startswith(f"mlflow: logging off: {uri} did not answer within 0.5 s (")
            assert line.endswith("the results are in the run directories as always")
        assert {p.name: p.read_bytes() for p in job.iterdir() if p.is_file()} == before
        if server:
            assert len(server.requests) == 2  # one question per command, none per job
    finally:
        if server:
            server.close()


def test_a_server_that_stops_answering_costs_one_attempt_per_process(tmp_path, monkeypatch, capsys):
    """It answered when the command started, then not: the first job's logging times out
    (MLflow's timeout and retries bounded, here through the environment), says so, and the
    process's later jobs do not try again."""
    server = _Server(health=True)
    monkeypatch.setenv("MLFLOW_HTTP_REQUEST_TIMEOUT", "1")
    monkeypatch.setenv("MLFLOW_HTTP_REQUEST_MAX_RETRIES", "0")
    try:
        job, config, _ = job_dir(tmp_path)
        callback = MlflowCallback("x", tracking_uri=server.uri, artifacts=True, timeseries=False)
        callback.on_run_start(config)
        callback.on_job_end(config, job_return=None)
        callback.on_job_end(config, job_return=None)
        out = capsys.readouterr().out.splitlines()
        assert len(out) == 1 and out[0].startswith("mlflow: could not log 14-03-12_fr3_impedance_quintic: ")
        assert out[0].endswith("no more attempts from this process")
        assert sum(" /health " not in r for r in server.requests) == 1
    finally:
        server.close()


def _callbacks(*overrides: str) -> dict:
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    from compliant_docking import CONF_DIR
    from compliant_docking.config import register_schemas

    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose("config", overrides=list(overrides), return_hydra_config=True)
    return OmegaConf.to_container(cfg.hydra.callbacks)


def test_the_old_spelling_composes_the_same_logger_and_says_it_is_deprecated(capsys):
    """``+tracking=mlflow`` (scripts may have it) is ``+logger=mlflow`` plus one line saying
    so when the command starts."""
    from hydra.utils import instantiate

    new, old = _callbacks("+logger=mlflow"), _callbacks("+tracking=mlflow")
    assert new["mlflow"]["_target_"] == "compliant_docking.logger.mlflow_callback.MlflowCallback"
    assert old["mlflow"] == new["mlflow"]
    assert set(old) - set(new) == {"renamed_tracking"} and "renamed_tracking" not in new
    renamed = instantiate(old["renamed_tracking"])
    for start in (renamed.on_run_start, renamed.on_multirun_start):
        start(OmegaConf.create({}))
        err = capsys.readouterr().err
        assert err.startswith("compliant-docking: +tracking=mlflow is deprecated: use +logger=mlflow ")
        assert err.count("\n") == 1
