"""The sensor model (compliant_docking/sim/sensor.py: SensorModel, SensedWrench, the loop's
readers): closed forms of the filter, the sample-and-hold, the delay and the noise, and
the loop handing the controller the modelled reading while it logs the exact one."""

import math

import numpy as np
import pytest

from compliant_docking.sim.sensor import SENSED_COLUMNS, SensedWrench, SensorModel
from compliant_docking.sim.settings import sim_settings
from compliant_docking.sim.simulate import prepare
from tests.helpers import FREE_SPACE_HOLD, make_cfg

DT = 0.001


def _respond(model: SensorModel, inputs: np.ndarray) -> np.ndarray:
    """The readings of ``model`` for the exact readings ``inputs`` (n × 6), one per step."""
    source, out = np.zeros(6), np.zeros(6)
    path = SensedWrench(model, len(inputs), source, out)
    readings = np.zeros_like(inputs)
    for k, row in enumerate(inputs):
        source[:] = row
        path.step(k)
        readings[k] = out
    return readings


def _step(n: int, at: int = 1) -> np.ndarray:
    inputs = np.zeros((n, 6))
    inputs[at:] = np.arange(1.0, 7.0)
    return inputs


def _settings(**changes):
    cfg = make_cfg("sensor=ideal", *(f"sensor.{k}={v}" for k, v in changes.items()))
    return sim_settings(cfg).sensor


def test_the_filter_s_step_response_is_the_first_order_lag_at_the_sample_times():
    """y(t) = 1 − exp(−2π f_c t) for a unit step at t = 0 (step 1), exactly at every step:
    the discretisation is exact for an input held over the step; at t = 1/(2π f_c) it is
    1 − 1/e."""
    cutoff = 200.0
    model = SensorModel.from_settings(_settings(cutoff_hz=cutoff), DT)
    readings = _respond(model, _step(40))
    t = np.arange(40) * DT
    expected = np.where(t > 0, 1.0 - np.exp(-2.0 * math.pi * cutoff * t), 0.0)
    np.testing.assert_allclose(
        readings / np.arange(1.0, 7.0), np.outer(expected, np.ones(6)), rtol=0, atol=1e-12
    )
    assert readings[0].tolist() == [0.0] * 6  # settled on the first reading: no start transient


def test_the_delay_shifts_the_reading_by_its_steps_and_the_rate_holds_each_sample():
    """delay_s = 3 ms: the step of step 1 reaches the controller at step 4; at 250 Hz a
    sample is taken every 4th step and held in between (so the step, sampled at step 4,
    arrives at step 7)."""
    inputs = _step(20)
    delayed = _respond(SensorModel.from_settings(_settings(delay_s=0.003), DT), inputs)
    np.testing.assert_array_equal(delayed[3:], inputs[:-3])
    np.testing.assert_array_equal(delayed[:3], 0.0)
    held = _respond(SensorModel.from_settings(_settings(delay_s=0.003, rate_hz=250.0), DT), inputs)
    first = np.flatnonzero(held[:, 0])[0]
    assert first == 4 + 3
    assert (np.diff(held[first:, 0]) == 0).all()


@pytest.mark.parametrize("cutoff", [None, 200.0])
def test_noise_and_bias_have_their_mean_and_std(cutoff):
    """Over 40 000 steps: mean = bias (within 5 standard errors), std = σ without the filter
    and σ·√(α/(2−α)) with it (the stationary std of the first-order filter; 3 %)."""
    n = 40_000
    sigma = [0.5, 0.5, 1.0, 0.01, 0.01, 0.02]
    bias = [0.3, -0.2, 0.1, 0.004, -0.003, 0.002]
    model = SensorModel.from_settings(
        _settings(
            cutoff_hz="null" if cutoff is None else cutoff,
            force_noise_N=sigma[:3],
            moment_noise_Nm=sigma[3:],
            force_bias_N=bias[:3],
            moment_bias_Nm=bias[3:],
            seed=7,
        ),
        DT,
    )
    readings = _respond(model, np.zeros((n, 6)))
    alpha = 1.0 - math.exp(-2.0 * math.pi * cutoff * DT) if cutoff else 1.0
    std = np.asarray(sigma) * math.sqrt(alpha / (2.0 - alpha))
    # the filtered samples are correlated: the standard error of the mean grows by √((2−α)/α)
    stderr = std / math.sqrt(n) * math.sqrt((2.0 - alpha) / alpha)
    assert (np.abs(readings.mean(axis=0) - bias) < 5 * stderr).all()
    np.testing.assert_allclose(readings.std(axis=0), std, rtol=0.03)


