"""The reward's terms in closed form (compliant_docking/env/reward.py, docs/env.md)."""

from __future__ import annotations

import numpy as np
import pytest

from compliant_docking.env import make_env
from compliant_docking.env import reward as R
from compliant_docking.sim.telemetry import axial_force

SHORT = ("trajectory.duration=1", "task.settle_time=1", "task.progress=false")
WEIGHTS = R.Weights(distance=2.0, force=3.0, success=10.0, diverged=7.0)


def test_the_potential_is_minus_the_weighted_distance_over_the_start_distance():
    assert R.potential(0.2, 0.2, 2.0) == -2.0
    assert R.potential(0.0, 0.2, 2.0) == 0.0
    assert R.potential(0.05, 0.2, 2.0) == pytest.approx(-0.5)


def test_the_force_penalty_is_the_mean_s_excess_over_the_budget():
    assert R.force_penalty(np.array([60.0, 60.0]), 50.0, 3.0) == pytest.approx(-3.0 * 10.0 / 50.0)
    assert R.force_penalty(np.array([100.0, 0.0]), 50.0, 3.0) == 0.0  # the mean, not the peak
    assert R.force_penalty(np.array([49.0, 50.0]), 50.0, 3.0) == 0.0
    assert R.force_penalty(np.array([]), 50.0, 3.0) == 0.0


def test_the_terms_of_one_step():
    terms = R.terms(
        WEIGHTS,
        potential_before=-1.0,
        potential_after=-0.75,
        axial_force=np.array([75.0]),
        budget=50.0,
        success=True,
        diverged=False,
    )
    assert terms == pytest.approx({"shaping": 0.25, "force": -1.5, "success": 10.0, "diverged": 0.0})
    assert tuple(terms) == R.TERMS


#: a run that docks: 2 s of approach, the default 3 s of settling
DOCKS = ("trajectory.duration=2", "task.progress=false")


def _episode(*overrides: str, seed: int = 0, base=SHORT):
    env = make_env(*base, *overrides)
    obs, info = env.reset(seed=seed)
    rewards, terms = [], []
    while True:
        obs, reward, terminated, _, step_info = env.step(np.zeros(env.action_space.shape))
        rewards.append(reward)
        terms.append(step_info["reward_terms"])
        if terminated:
            return env, obs, info, rewards, terms, step_info


def test_an_episode_s_shaping_sums_to_one_minus_the_end_distance_over_the_start():
    """Potential-based: Σ shaping = w·(1 − d_end/d₀), d the tip's distance to the TRUE seat."""
    env, obs, info, rewards, terms, end = _episode(
        "task.misalignment.x=0.002", "task.misalignment.y=-0.001", "env.reward.distance=2"
    )
    tip = obs[env.names.index("x") : env.names.index("x") + 3].astype(float)  # believed socket frame
    true_seat = np.array([info["misalignment_x_m"], info["misalignment_y_m"], 0.0])  # no tilt, no yaw
    start = np.linalg.norm(np.array([0.0, 0.0, 0.18]) - true_seat)
    expected = 2.0 * (1.0 - np.linalg.norm(tip - true_seat) / start)
    assert sum(t["shaping"] for t in terms) == pytest.approx(expected, abs=1e-6)  # float32 tip
    assert rewards == pytest.approx([sum(t.values()) for t in terms])
    assert end["metrics"]["env_return"] == pytest.approx(sum(rewards))


def test_an_episode_s_force_terms_follow_its_axial_force_and_its_bonus_its_gate():
    """A budget of 0.1 N, below the press of the held plug: every step's force term is
    −w·max(0, F̄ − budget)/budget with F̄ the mean axial force of its physics steps."""
    env, _, _, _, terms, end = _episode("task.gate.peak_force_budget_N=0.1", "env.reward.force=3")
    wrench = env.sim.telemetry.wrench[: env.sim.steps_done]
    axial = axial_force(wrench[:, :3], env.sim.waypoints.axis)
    n = env.policy_steps
    expected = [3.0 * min(0.0, 0.1 - axial[i : i + n].mean()) / 0.1 for i in range(0, len(axial), n)]
    assert [t["force"] for t in terms] == pytest.approx(expected, abs=1e-12)
    assert min(expected) < -1.0  # the press: about k × overshoot = 0.25 N
    assert not end["is_success"]  # the same budget fails the gate's force check
    assert all(t["success"] == 0.0 for t in terms)
    env, _, _, _, terms, end = _episode(base=DOCKS)
    assert end["is_success"] and terms[-1]["success"] == env.weights.success
    assert all(t["success"] == 0.0 for t in terms[:-1])
