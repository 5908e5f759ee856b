"""The free-space tracking gate: statistics, PASS / each FAIL reason / INCOMPLETE, fail
closed on NaN/inf, config thresholds, and the preset end to end on both robots."""

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from omegaconf import OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.evaluation.tracking_gate import (
    FAIL,
    INCOMPLETE,
    PASS,
    compute_tracking_metrics,
    format_tracking_gate,
    tracking_gate,
)
from compliant_docking.run.rundir import write_metrics
from compliant_docking.run.runner import execute
from compliant_docking.run.summary import format_summary
from tests.helpers import cli_in_process_output, make_cfg

#: the thresholds of conf/task (the seed's TrackingThresholds values)
THRESHOLDS = OmegaConf.to_object(make_cfg().task.tracking_gate)

SEGMENTS = [
    ("transition_1", 0.0, 1.5),
    ("circle", 1.5, 6.5),
    ("transition_2", 6.5, 8.0),
    ("figure8", 8.0, 13.0),
]
DT = 0.001


def frame(duration=15.0, pos=1e-4, ori=1e-4, nv=7):
    """A clean run: constant errors, no saturation, no contact."""
    t = np.arange(int(round(duration / DT))) * DT
    n = len(t)
    data = {"t": t, "pos_error": np.full(n, pos)}
    for axis, value in zip("xyz", (ori, 0.0, 0.0)):
        data[f"ori_error_{axis}"] = np.full(n, value)
    for i in range(nv):
        data[f"tau{i + 1}"] = np.full(n, 2.0 * (-1) ** i)
    data["torque_saturated"] = np.zeros(n, dtype=bool)
    data["contacts"] = np.zeros(n, dtype=np.int32)
    return pd.DataFrame(data)


def window(ts, t0, t1):
    return (ts["t"] >= t0) & (ts["t"] < t1)


def judge(ts, thresholds=None, complete=True, segments=SEGMENTS):
    return tracking_gate(ts, segments, thresholds or THRESHOLDS, complete=complete)


def test_statistics_per_segment_and_overall():
    ts = frame()
    ts.loc[window(ts, 1.5, 6.5), "pos_error"] = 0.002
    ts.loc[window(ts, 8.0, 13.0), "pos_error"] = np.linspace(0, 0.003, 5000)
    ts.loc[ts["t"] >= 13.0, "pos_error"] = 0.1  # the hold after the motion is not judged…
    ts.loc[ts["t"] >= 14.0, "contacts"] = 2  # …but contacts count over the whole run
    m = compute_tracking_metrics(ts, SEGMENTS)
    assert [name for name, _ in m.segments] == [s[0] for s in SEGMENTS]
    assert math.isclose(m.segment("circle").position_rms_m, 0.002)
    ramp = np.linspace(0, 0.003, 5000)
    assert math.isclose(m.segment("figure8").position_rms_m, np.sqrt(np.mean(ramp**2)))
    assert math.isclose(m.segment("figure8").position_peak_m, 0.003)
    assert math.isclose(m.overall.position_peak_m, 0.003)
    assert math.isclose(m.overall.orientation_rms_rad, 1e-4)
    assert m.peak_joint_torque_Nm == 2.0 and m.torque_saturation_ratio == 0.0
    assert m.max_contacts == 2


def test_pass():
    result = judge(frame())
    assert result.status == PASS and result.success and result.failures == ()
    record = result.record()
    assert record["tracking_gate"] == "PASS"
    assert math.isclose(record["tracking_circle_pos_rms_m"], 1e-4)
    assert "PASS" in format_tracking_gate(result)


