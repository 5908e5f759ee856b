"""End to end: the default scene docks, the run directory is complete, failures are clean."""

import json

import pytest

from compliant_docking.evaluation.registry import CONTACT_KEYS, DOCKING_KEYS
from compliant_docking.run.runner import execute
from tests.helpers import SHORT_CONTACT, cli_in_process, make_cfg

REQUIRED = {
    "status",
    "error",
    "success",
    "sim_time_s",
    "wall_time_s",
    "real_time_factor",
    "seat_depth_error_m",
    "seat_lateral_error_m",
    "seat_tilt_deg",
    "gate_failures",
    "robot",
    "controller",
    "trajectory",
    *DOCKING_KEYS,
    *CONTACT_KEYS,
    "gate_verdict",
}


def test_default_scene_docks_under_gravity(tmp_path):
    """The default scene with gravity on (physics=earth); its zero-g twin runs through the
    command line (tests/run/test_cli.py). Seated (< 1 mm) inside the 0.4 mm clearance
    (+0.1 mm chamfer play); pressed home with k·5 mm = 0.25 N (measured 0.24999 N: 0.1 %);
    peak force 1.37 N, the press, as in zero gravity (it used to read 3.57 N: the tool's
    weight in the sensor reading at t = 0, taken with the arm in free fall)."""
    record = execute(make_cfg("physics=earth", "task.progress=false"), tmp_path, figures=False, echo=False)
    assert record["status"] == "ok" and record["error"] is None
    assert record["success"] is True, record["gate_failures"]
    assert record["seat_depth_error_m"] < 1e-3
    assert record["seat_lateral_error_m"] < 0.4e-3 + 1e-4
    assert record["steady_axial_force_N"] == pytest.approx(50.0 * 0.005, rel=1e-3)
    assert record["sim_time_s"] == pytest.approx(18.0)
    # it touched once, at the seat, and holds still: no chatter, the gate says docked
    assert record["gate_verdict"] == "docked" and record["steady_contact_events_per_s"] == 0.0
    assert record["first_strike_force_N"] == pytest.approx(1.37, abs=0.05)  # the press, not a strike
    # the peak is the contact's, in zero and in Earth gravity alike: no reading at t = 0
    # shows a force that is no contact (it used to be the tool's weight, 3.6 N, under gravity)
    assert record["peak_axial_force_N"] == pytest.approx(record["first_strike_force_N"], abs=0.01)
    text = (tmp_path / "metrics.json").read_text()
    assert REQUIRED <= json.loads(text).keys()
    assert "NaN" not in text and "Infinity" not in text


def test_diverging_run_fails_cleanly(tmp_path):
    record = execute(
        make_cfg(
            "robot.max_torque=[1e9,1e9,1e9,1e9,1e9,1e9,1e9]",
            "controller.k=1e9",
            "controller.m=0.001",
            "task.progress=false",
        ),
        tmp_path,
        echo=False,
    )
    assert record["status"] == "failed" and record["success"] is False
    assert "diverged" in record["error"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metrics.json", "summary.txt"]
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["peak_axial_force_N"] is None and saved["status"] == "failed"


@pytest.mark.parametrize(
    "override, message",
    [
        ("controller=nope", "Available options in 'controller'"),
        ("controller.kk=1", "controller.kk"),
        ("controller.k=abc", "could not be converted to Float"),
        ("physics.integrator=foo", "expected one of [euler, rk4, implicit, implicitfast]"),
    ],
)
def test_bad_config_fails_at_composition(tmp_path, capsys, override, message):
    code, err = cli_in_process(capsys, override, f"hydra.run.dir={tmp_path / 'run'}")
    assert code == 2
    assert message in err
    assert not (tmp_path / "run").exists()  # nothing written


@pytest.mark.parametrize(
    "override, message",
    [
        ("tool.geometry.radius=-0.01", "radius"),
        ("target.geometry.radial_clearance=-0.001", "radial_clearance"),
        ("task.stroke=[0,0,0]", "task.stroke"),
        ("robot.max_torque=[1,1]", "robot.max_torque has 2 values"),
        ("target.pos=[3.0,0.0,0.2]", "inverse kinematics did not reach the start pose"),
    ],
)
def test_bad_values_fail_the_run_with_a_clear_error(tmp_path, override, message):
    record = execute(make_cfg(override), tmp_path, echo=False)
    assert record["status"] == "failed"
    assert message in record["error"]
    assert "\n" not in record["error"]


def test_fragment_files_are_checked(tmp_path):
    no_dock = tmp_path / "no_dock.xml"
    no_dock.write_text(
        '<mujoco><worldbody><body name="plug"><geom size="0.01"/>'
        '<site name="sensor_site"/></body></worldbody></mujoco>'
    )
    no_sensor = tmp_path / "no_sensor.xml"
    no_sensor.write_text(
        '<mujoco><worldbody><body name="dock"><geom size="0.01"/></body></worldbody></mujoco>'
    )
    cases = [
        (f"tool.mjcf={no_dock}", "no body named 'dock'"),
        (f"tool.mjcf={no_sensor}", "no site named 'sensor_site'"),
        (f"target.mjcf={no_dock}", "no body named 'dock'"),
        (f"tool.mjcf={tmp_path / 'missing.xml'}", "tool.mjcf must name an MJCF file; there is no such file"),
    ]
    for override, message in cases:
        record = execute(make_cfg(override), tmp_path / "run", echo=False)
        assert record["status"] == "failed" and message in record["error"], record["error"]


def test_a_fragment_file_tool_docks_like_the_generated_one(tmp_path):
    """Write the parametric plug to a file and dock with it: the file path works end to end
    (in the short held-contact scene: the plug is seated, pressed and held, and judged by
    the docking gate; the full approach with a file tool: test_converted_example_docks)."""
    from compliant_docking.config.store import default_interface
    from compliant_docking.sim.geometry import build_plug

    plug, _, contact = default_interface()
    path = tmp_path / "plug.xml"
    path.write_text(build_plug(plug, contact).to_xml())
    record = execute(
        make_cfg(f"tool.mjcf={path}", *SHORT_CONTACT), tmp_path / "run", figures=False, echo=False
    )
    assert record["success"] is True, record["error"] or record["gate_failures"]
