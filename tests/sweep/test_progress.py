"""The console's sense of time and its lines: a sweep's progress line (time left, reasons
cut at whole clauses), the launch lines left out unless -v, a run's progress."""

import json
import logging

import pytest

from compliant_docking.sim.progress import RunProgress, duration_text
from compliant_docking.sweep import progress
from compliant_docking.sweep.progress import LaunchLines, clauses, job_line, time_left, verbose_argv

#: the gate's verdict of a run that failed four items (the force item's number is what a
#: cut at 160 characters used to split: "… over the 5")
VERDICT = (
    "not seated: depth error 12.3 mm > 1 mm; lateral error 0.6 mm > 0.5 mm; tilt 1.2 deg > 1 deg; "
    "key yaw 3.1 deg > 2.34 deg; peak force 63.6 N (filtered) over the 50 N budget"
)


def test_a_reason_is_cut_at_whole_clauses_never_inside_a_number():
    short = clauses(VERDICT)
    assert len(short) < 200 and short.endswith("; … (+1 more)")
    for clause in short.removesuffix("; … (+1 more)").split("; "):
        assert clause in VERDICT.split("; ")  # every clause kept whole
    assert clauses(VERDICT, limit=1000) == VERDICT
    assert clauses("one very long clause " * 20) == ("one very long clause " * 20).strip()  # the first: whole


def test_the_progress_line_says_the_time_left_and_the_whole_reason(tmp_path):
    sweep = tmp_path / "sweep"
    job = sweep / "3_controller=hqp"
    job.mkdir(parents=True)
    record = {"status": "ok", "success": False, "filtered_peak_axial_force_N": 63.6, "wall_time_s": 4.2}
    (job / "metrics.json").write_text(json.dumps({**record, "gate_verdict": VERDICT}))
    progress.reset_count(sweep)
    started = progress.started_at(sweep)
    assert started is not None
    (sweep / progress.COUNT_FILE).write_text(f"{2:<{progress.COUNT_WIDTH}d}{started - 30:.3f}\n")  # 30 s ago
    line = job_line(job, sweep, total=12)  # the 3rd of 12 jobs after 30 s: 9 left at 10 s each
    assert line.startswith("[3/12] 3_controller=hqp · finished · not docked · peak 63.6 N · 4.2 s · ")
    assert "about 1 min 30 s left" in line or "about 1 min 31 s left" in line
    assert line.endswith("; … (+1 more)") and "over the 5" not in line


def test_time_left_at_the_sweeps_pace():
    assert time_left(100.0, 4, 10, now=140.0) == "about 1 min 00 s left"
    assert time_left(100.0, 10, 10, now=140.0) == ""  # finished
    assert (
        time_left(None, 4, 10) == "" and time_left(100.0, None, 10) == "" and time_left(100.0, 4, None) == ""
    )
    assert [duration_text(s) for s in (0.4, 59.6, 61, 3599, 3720)] == ["0 s", "1 min 00 s", "1 min 01 s",
                                                                      "59 min 59 s", "1 h 02 min"]  # fmt: skip


@pytest.mark.parametrize(
    ("message", "shown"),
    [
        ("\t#12 : controller=hqp robot=fr3", False),  # Hydra's joblib and submitit launchers, ours
        ("PoolLauncher(2 workers) is launching 180 jobs", True),
        ("Launching jobs, sweep output dir : runs/multirun/x", True),
    ],
)
def test_the_launch_lines_are_left_out_unless_verbose(message, shown):
    record = logging.LogRecord("hydra", logging.INFO, __file__, 1, message, None, None)
    assert LaunchLines().filter(record) is shown
    assert verbose_argv(["-m", "-v", "robot=fr3"]) == ["-m", progress.VERBOSE_OVERRIDE, "robot=fr3"]
    assert verbose_argv(["--verbose"]) == [progress.VERBOSE_OVERRIDE]


def test_the_hydra_logging_config_names_the_filter_and_verbose_removes_it():
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    from compliant_docking import CONF_DIR
    from compliant_docking.config import register_schemas

    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        quiet = compose("config", return_hydra_config=True).hydra.hydra_logging
        loud = compose(
            "config", overrides=[progress.VERBOSE_OVERRIDE], return_hydra_config=True
        ).hydra.hydra_logging
    GlobalHydra.instance().clear()
    assert quiet.filters.launch_lines["()"] == "compliant_docking.sweep.progress.LaunchLines"
    assert (
        list(quiet.handlers.console.filters) == ["launch_lines"] and list(loud.handlers.console.filters) == []
    )


def test_a_run_in_a_log_prints_plain_lines_with_the_time_left(capsys):
    """stderr not a terminal (a log, a batch job): a line at each quarter of the run."""
    reporter = RunProgress(n_steps=18000, dt=0.001, enabled=True)
    assert not reporter.bar
    assert (
        reporter.line(4500, elapsed=1.5)
        == "  simulated 4.5 / 18.0 s (25 %) · 3.0× real time · about 4 s left"
    )
    for k in range(0, 18000, 100):
        reporter.update(k)
    reporter.done()
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(" · ")[0] for line in lines] == [
        "  simulated 4.5 / 18.0 s (25 %)",
        "  simulated 9.0 / 18.0 s (50 %)",
        "  simulated 13.5 / 18.0 s (75 %)",
    ]
    RunProgress(n_steps=18000, dt=0.001, enabled=False).update(4500)
    assert capsys.readouterr().err == ""