@pytest.mark.parametrize(
    "reason, expected",
    [
        ("circle RMS", "circle position RMS 6 mm > 5 mm"),
        ("figure-8 RMS", "figure8 position RMS 6 mm > 5 mm"),
        ("peak", "overall position peak 16 mm > 15 mm"),
        ("orientation", "overall orientation RMS 0.6 deg > 0.5 deg"),
        ("saturation", "torque saturation ratio 2 % > 1 %"),
        ("contacts", "max contacts 1 > 0"),
    ],
)
def test_each_fail_reason(reason, expected):
    ts = frame()
    if reason in ("circle RMS", "figure-8 RMS"):
        t0, t1 = (1.5, 6.5) if reason == "circle RMS" else (8.0, 13.0)
        ts.loc[window(ts, t0, t1), "pos_error"] = 0.006
    elif reason == "peak":
        ts.loc[ts["t"] == 0.5, "pos_error"] = 0.016  # one sample in a transition
    elif reason == "orientation":
        ts["ori_error_y"] = math.radians(0.6)
        ts["ori_error_x"] = 0.0
    elif reason == "saturation":
        ts.loc[window(ts, 2.0, 2.26), "torque_saturated"] = True  # 260 of 13 000 steps
    elif reason == "contacts":
        ts.loc[ts["t"] == 14.5, "contacts"] = 1  # during the hold
    result = judge(ts)
    assert result.status == FAIL and not result.success
    assert result.failures == (expected,), result.failures


def test_every_failing_item_is_listed():
    ts = frame(pos=0.02, ori=0.02)
    ts["contacts"] = 3
    result = judge(ts)
    assert result.status == FAIL
    text = "; ".join(result.failures)
    for item in (
        "circle position RMS",
        "figure8 position RMS",
        "overall position peak",
        "overall orientation RMS",
        "max contacts",
    ):
        assert item in text
    assert len(result.failures) == 5


def test_a_missing_gated_segment_fails():
    result = judge(frame(), segments=[s for s in SEGMENTS if s[0] != "figure8"])
    assert result.status == FAIL
    assert result.failures == ("figure8 position RMS not available (no data)",)


def test_incomplete_is_not_judged():
    ts = frame(duration=5.0, pos=0.05)  # bad, but the run stopped early
    result = judge(ts, complete=False)
    assert result.status == INCOMPLETE and not result.success and result.failures == ()
    assert result.record()["tracking_gate"] == "INCOMPLETE"
    assert "INCOMPLETE" in format_tracking_gate(result)


@pytest.mark.parametrize(
    "column, value, where",
    [
        ("pos_error", np.nan, 3.0),  # in the circle
        ("pos_error", np.inf, 0.5),  # in a transition
        ("ori_error_z", np.nan, 9.0),
        ("tau3", np.inf, 7.0),  # peak torque has no threshold: still fails closed
        ("tau1", np.nan, 10.0),
    ],
)
def test_non_finite_values_fail_closed(column, value, where):
    ts = frame()
    ts.loc[np.isclose(ts["t"], where), column] = value
    result = judge(ts)
    assert result.status == FAIL
    assert any("not finite" in f for f in result.failures), result.failures


def test_a_non_finite_threshold_fails_closed():
    result = judge(frame(), replace(THRESHOLDS, position_peak_m=float("nan")))
    assert result.status == FAIL and "threshold position_peak_m" in result.failures[0]


def test_thresholds_come_from_the_config_and_unknown_keys_are_rejected():
    cfg = make_cfg("+experiment=tracking_gate", "task.tracking_gate.circle_position_rms_m=1e-5")
    assert cfg.task.tracking_gate.circle_position_rms_m == 1e-5
    assert cfg.task.tracking_gate.max_contacts == 0
    assert math.isclose(cfg.task.tracking_gate.orientation_rms_rad, math.radians(0.5))
    result = judge(frame(), cfg.task.tracking_gate)  # a DictConfig works as thresholds
    assert result.failures == ("circle position RMS 0.1 mm > 0.01 mm",)
    with pytest.raises(Exception, match="circle_position_rms"):
        make_cfg("+experiment=tracking_gate", "task.tracking_gate.circle_position_rms=1e-5")


