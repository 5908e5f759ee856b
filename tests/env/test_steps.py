"""What a reset and a step do: the seeded draw, the observation's frames, the action's effect
on the setpoint, the gains and the torque, and an episode's end."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from compliant_docking.env import make_env
from compliant_docking.sim import misalignment
from compliant_docking.sim.settings import sim_settings
from tests.helpers import make_cfg, push_at_tcp

SHORT = ("trajectory.duration=1", "task.settle_time=1", "task.progress=false")
DRAWN = (
    "task.misalignment.x_range=[-0.004,0.004]",
    "task.misalignment.y_range=[-0.004,0.004]",
    "task.misalignment.tilt_deg_range=[0,1]",
    "task.misalignment.yaw_deg_range=[-180,180]",
)
#: the believed socket turned 90° about its axis (world z): socket x = world y, socket y = −world x
TURNED = "target.quat=[0.7071067811865476,0,0,0.7071067811865476]"


def _index(env, name: str) -> int:
    return env.names.index(name)


def test_reset_draws_the_misalignment_of_the_same_seed_as_a_run():
    env = make_env(*SHORT, *DRAWN)
    obs, info = env.reset(seed=7)
    again, info_again = env.reset(seed=7)
    assert np.array_equal(obs, again) and info == info_again
    run = misalignment.draw(sim_settings(make_cfg(*DRAWN, "task.misalignment.seed=7")).task.misalignment)
    assert (
        info["seed"] == 7
        and info["misalignment_x_m"] == run.x
        and info["misalignment_tilt_deg"] == run.tilt_deg
    )
    assert env.sim.scene.socket.misalignment == run  # the scene's true socket: the run's
    _, other = env.reset(seed=8)
    assert other["misalignment_x_m"] != run.x


def test_unseeded_resets_continue_the_seeded_generator():
    env = make_env(*SHORT, *DRAWN)
    env.reset(seed=3)
    first = [env.reset()[1]["seed"] for _ in range(3)]
    env.reset(seed=3)
    assert [env.reset()[1]["seed"] for _ in range(3)] == first
    assert len(set(first)) == 3 and 3 not in first


def test_the_observation_is_in_the_believed_socket_frame():
    """At reset the plug tip is task.stroke above the believed seat, whatever the socket's
    yaw, at rest, aligned, with the setpoint on it; a push along world x reads as −y."""
    env = make_env(*SHORT, TURNED, "task.misalignment.x=0.003")
    obs, _ = env.reset(seed=0)
    at = {name: float(obs[_index(env, name)]) for name in env.names}
    assert [at["x"], at["y"], at["z"]] == pytest.approx([0.0, 0.0, 0.18], abs=1e-6)
    assert [at["x_ref"], at["y_ref"], at["z_ref"]] == pytest.approx([0.0, 0.0, 0.18], abs=1e-6)
    assert max(abs(at[n]) for n in ("rx", "ry", "rz", "vx", "wz", "fx", "fy", "fz")) < 1e-6
    assert at["phase"] == 0.0
    assert np.allclose(obs[:7], env.sim.q0, atol=1e-6)
    push_at_tcp(env.sim, force=(5.0, 0.0, 0.0))
    obs, *_ = env.step(np.zeros(9))
    force = obs[_index(env, "fx") : _index(env, "fx") + 3]
    # the F/T reading of the push less the tool's inertia: the impedance's 10 kg take 5 N at
    # 0.5 m/s², and the 0.3 kg tool's share is 0.15 N (measured 0.166 N)
    assert force == pytest.approx([0.0, -5.0 + 0.3 * 0.5, 0.0], abs=0.03)
    assert obs[_index(env, "phase")] == pytest.approx(10 / env.sim.n_steps)


def test_a_setpoint_action_moves_the_reference_of_its_steps_only():
    env = make_env(*SHORT, TURNED, "env.action.max_offset_m=0.01", "env.action.max_rotation_deg=4")
    env.reset(seed=0)
    ref = env.sim.reference
    planned_pos, planned_rot = ref.pos.copy(), ref.rot.copy()
    action = np.zeros(9)
    action[0], action[5] = 0.5, -0.25  # 5 mm along the socket's x (world y), −1° about its axis
    env.step(action)
    n = env.policy_steps
    assert np.allclose(ref.pos[:n] - planned_pos[:n], [0.0, 0.005, 0.0], rtol=0.0, atol=1e-15)
    turn = pin.exp3(np.array([0.0, 0.0, -math.radians(1.0)]))
    assert np.allclose(ref.rot[:n], turn @ planned_rot[:n], atol=1e-15)
    assert np.array_equal(ref.pos[n:], planned_pos[n:]) and np.array_equal(ref.rot[n:], planned_rot[n:])


def test_gain_components_scale_the_stiffness_from_the_configured_gains():
    env = make_env(*SHORT)
    env.reset(seed=0)
    controller = env.sim.controller
    configured = controller.G.copy()
    action = np.zeros(9)
    action[6:9] = [1.0, -0.5, 0.0]
    env.step(action)
    k, m = float(env.cfg.controller.k), float(env.cfg.controller.m)
    stiffness = controller.G[:3, :3] * m  # K = k (s_lat P⊥ + s_ax P∥), axis world −z
    assert np.allclose(np.diag(stiffness), [10 * k, 10 * k, k / math.sqrt(10)])
    env.step(np.zeros(9))
    assert np.array_equal(controller.G, configured)


def test_a_torque_action_adds_its_residual_to_the_command():
    env = make_env(*SHORT, "env.action.kind=torque", "env.action.max_residual_torque=0.5")
    env.reset(seed=0)
    inner = env.sim.controller.controller
    commands = []
    compute = inner.compute
    inner.compute = lambda *args: commands.append(compute(*args).copy()) or commands[-1]
    action = np.linspace(-1.0, 1.0, 7)
    env.step(action)
    logged = env.sim.telemetry.tau_cmd[: env.policy_steps]
    assert np.allclose(logged - np.array(commands), 0.5 * action, atol=1e-12)


def test_actions_are_clipped_and_bad_ones_refused():
    env = make_env(*SHORT, "env.action.max_offset_m=0.01")
    env.reset(seed=0)
    planned = env.sim.reference.pos[0].copy()
    env.step([3.0, 0, 0, 0, 0, 0, 0, 0, 0])  # beyond +1: the bound
    assert env.sim.reference.pos[0] - planned == pytest.approx([0.01, 0.0, 0.0])
    for bad in ([0.0] * 8, [math.nan] + [0.0] * 8, "up"):
        with pytest.raises(ValueError, match="an action must be 9 finite numbers"):
            env.step(bad)


def test_the_episode_ends_at_the_run_s_end_with_its_metrics():
    env = make_env(*SHORT)
    env.reset(seed=0)
    steps, terminated, info = 0, False, {}
    while not terminated:
        _, _, terminated, truncated, info = env.step(np.zeros(9))
        assert not truncated
        steps += 1
    assert steps == math.ceil(env.sim.n_steps / env.policy_steps)
    metrics = info["metrics"]
    assert metrics["status"] == "ok" and info["is_success"] == bool(metrics["success"])
    assert metrics["steps"] == env.sim.n_steps and "filtered_peak_axial_force_N" in metrics
    with pytest.raises(RuntimeError, match="call reset"):
        env.step(np.zeros(9))


def test_a_diverged_episode_terminates_with_its_penalty_and_keeps_mujoco_s_warnings(tmp_path, monkeypatch):
    """A non-finite joint speed: the loop stops the run as diverged at its first check, the
    episode ends with the penalty, and MuJoCo's warning goes to the record and the run
    directory's mujoco.log, never to MUJOCO_LOG.TXT in the working directory."""
    monkeypatch.chdir(tmp_path)
    env = make_env(*SHORT, f"env.record_dir={tmp_path / 'episodes'}")
    env.reset(seed=0)
    env.sim.data.qvel[0] = math.nan
    obs, reward, terminated, truncated, info = env.step(np.zeros(9))
    assert terminated and not truncated and np.isfinite(obs).all()
    assert info["reward_terms"]["diverged"] == -env.weights.diverged and reward == -env.weights.diverged
    metrics = info["metrics"]
    assert metrics["status"] == "failed" and metrics["error"].startswith("simulation diverged at t = 0.000 s")
    assert not info["is_success"] and metrics["mujoco_warnings"] == 1
    assert "Nan, Inf or huge value in QVEL" in (Path(metrics["run_dir"]) / "mujoco.log").read_text()
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