def test_the_drawn_bias_is_reproducible_and_its_spread_is_the_setting():
    """Same seed, same bias; over 400 seeds the drawn biases have the configured std (±18 %: five
    standard errors of a std from 400 draws)."""
    settings = _settings(force_bias_std_N=0.1, moment_bias_std_Nm=0.002)
    draws = []
    for seed in range(400):
        settings.seed = seed
        draws.append(SensorModel.from_settings(settings, DT).bias)
    settings.seed = 5
    np.testing.assert_array_equal(SensorModel.from_settings(settings, DT).bias, draws[5])
    draws = np.array(draws)
    np.testing.assert_allclose(draws.std(axis=0), [0.1] * 3 + [0.002] * 3, rtol=0.18)


def test_the_ideal_sensor_leaves_the_loop_as_it_was():
    """sensor=ideal: no sensing stage (the loop hands the controller the exact, logged
    wrench: bit for bit the runs without sensor models)."""
    assert SensorModel.from_settings(_settings(), DT).ideal
    assert prepare(make_cfg(*FREE_SPACE_HOLD)).sensing is None


def test_the_controller_gets_the_modelled_reading_and_the_log_keeps_both():
    """A wrist sensor in the loop: the time series' fx … mz are the exact wrench, and its
    sensed_* columns are exactly the sensor model applied to them, step by step."""
    cfg = make_cfg(
        *FREE_SPACE_HOLD, "physics=earth", "sensor=wrist_ft", "task.duration=0.05", "sensor.seed=3"
    )
    sim = prepare(cfg)
    sim.run()
    n = sim.telemetry.count
    sensed = np.column_stack(list(sim.sensing.timeseries(n).values()))
    assert list(sim.sensing.timeseries(n)) == list(SENSED_COLUMNS)
    expected = _respond(SensorModel.from_settings(sim.settings.sensor, DT), sim.telemetry.wrench[:n])
    np.testing.assert_array_equal(sensed, expected)
    assert np.abs(sensed - sim.telemetry.wrench[:n]).max() > 0.05  # the noise is there


def test_force_feedback_amplifies_a_sensor_bias_by_the_inertia_ratio():
    """A bias δ is no force on the arm: with the impedance law's force feedback the arm
    obeys Λ ë = Λ a − δ with a = W⁻¹(δ + K e + D ė), so at rest K e = (W Λ⁻¹ − I) δ — not
    K e = δ (docs/robustness.md). Held in free space (no gravity, no floor on W), the TCP
    settles where that formula says, many times b/k away."""
    bias = np.array([0.2, 0.0, 0.0])
    cfg = make_cfg(
        *FREE_SPACE_HOLD,
        "controller.k=400",
        "controller.d=126.49",
        "controller.apparent_inertia_floor=null",
        "task.duration=2.5",
        f"sensor.force_bias_N=[{bias[0]},{bias[1]},{bias[2]}]",
    )
    sim = prepare(cfg)
    sim.run()
    last = sim.telemetry.count - 1
    arm = sim.scene.arm
    arm.update(sim.telemetry.q[last].copy(), np.zeros(arm.nv))
    task_inertia = np.linalg.inv(arm.J @ arm.Minv @ arm.J.T)
    W = np.diag([10.0] * 3 + [1.0] * 3)  # conf/controller/impedance.yaml: m, m_rot
    K = np.diag([400.0] * 3 + [25.0] * 3)
    predicted = np.linalg.solve(K, (W @ np.linalg.inv(task_inertia) - np.eye(6)) @ np.r_[bias, 0, 0, 0])
    offset = sim.reference.pos[last] - arm.pos  # e = x_d − x
    assert np.linalg.norm(offset) > 3 * bias[0] / 400.0  # amplified, not b/k
    np.testing.assert_allclose(offset, predicted[:3], atol=0.02 * np.linalg.norm(predicted[:3]))


def test_the_encoders_noise_reaches_the_controller_s_model_not_the_log():
    """joint_position_noise_rad / joint_velocity_noise_rad_s: the controller's arm model is
    updated with q + σ_q ε, v + σ_v ε of that step (seeded), the log keeps the true q, v."""
    cfg = make_cfg(
        *FREE_SPACE_HOLD,
        "task.duration=0.02",
        "sensor.joint_position_noise_rad=0.001",
        "sensor.joint_velocity_noise_rad_s=0.01",
    )
    sim = prepare(cfg)
    sim.run()
    last = sim.telemetry.count - 1
    arm, sensing = sim.scene.arm, sim.sensing
    np.testing.assert_array_equal(arm.q, sim.telemetry.q[last] + sensing.q_noise[last])
    np.testing.assert_array_equal(arm.v, sim.telemetry.v[last] + sensing.v_noise[last])
    assert 0.0005 < sensing.q_noise.std() < 0.002 and 0.005 < sensing.v_noise.std() < 0.02