def test_record_is_flat_json_with_nulls(tmp_path):
    ts = frame()
    ts.loc[np.isclose(ts["t"], 3.0), "pos_error"] = np.nan
    record = {"status": "ok", **judge(ts).record()}
    write_metrics(tmp_path, record)
    back = json.loads((tmp_path / "metrics.json").read_text())
    assert back["tracking_gate"] == "FAIL" and back["tracking_circle_pos_rms_m"] is None
    assert all(not isinstance(v, (dict, list)) for v in back.values())


def test_summary_prints_the_gate():
    record = {
        "status": "ok",
        "success": False,
        "gate_failures": "circle position RMS 6 mm > 5 mm",
        **judge(frame()).record(),
    }
    record["tracking_gate"] = "FAIL"
    text = format_summary(record)
    assert "[tracking gate: FAIL]" in text and "tracking gate FAIL" in text
    assert "circle" in text and "[seat" not in text


# --------------------------------------------------------------------------- end to end
#: per-segment position RMS bounds [m] (circle, figure-8): 1.5× the worst measured over
#: the three controllers (iiwa14 0.016 / 0.032 mm, FR3 0.171 / 0.211 mm), so a regression
#: of half the error fails; the research code's values (iiwa14 0.236 / 0.269 mm, FR3
#: 1.545 / 0.938 mm) are 5-15× looser than ours and would hide one
TARGETS = {"iiwa14": (0.024e-3, 0.048e-3), "fr3": (0.26e-3, 0.32e-3)}


def available_controllers():
    """Every controller with a config option in conf/controller/ (impedance first)."""
    names = sorted(p.stem for p in (Path(CONF_DIR) / "controller").glob("*.yaml"))
    return sorted(names, key=lambda n: n != "impedance")


def preset_cells():
    """(robot, controller) of every robot and controller: the default controller's cells run
    in the fast suite (the preset, its gate and the runner on both robots); the other
    controllers' cells, each a 15 s run with its own gain file, are `slow` (nightly): the fast
    suite proves that each gain file reaches the controller
    (test_each_controllers_tracking_gains_reach_the_preset) and each law by its own tests
    (tests/control/test_transients.py, test_observer.py, test_hqp.py, test_se3_lie.py)."""
    nightly = pytest.mark.slow(reason="the impedance cells prove the preset on this robot; see preset_cells")
    return [
        (robot, name) if name == "impedance" else pytest.param(robot, name, marks=nightly)
        for name in available_controllers()
        for robot in ("iiwa14", "fr3")
    ]


@pytest.mark.parametrize("robot, controller", preset_cells())
def test_the_preset_passes_on_both_robots(robot, controller, tmp_path):
    """The preset with the default controller (impedance), and with every other controller
    (its tracking gains come from conf/robot_controller/tracking/<robot>_<controller>.yaml)."""
    overrides = [] if controller == "impedance" else [f"controller={controller}"]
    cfg = make_cfg("+experiment=tracking_gate", f"robot={robot}", "task.progress=false", *overrides)
    record = execute(cfg, tmp_path, figures=False, echo=False)
    assert record["status"] == "ok", record["error"]
    assert record["tracking_gate"] == "PASS" and record["success"] is True, record["gate_failures"]
    circle, eight = TARGETS[robot]
    assert record["tracking_circle_pos_rms_m"] <= circle
    assert record["tracking_figure8_pos_rms_m"] <= eight
    assert record["tracking_contacts_max"] == 0 and record["tracking_saturation_ratio"] <= 0.01
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["tracking_gate"] == "PASS" and saved["gate_failures"] is None


