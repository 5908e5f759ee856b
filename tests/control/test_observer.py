"""The generalised-momentum observer (compliant_docking/control/observer.py).

A known constant wrench is pushed on the tool with ``xfrc_applied`` (moved from the TCP
to the tool's centre of mass, where MuJoCo applies it); the observer must report it
without using the force/torque sensor.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from compliant_docking.control.observer import WRENCH_COLUMNS, MomentumObserver
from compliant_docking.run.runner import execute
from compliant_docking.sim.simulate import prepare
from tests.helpers import SHORT_CONTACT, make_cfg, push_at_tcp

WRENCH = np.array([6.0, -4.0, 5.0, 0.3, -0.2, 0.1])  # [f; m] at the TCP, world axes
RAMP_S = 0.5  # the push rises smoothly over this time


def push(sim, wrench, ramp_s=RAMP_S):
    """Wrap the controller so that every step first applies `wrench` (at the TCP, world
    axes, smoothly ramped in) to the tool body."""
    compute = sim.controller.compute

    def pushed(t, state, ref, measured):
        a = min(t / ramp_s, 1.0)
        w = a * a * (3.0 - 2.0 * a) * wrench
        push_at_tcp(sim, force=w[:3], moment=w[3:])
        return compute(t, state, ref, measured)

    sim.controller.compute = pushed


def ride_along(sim) -> MomentumObserver:
    """An observer fed by the run's controller, step by step (any controller can host one)."""
    observer = MomentumObserver(sim.controller.ctx, kp=20.0, ki=40.0)
    compute = sim.controller.compute

    def observed(t, state, ref, measured):
        observer.update(state, measured)
        tau = compute(t, state, ref, measured)
        observer.command(tau)
        return tau

    sim.controller.compute = observed
    return observer


def hold_cfg(robot, *overrides, seconds=6):
    return make_cfg(
        f"robot={robot}",
        "target=none",
        "trajectory=hold",
        f"trajectory.duration={seconds}",
        "task.init_pos=[0.55,0.0,0.30]",
        "task.progress=false",
        *overrides,
    )


@pytest.mark.parametrize("robot", ["iiwa14", "fr3"])
def test_observer_estimates_a_constant_push(robot):
    """A stiff impedance controller holds the tool against the push; an observer rides
    along (any controller can host one). After settling (the last second of a 4 s hold)
    the estimate is the wrench: on the iiwa14 (exact model, no friction) to 1e-6 (measured
    1.4e-7: the PI observer's residual, 1.6e-9 after 6 s); on the FR3 to 1 % (measured
    0.58 %, 0.12 % after 6 s): its joints
    keep their friction, which hides up to 1.14 N·m while a joint sticks. The host runs
    the law of §1 (no apparent-inertia floor): the floor, meant for stiff contact, leaves
    the FR3 (m = 2 kg) up to 4× heavier here, so friction makes it creep for longer than
    the run."""
    sim = prepare(
        hold_cfg(
            robot,
            "controller.k=2000",
            "controller.d=280",
            "controller.k_rot=200",
            "controller.d_rot=28",
            "controller.apparent_inertia_floor=null",
            seconds=4,
        )
    )
    observer = ride_along(sim)
    push(sim, WRENCH)
    sim.run()
    last = slice(observer.count - 1000, observer.count)
    estimate = observer.estimates[last].mean(axis=0)
    tolerance = 1e-6 if robot == "iiwa14" else 0.01
    assert np.linalg.norm(estimate - WRENCH) <= tolerance * np.linalg.norm(WRENCH)
    # the sensor agrees with what was applied (a check of the test itself; measured 1e-7 N
    # on the FR3, whose sticking joints leave the tool a residual acceleration)
    np.testing.assert_allclose(observer.measured[last].mean(axis=0), WRENCH, atol=1e-6)


def test_observer_sees_no_wrench_in_fast_free_motion():
    """No contact, a 1 s stroke at up to 0.34 m/s: M(q) changes, the Coriolis terms are
    large; the observer (β = h − Ṁv through ΔM v) must still report ~0 (iiwa14: the
    Pinocchio model is MuJoCo's)."""
    sim = prepare(
        make_cfg("robot=iiwa14", "trajectory.duration=1.0", "task.duration=0.6", "task.progress=false")
    )
    observer = ride_along(sim)
    sim.run()
    # really no contact (the sensor is no reference here: it also feels the tool's inertia)
    assert not sim.telemetry.contacts[: sim.telemetry.count].any()
    # exact model: only round-off remains (measured 1.3e-13 N, 1.8e-14 N·m); 1e-8 N is a
    # millionth of the 0.05 N a missing Coriolis term alone would show
    assert np.abs(observer.estimates[: observer.count, :3]).max() < 1e-8  # [N]
    assert np.abs(observer.estimates[: observer.count, 3:]).max() < 1e-9  # [N·m]


