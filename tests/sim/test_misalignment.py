"""Socket misalignment: the physics and the gate see the TRUE pose, the planner the believed one."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from compliant_docking.run.rundir import read_timeseries
from compliant_docking.run.runner import execute
from compliant_docking.sim import misalignment as drawing
from compliant_docking.sim.misalignment import RECORD_KEYS, Misalignment
from compliant_docking.sim.scene import socket_pose as pose_of
from compliant_docking.sim.settings import sim_settings
from compliant_docking.sim.simulate import prepare
from tests.helpers import make_cfg, misalignment

M = "task.misalignment"


def draw(given: dict | None) -> Misalignment:
    """The draw of ``task.misalignment`` set to ``given`` (None: no settings)."""
    return drawing.draw(None if given is None else misalignment(**given))


def socket_pose(cfg):
    return pose_of(sim_settings(cfg))


def record_for(cfg) -> dict:
    return drawing.record_for(sim_settings(cfg))


def test_default_is_no_misalignment():
    cfg = make_cfg()
    pose = socket_pose(cfg)
    assert pose.misalignment == Misalignment() and pose.misalignment.is_zero
    assert np.allclose(pose.true.homogeneous, pose.believed.homogeneous)
    assert record_for(cfg)["misalignment_seed"] is None


def test_offsets_are_expressed_in_the_believed_socket_frame():
    # a socket rotated 90° about world z: its x axis is world y
    quat = [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]
    cfg = make_cfg(
        f"target.quat=[{','.join(map(str, quat))}]",
        f"{M}.x=0.003",
        f"{M}.y=-0.002",
        f"{M}.yaw_deg=90",
        f"{M}.tilt_deg=10",
    )
    pose = socket_pose(cfg)
    believed = pose.believed
    assert np.allclose(believed.translation, cfg.target.pos)
    # lateral offset along the socket's x (world y) and y (world −x)
    assert np.allclose(pose.true.translation - believed.translation, [0.002, 0.003, 0.0], atol=1e-12)
    # the true axis: tilted 10° from the believed one; yaw 90° turns the tilt direction
    # from the socket's −y to its +x, i.e. to world +y here
    axis = pose.true.rotation[:, 2]
    assert np.degrees(np.arccos(axis @ believed.rotation[:, 2])) == pytest.approx(10.0)
    assert axis @ np.array([0.0, 1.0, 0.0]) == pytest.approx(np.sin(np.radians(10.0)))


def test_physics_sees_the_true_pose_and_the_planner_the_believed_one():
    cfg = make_cfg(f"{M}.x=0.004", f"{M}.y=0.001", f"{M}.yaw_deg=15", f"{M}.tilt_deg=3")
    sim = prepare(cfg)
    pose = sim.scene.socket
    # MuJoCo: the socket body sits at the TRUE pose
    data = mujoco.MjData(sim.scene.model)
    mujoco.mj_kinematics(sim.scene.model, data)
    body = sim.scene.model.body(f"{cfg.target.prefix}dock").id
    assert np.allclose(data.xpos[body], pose.true.translation, atol=1e-9)
    assert np.allclose(data.xmat[body].reshape(3, 3), pose.true.rotation, atol=1e-9)
    assert not np.allclose(pose.true.translation, pose.believed.translation)
    # the planner: start = believed seat − stroke; goal on the believed axis, at the
    # believed seat (or the overshoot past it)
    stroke = np.asarray(cfg.task.stroke, float)
    seat, socket_axis = pose.believed.translation, pose.believed.rotation[:, 2]
    assert np.allclose(sim.waypoints.start.translation, seat - stroke)
    goal = sim.waypoints.goal.translation - seat
    assert np.linalg.norm(goal - (goal @ socket_axis) * socket_axis) < 1e-9
    assert np.linalg.norm(goal) <= cfg.task.insertion_overshoot + 1e-9
    # the plug points along the believed socket axis, not the true (tilted) one
    assert np.allclose(sim.waypoints.start.rotation[:, 2], -pose.believed.rotation[:, 2])


def test_same_seed_same_draw_and_components_draw_independently():
    ranges = {"x_range": [-0.01, 0.01], "yaw_deg_range": [-180.0, 180.0], "tilt_deg_range": [0.0, 3.0]}
    a = draw({**ranges, "seed": 7})
    assert a == draw({**ranges, "seed": 7})
    assert a != draw({**ranges, "seed": 8})
    assert -0.01 <= a.x <= 0.01 and 0.0 <= a.tilt_deg <= 3.0 and a.y == 0.0 and a.seed == 7
    # the x draw does not depend on which other components are drawn
    assert draw({"x_range": [-0.01, 0.01], "seed": 7}).x == a.x
    # scaling the range scales the draw (common random numbers across a grid)
    assert draw({"x_range": [-0.02, 0.02], "seed": 7}).x == pytest.approx(2 * a.x)
    # and through the config: the same seed records the same values
    overrides = (f"{M}.x_range=[-0.01,0.01]", f"{M}.tilt_deg_range=[0,3]", f"{M}.seed=7")
    assert record_for(make_cfg(*overrides)) == record_for(make_cfg(*overrides))
    assert record_for(make_cfg(*overrides))["misalignment_x_m"] == pytest.approx(a.x)
    seeds = {draw({"x_range": [0.0, 1.0], "seed": s}).x for s in range(20)}
    assert len(seeds) == 20 and min(seeds) < 0.25 and max(seeds) > 0.75


# --------------------------------------------------------------------------- definitions
# Closed forms of the draws and of the composition (docs/sweeps.md, "Socket misalignment"),
# without a simulation; benchmarks/mutation_score.py (D*) changes each part of them and
# checks that one of these tests fails.


def test_the_true_pose_is_the_believed_one_times_trans_then_rz_then_rx():
    """T = B · Trans(x, y, 0) · Rz(ψ) · Rx(θ) for a believed pose B (turned and tilted, off
    the origin), x = 3 mm, y = −2 mm, ψ = 30°, θ = 10° (degrees): the true seat is at
    B.p + B.R (x, y, 0) (offsets in the believed frame, not turned by ψ or θ); its x axis
    is B.R (cos ψ, sin ψ, 0) (the tilt is about it); its z axis is B.R (sin θ sin ψ,
    −sin θ cos ψ, cos θ): it leans by θ towards the yawed −y direction."""
    import pinocchio as pin

    b_rot = np.array([[0.0, -1.0, 0.0], [0.6, 0.0, -0.8], [0.8, 0.0, 0.6]])
    believed = pin.SE3(b_rot, np.array([0.5, -0.2, 0.1]))
    psi, theta = np.radians(30.0), np.radians(10.0)
    true = Misalignment(x=0.003, y=-0.002, yaw_deg=30.0, tilt_deg=10.0).apply(believed)
    assert np.allclose(true.translation, believed.translation + b_rot @ [0.003, -0.002, 0.0], atol=1e-15)
    assert np.allclose(true.rotation[:, 0], b_rot @ [np.cos(psi), np.sin(psi), 0.0], atol=1e-15)
    z = [np.sin(theta) * np.sin(psi), -np.sin(theta) * np.cos(psi), np.cos(theta)]
    assert np.allclose(true.rotation[:, 2], b_rot @ z, atol=1e-15)


#: the components in the order of their streams (docs/sweeps.md: i = 0, 1, 2, 3), each with
#: a range that is neither symmetric nor starting at 0
STREAMS = (
    ("x", [0.001, 0.004]),
    ("y", [-0.003, -0.001]),
    ("yaw_deg", [10.0, 40.0]),
    ("tilt_deg", [-2.0, 5.0]),
)


@pytest.mark.parametrize("seed", [0, 7, 123456789])
def test_a_drawn_component_is_low_plus_width_times_the_first_uniform_of_its_stream(seed):
    """value = low + (high − low)·u, u the first uniform number of the stream
    numpy.random.default_rng(SeedSequence([seed, i])), i the component's index (x, y, yaw,
    tilt): one stream per (seed, component), whatever else is drawn."""
    drawn = draw({f"{name}_range": bounds for name, bounds in STREAMS} | {"seed": seed})
    for i, (name, (low, high)) in enumerate(STREAMS):
        u = np.random.default_rng(np.random.SeedSequence([seed, i])).random()
        assert getattr(drawn, name) == pytest.approx(low + (high - low) * u, rel=1e-12, abs=0.0), name
        alone = draw({f"{name}_range": [low, high], "seed": seed})
        assert getattr(alone, name) == getattr(drawn, name), name
    assert drawn.seed == seed


def test_a_range_of_one_value_draws_it_and_a_reversed_range_is_refused():
    """[a, a] is a range (low <= high) and draws a; [high, low] is refused, naming it."""
    assert draw({"x_range": [0.002, 0.002], "seed": 3}).x == 0.002
    with pytest.raises(
        ValueError, match=r"task\.misalignment\.x_range must be \[low, high\] with low <= high"
    ):
        draw({"x_range": [0.002, 0.0015], "seed": 3})


def test_a_fixed_component_passes_through_and_cannot_be_drawn_as_well():
    fixed = draw({"x": 0.001, "yaw_deg": 5.0, "tilt_deg": -2.0, "seed": 4})
    assert fixed == Misalignment(x=0.001, yaw_deg=5.0, tilt_deg=-2.0, seed=None)
    with pytest.raises(ValueError, match=r"task\.misalignment\.x = 0\.001 and task\.misalignment\.x_range"):
        draw({"x": 0.001, "x_range": [0.0, 0.002], "seed": 4})


@pytest.mark.parametrize("tilt", [60.0, -60.0, 75.0, -75.0])
def test_a_tilt_of_60_degrees_or_more_either_way_is_refused(tilt):
    """|tilt| < 60° (the socket would face sideways): fixed or drawn, ±60° itself refused
    (the schema's range, in the config check's words)."""
    with pytest.raises(
        ValueError, match=r"^task\.misalignment\.tilt_deg must be a finite number in \(-60, 60\) deg"
    ):
        draw({"tilt_deg": tilt})
    with pytest.raises(
        ValueError, match=r"^task\.misalignment\.tilt_deg_range\[0\] must be a finite number in \(-60, 60\)"
    ):
        draw({"tilt_deg_range": [tilt, tilt], "seed": 0})
    assert draw({"tilt_deg": np.copysign(59.99, tilt)}).tilt_deg == np.copysign(59.99, tilt)


@pytest.mark.parametrize(
    "settings, key",
    [
        ({"x": float("nan")}, "task.misalignment.x must be a finite number in [-1, 1] m; got nan."),
        ({"y": float("inf")}, "task.misalignment.y must be a finite number in [-1, 1] m; got inf."),
        ({"x_range": [0.0, float("inf")], "seed": 0}, "task.misalignment.x_range[1] must be a finite number"),
        ({"yaw_deg_range": [1.0], "seed": 0}, "task.misalignment.yaw_deg_range must have 2 values; got 1"),
        (
            {"yaw_deg_range": [0.0, 1.0, 2.0], "seed": 0},
            "task.misalignment.yaw_deg_range must have 2 values; got 3",
        ),
        ({"x_range": [0.0, 0.001, 0.002], "seed": 0}, "task.misalignment.x_range must have 2 values; got 3"),
        ({"tilt_deg_range": [0.0], "seed": 0}, "task.misalignment.tilt_deg_range must have 2 values; got 1"),
        ({"x_range": [0.0, 0.001], "seed": -1}, "task.misalignment.seed must be an integer in [0, "),
        ({"x_range": [0.0, 0.001], "seed": None}, "task.misalignment.seed must be an integer >= 0 to draw"),
    ],
)
def test_meaningless_draw_settings_are_refused_naming_the_setting(settings, key):
    with pytest.raises(ValueError) as refused:
        draw(settings)
    assert key in str(refused.value)


def test_the_recorded_keys():
    """x, y, yaw, tilt as drawn; the lateral distance √(x² + y²) (3-4-5 mm); the seed only
    when something was drawn; no settings: no misalignment and no seed."""
    assert Misalignment(x=0.003, y=-0.004, yaw_deg=5.0, tilt_deg=1.5, seed=9).record() == {
        "misalignment_x_m": 0.003,
        "misalignment_y_m": -0.004,
        "misalignment_lateral_m": pytest.approx(0.005, rel=1e-15),
        "misalignment_yaw_deg": 5.0,
        "misalignment_tilt_deg": 1.5,
        "misalignment_seed": 9,
    }
    assert draw({"x": 0.001, "seed": 9}).record()["misalignment_seed"] is None
    assert draw({"x_range": [0.0, 0.001], "seed": 9}).record()["misalignment_seed"] == 9
    assert draw(None) == Misalignment() and draw(None).record()["misalignment_seed"] is None


@pytest.mark.parametrize(
    "overrides, message",
    [
        ((f"{M}.x=0.001", f"{M}.x_range=[0,0.002]"), "task.misalignment.x = 0.001 and"),
        ((f"{M}.y_range=[0.002,0.001]",), "low <= high"),
        ((f"{M}.tilt_deg_range=[1]",), "task.misalignment.tilt_deg_range must have 2 values; got 1"),
        (
            (f"{M}.tilt_deg=75",),
            "task.misalignment.tilt_deg must be a finite number in (-60, 60) deg; got 75.0",
        ),
        ((f"{M}.x_range=[0,0.002]", f"{M}.seed=-1"), "task.misalignment.seed"),
    ],
)
def test_meaningless_settings_fail_the_run_naming_the_key(tmp_path, overrides, message):
    record = execute(make_cfg(*overrides, "task.progress=false"), tmp_path, figures=False, echo=False)
    assert record["status"] == "failed" and message in record["error"]
    assert all(record[k] is None for k in RECORD_KEYS)


def test_unknown_misalignment_keys_are_rejected_at_composition():
    with pytest.raises(Exception, match="task.misalignment.lateral"):
        make_cfg(f"{M}.lateral=0.001")


def test_a_misalignment_needs_a_socket():
    with pytest.raises(ValueError, match="needs a socket"):
        socket_pose(make_cfg("target=none", f"{M}.x=0.001"))


def test_large_misalignment_fails_the_gate_and_says_why(tmp_path):
    """20 mm off: beyond the funnel's mouth (≈ 8.7 mm of capture), the plug lands beside it.
    The stroke in 8 s instead of 15 and 1 s of settling instead of 3: where the plug lands
    does not depend on how fast it comes (first contact 19.997 mm off against 20.001 mm on
    the default run, measured)."""
    cfg = make_cfg(f"{M}.x=0.02", "trajectory.duration=8", "task.settle_time=1", "task.progress=false")
    record = execute(cfg, tmp_path, figures=False, echo=False)
    assert record["status"] == "ok" and record["success"] is False
    assert "off the axis: tip up to 20 mm from the socket axis" in record["gate_failures"]
    assert record["seat_lateral_error_m"] > 0.015  # measured against the TRUE socket
    # the plug comes down the believed axis: it first touches 20 mm from the TRUE one
    assert record["first_contact_lateral_offset_m"] == pytest.approx(0.02, abs=1e-4)
    # the gate's force is the run's axial force (down −z, the believed axis) averaged over
    # task.force_window = 50 ms: 50 rows at dt = 1 ms
    ts = read_timeseries(tmp_path, ["t", "fz"])
    assert np.diff(ts["t"].to_numpy()) == pytest.approx(0.001)
    axial = ts["fz"].to_numpy()
    assert record["peak_axial_force_N"] == pytest.approx(np.max(np.abs(axial)), rel=1e-12)
    window_means = np.convolve(axial, np.full(50, 1 / 50), mode="valid")
    assert record["filtered_peak_axial_force_N"] == pytest.approx(np.max(np.abs(window_means)), rel=1e-9)
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["misalignment_x_m"] == 0.02 and saved["misalignment_lateral_m"] == 0.02
    assert saved["misalignment_yaw_deg"] == 0.0 and saved["misalignment_seed"] is None