# the FR3's cell is nightly (`slow`), with the slow cells of test_the_preset_passes_on_both_robots
# whose wiring it checks; fast proof: the iiwa14's cell (the same `tracking/${robot}_${controller}`
# entry, the robot an interpolation) and test_the_preset_passes_on_both_robots[fr3-impedance]
# (the FR3's tracking gains reach the run: with its docking gains the circle RMS is 0.88 mm,
# over the cell's 0.26 mm bound; measured)
@pytest.mark.parametrize("robot", ["iiwa14", pytest.param("fr3", marks=pytest.mark.slow)])
def test_each_controllers_tracking_gains_reach_the_preset(robot):
    """Every controller's tracking gain file (conf/robot_controller/tracking/) is what the
    preset's controller carries on each robot, and differs from its docking gains: the
    wiring the slow cells of test_the_preset_passes_on_both_robots rely on."""

    def gains_of(option: str) -> dict:  # a gain file's keys, after those of the files it extends
        path = Path(CONF_DIR) / "robot_controller" / f"{option}.yaml"
        own = OmegaConf.to_container(OmegaConf.load(path))
        extended = [gains_of(name) for name in own.pop("defaults", []) if name != "_self_"]
        return {key: value for gains in [*extended, own] for key, value in gains.items()}

    for controller in available_controllers():
        option = f"tracking/{robot}_{controller}"
        gains = gains_of(option)
        overrides = (f"robot={robot}", f"controller={controller}")
        preset = OmegaConf.to_container(
            make_cfg("+experiment=tracking_gate", *overrides).controller, enum_to_str=True
        )
        docking = OmegaConf.to_container(make_cfg(*overrides).controller, enum_to_str=True)
        assert gains and {key: preset[key] for key in gains} == gains, option
        assert any(docking[key] != value for key, value in gains.items()), option


def test_a_gate_failure_exits_3_through_the_command_line(tmp_path, capsys):
    """The PASS side runs through the runner above (every robot and controller); here the
    command line (its main, in this process) turns a FAIL into exit status 3 and prints the
    failing item. Exit statuses through a real process: tests/run/test_interrupt.py, and
    tests/run/test_cli.py's nightly tests. The path at twice its speed (7.2 s instead of
    15 s): only the circle's RMS, held to 0.1 µm, fails."""
    code, out, err = cli_in_process_output(
        capsys,
        "+experiment=tracking_gate",
        "task.progress=false",
        "task.tracking_gate.circle_position_rms_m=1e-7",
        "trajectory.transition_duration=1.0",
        "trajectory.circle_duration=2.5",
        "trajectory.figure8_duration=2.5",
        "task.settle_time=0.2",
        "figures=false",
        f"hydra.run.dir={tmp_path / 'run'}",
    )
    assert code == 3, out + err
    failures = out.split("gate: ")[-1]  # the failing items, after the summary's last "gate: "
    assert (
        "tracking gate FAIL" in out
        and failures.startswith("circle position RMS")
        and "figure8" not in failures
    )


def test_a_short_run_is_incomplete(tmp_path):
    cfg = make_cfg("+experiment=tracking_gate", "task.duration=1.0", "task.progress=false")
    record = execute(cfg, tmp_path, figures=False, echo=False)
    assert record["status"] == "incomplete" and record["tracking_gate"] == "INCOMPLETE"
    assert record["success"] is False and "incomplete" in record["gate_failures"]


def test_tracking_with_a_target_is_refused(tmp_path):
    record = execute(
        make_cfg("trajectory=tracking", "task.progress=false"), tmp_path, figures=False, echo=False
    )
    assert record["status"] == "failed" and record["success"] is False
    assert "target=none" in record["error"]


def test_other_free_space_runs_have_no_gate(tmp_path):
    cfg = make_cfg(
        "target=none",
        "trajectory=hold",
        "trajectory.duration=0.2",
        "task.init_pos=[0.55,0.0,0.45]",
        "task.settle_time=0.0",
        "task.progress=false",
    )
    record = execute(cfg, tmp_path, figures=False, echo=False)
    assert record["status"] == "ok" and record["success"] is None
    assert "tracking_gate" not in record