def test_observer_clips_the_command_like_the_motors():
    """A saturated command: the observer integrates the clipped torque (what the motors
    apply), so it stays right while the controller asks for more than the clip."""
    sim = prepare(hold_cfg("iiwa14", seconds=3))
    observer = MomentumObserver(sim.controller.ctx, kp=20.0, ki=40.0)
    compute = sim.controller.compute
    boost = np.array([30.0, 0, 0, 0, 0, 0, 0])  # far beyond the 10 N·m clip on joint 1

    def saturating(t, state, ref, measured):
        observer.update(state, measured)
        tau = compute(t, state, ref, measured) + (boost if t < 0.2 else 0.0)
        observer.command(tau)
        return tau

    sim.controller.compute = saturating
    sim.run()
    saturated = sim.telemetry.applied_torque(np.full(7, 10.0))[1]
    assert saturated[:200].sum() >= 10  # the motors did clip
    # no external wrench: with the unclipped command the observer would see tens of N
    # (measured with the clipped one: 2.3e-13 N, round-off)
    assert np.abs(observer.estimates[: observer.count, :3]).max() < 1e-8


#: the FR3 cell is `slow` (nightly): the iiwa14 cell proves the wiring (the estimate drives
#: hqp, its columns and metrics are written, the run docks on it); the FR3's observer under
#: joint friction is held to 1 % by test_observer_estimates_a_constant_push[fr3], and hqp
#: docks the FR3 in tests/control/test_hqp.py::test_docks_the_default_scene_fr3
@pytest.mark.parametrize(
    "robot",
    ["iiwa14", pytest.param("fr3", marks=pytest.mark.slow(reason="the iiwa14 cell proves the wiring"))],
)
def test_hqp_with_the_observer_docks_and_reports_it(tmp_path, robot):
    """controller.force_source=observer: the estimate goes to the time series beside the
    sensor wrench and its error against the sensor to metrics.json. The iiwa14 on the
    short held-contact scene (tests.helpers.SHORT_CONTACT: the estimate drives the same
    approach, seat and hold; steady error 0.0115 N against 0.0116 N on the full run,
    measured), the FR3 (nightly) on the full run."""
    short = SHORT_CONTACT if robot == "iiwa14" else ()
    rec = execute(
        make_cfg(
            "controller=hqp",
            f"robot={robot}",
            "controller.force_source=observer",
            "task.progress=false",
            *short,
        ),
        tmp_path,
        figures=False,
        echo=False,
    )
    assert rec["hqp_force_source"] == "observer"
    for key in (
        "observer_force_err_rms_N",
        "observer_force_err_steady_N",
        "observer_moment_err_rms_Nm",
        "observer_moment_err_steady_Nm",
    ):
        assert rec[key] is not None
    ts = pd.read_parquet(tmp_path / "timeseries.parquet")
    assert all(col in ts.columns for col in WRENCH_COLUMNS)
    diff = ts[list(WRENCH_COLUMNS[:3])].to_numpy() - ts[["fx", "fy", "fz"]].to_numpy()
    rms = float(np.sqrt(np.mean(np.sum(diff**2, axis=1))))
    assert rms == pytest.approx(rec["observer_force_err_rms_N"], rel=1e-9)
    assert rec["success"], rec["gate_failures"]  # both dock on the estimate alone
    if robot == "iiwa14":  # exact model, no friction: 0.012 N measured in the steady window
        assert rec["observer_force_err_steady_N"] < 0.05
    else:  # the FR3's joints stick: friction (up to 1.14 N·m) the observer's model lacks
        # shows as 1.09 N / 0.34 N·m (measured): tenfold the iiwa14's, and under 1.5 N /
        # 0.5 N·m, a tenth of what a full 1.14 N·m on every joint could hide here (11 N)
        assert 0.2 < rec["observer_force_err_steady_N"] < 1.5
        assert rec["observer_moment_err_steady_Nm"] < 0.5
